"""The speed of the GPS track read over chords that span the positions' updates: a receiver that
updates every few seconds, held on a faster grid, moves as fast as the wheels say."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from agrobot.measurements import LogError, read_log
from agrobot.measurements.log import track_span


def held_log(update_s: float, speed: float = 1.2, h: float = 0.1, duration: float = 120.0,
             ramp: int = 1) -> pd.DataFrame:
    """A vehicle at `speed` m/s on a wide circle (radius 40 m), logged at 1/h Hz; its positions
    are the receiver's, updated every `update_s` seconds and held in between (zero-order hold),
    each update spread over `ramp` rows (a resampled log interpolates from one fix to the next)."""
    t = np.arange(0.0, duration, h)
    r = speed / 40.0
    held = np.floor(t / update_s) * update_s
    if ramp > 1:
        held = np.convolve(np.pad(held, (ramp - 1, 0), mode="edge"), np.ones(ramp) / ramp, mode="valid")
    x, y = 40.0 * np.sin(r * held), 40.0 * (1 - np.cos(r * held))
    return pd.DataFrame({"t": t, "delta_cmd": 0 * t + 0.06, "delta": 0 * t + 0.06, "v": speed + 0 * t,
                         "yaw_rate": r + 0 * t, "x": x, "y": y})


@pytest.mark.parametrize("update_s, ramp", [(0.1, 1), (1.0, 1), (4.0, 1), (8.0, 1), (4.0, 3)])
def test_positions_held_between_slow_updates_read_at_the_wheels_speed(tmp_path, update_s, ramp):
    """Truth: v is m/s and x, y are metres, whatever the receiver's update interval. A 1 s chord
    between two updates 4 s apart measures a track standing still: v looked a billion times too fast
    and the log was refused as degrees of latitude."""
    path = tmp_path / "held.csv"
    held_log(update_s, ramp=ramp).to_csv(path, index=False)
    frame = read_log(path)                       # no LogError: the units are right
    assert len(frame) == 1200


def test_the_span_covers_two_updates_and_never_less_than_a_second():
    t = np.arange(0.0, 60.0, 0.1)
    assert track_span(t, held_log(4.0)[["x", "y"]].to_numpy()[: len(t)]) == pytest.approx(8.0, abs=0.11)
    assert track_span(t, held_log(0.1)[["x", "y"]].to_numpy()[: len(t)]) == 1.0
    assert track_span(t, held_log(4.0, ramp=3)[["x", "y"]].to_numpy()[: len(t)]) == pytest.approx(8.0, abs=0.11)
    assert track_span(t, np.zeros((len(t), 2))) == 1.0            # a track that never moves


def test_a_true_unit_error_is_still_refused_with_slow_updates(tmp_path):
    """v in km/h beside 4 s position updates is still 3.6 times the track."""
    frame = held_log(4.0)
    frame["v"] *= 3.6
    path = tmp_path / "kmh.csv"
    frame.to_csv(path, index=False)
    with pytest.raises(LogError, match="3.6 times the speed of the GPS track"):
        read_log(path)
