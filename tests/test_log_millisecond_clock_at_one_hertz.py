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
