"""rate() of a counter read in rows faster than it updates: wheel ticks counted at 400 a second,
updated every 5th row of a 100 Hz table, with a 20 s stand. Differenced row by row the held count
gives rates of 0 between bursts five times the true one (and the zeros are then dropped as copies:
a mean of 10 m/s for 4); differenced over its updates it gives the speed, and 0 where it stands."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from agrobot.measurements.recording import ImportOptions, import_recording
from agrobot.measurements.signal_expressions import counter_rate
from agrobot.measurements.streams import Series

PER_METRE = 100.0                     # ticks per metre


def _speed(t):
    return np.where((t >= 30.0) & (t < 50.0), 0.0, 4.0)


def _ticks(t, hold: int = 5):
    """The count at 100 Hz rows, updated every ``hold`` rows."""
    count = np.floor(np.concatenate([[0.0], np.cumsum(_speed(t[:-1]) * np.diff(t))]) * PER_METRE)
    return count[(np.arange(len(t)) // hold) * hold]


def test_a_held_counter_gives_its_speed_not_bursts():
    t = np.arange(0.0, 80.0, 0.01)
    rate = counter_rate(Series(t, _ticks(t), None, "wheel.ticks"))
    moving = (np.abs(rate.t - 40.0) > 11.0) & (rate.t > 1.0)
    assert np.allclose(rate.values[moving] / PER_METRE, 4.0, atol=0.25), (rate.values.min(), rate.values.max())
    standing = np.abs(rate.t - 40.0) < 9.0
    assert standing.any() and np.all(rate.values[standing] == 0.0)
    assert "differenced over its updates" in rate.label


def test_a_counter_updated_every_row_is_differenced_row_by_row():
    t = np.arange(0.0, 20.0, 0.01)
    rate = counter_rate(Series(t, np.round(400.0 * t), None, "wheel.ticks"))
    assert len(rate.t) == len(t) - 1 and "row by row" in rate.label


def test_the_imported_speed_of_a_held_counter(tmp_path):
    t = np.arange(0.0, 80.0, 0.01)
    r = 0.1 * np.sin(0.3 * t) + 0.002 * np.random.default_rng(1).standard_normal(len(t))
    pd.DataFrame({"t": t, "ticks": _ticks(t), "gyro": r}).to_csv(tmp_path / "drive.csv", index=False)
    log, _ = import_recording(Path(tmp_path / "drive.csv"), ImportOptions(
        signals=[f"v=rate(ticks)*{1 / PER_METRE!r}[m/s]", "yaw_rate=gyro[rad/s]"], time="t[s]"))
    moving = np.abs(log["t"] - log["t"].iloc[0] - 40.0) > 11.0
    assert abs(float(log.loc[moving, "v"].mean()) - 4.0) < 0.1 and float(log.loc[moving, "v"].std()) < 0.3


def test_a_counter_of_one_sample_is_refused_naming_it():
    """rate() of a counter with one sample (a topic with one message) has no step: a LogError names
    the source, the expression and the signal, not an IndexError."""
    import pytest

    from agrobot.measurements.log import LogError
    from agrobot.measurements.signal_expressions import evaluate, parse_signal

    spec = parse_signal("v=rate(/wheel/ticks.data)*0.001[m/s]")
    one = Series(np.array([3.0]), np.array([120.0]), None, "/wheel/ticks.data")
    with pytest.raises(LogError, match=r"drive\.bag.*rate\(/wheel/ticks\.data\).*1 sample.*two or more"):
        evaluate(spec, {"/wheel/ticks.data": one}, "drive.bag")
