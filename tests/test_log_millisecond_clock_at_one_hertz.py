"""A log whose time is a millisecond clock is named so at every rate a vehicle log samples at,
including a 1 Hz receiver's (steps of 1000 ms and a jitter): the advice divides by 1000, not by 1e6
(which would make a 1 Hz log a 1 kHz one); a microsecond clock (a 100 Hz IMU's 10000 us steps) is
named as microseconds."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from agrobot.measurements.log import LogError, check_log


def _frame(step: float, n: int = 200, seed: int = 0) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    t = 6004.0 + step * np.arange(n) + rng.uniform(0.0, 0.01 * step, n)
    return pd.DataFrame({"t": t, "x": np.arange(n) * 4.0, "y": np.zeros(n)})


@pytest.mark.parametrize("step, unit, divide, hz", [
    (1000.4, "milliseconds", "divide t by 1000)", "(1 Hz)"),
    (534.0, "milliseconds", "divide t by 1000)", "(1.87 Hz)"),
    (50.0, "milliseconds", "divide t by 1000)", "(20 Hz)"),
    (10000.0, "microseconds", "divide t by 1e+06)", "(100 Hz)"),
])
def test_a_clock_is_named_by_the_rate_it_gives(step, unit, divide, hz):
    with pytest.raises(LogError) as err:
        check_log(_frame(step), "ride.csv", required=("t", "x", "y"))
    text = str(err.value)
    assert "ride.csv" in text and "'t'" in text
    assert f"looks like {unit} {hz}" in text and divide in text, text


def test_convert_names_the_table_clock_taken_as_seconds(tmp_path):
    """A logger's table whose clock column counts milliseconds without saying so (a 2 Hz IMU row with
    a 1 Hz fix): taken as seconds, the log steps by 1000; the refusal names the table's column and
    the --time that declares it."""
    from agrobot.api import convert

    n = 600
    ms = 6004.0 + 500.0 * np.arange(n)
    fix = np.arange(n) // 2
    pd.DataFrame({"Time": ms, "Gz": np.zeros(n), "LAT": 53.1 + 3e-5 * fix, "LNG": np.full(n, 8.85)}).to_csv(
        tmp_path / "ride.csv", index=False)
    with pytest.raises(LogError) as err:
        convert(tmp_path / "ride.csv", signals=["yaw_rate=Gz[deg/s]", "lat=LAT[deg]", "lon=LNG[deg]"])
    text = str(err.value)
    assert "looks like milliseconds" in text and "--time 'ride.Time[ms]'" in text, text
