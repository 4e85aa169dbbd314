"""The gyro's sign against a skid-steer's turn-rate input, judged through glitch bursts: a gyro
counted clockwise is refused even when a few bursts of a sensor's out-of-range value (runs of 4-5
rows at 9 rad/s, 1.5 % of the rows) outweigh the rest in a plain correlation."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.identification.skid_steer import identify_skid_steer
from agrobot.measurements import LogError
from tests.test_skid_steer import skid_log


def with_bursts(frame, share: float = 0.015, level: float = 9.0, seed: int = 5):
    """Runs of 4-5 rows at `level` rad/s in the gyro, `share` of the rows in all."""
    rng = np.random.default_rng(seed)
    r = frame["yaw_rate"].to_numpy().copy()
    n, done = len(r), 0
    while done < share * n:
        i, w = int(rng.integers(10, n - 10)), int(rng.integers(4, 6))
        r[i:i + w] = level + rng.normal(0, 0.1, w)
        done += w
    return frame.assign(yaw_rate=r)


def test_a_clockwise_gyro_is_refused_through_glitch_bursts():
    """Truth: the gyro is the odometry's turn rate with its sign turned (K -0.7)."""
    frame = with_bursts(skid_log(K=0.7, tau=-0.3, T=0.15, column="odom_yaw_rate"))
    frame["yaw_rate"] = np.where(frame["yaw_rate"] > 5, frame["yaw_rate"], -frame["yaw_rate"])
    assert abs(np.corrcoef(frame["yaw_rate"], frame["odom_yaw_rate"])[0, 1]) < 0.3   # the bursts hide the sign
    with pytest.raises(LogError, match="turns against odom_yaw_rate"):
        identify_skid_steer(frame, "gen.csv")


def test_a_counter_clockwise_gyro_with_the_same_bursts_is_fitted():
    rep = identify_skid_steer(with_bursts(skid_log(K=0.7, tau=-0.3, T=0.15, column="odom_yaw_rate")), "gen.csv")
    assert rep["final_model"] == "skid_steer"
