"""A value identify does not conclude is nowhere printed as concluded.

Truths: harness.truth_tractor's small Ackermann machine (wheelbase 1.27 m, linear tyres) driven at
0.6-1.9 m/s, its wheel-angle sensor reading 1.24 x the wheels' angle: its turns are 1 / 1.24 =
0.806 of what the logged angle asks, 0.6 % inside the turn scale's bound 0.8, and a gyro noisier
than the harness's (0.015 rad/s more) leaves the fitted scale's 95 % interval across that bound.
"""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.identification.ordinary_driving import TURN_GAIN, identify_driving, summary
from agrobot.orchestrator.study import Study
from harness.truth_tractor import make_log
from harness.vehicle_classes import study

SPEEDS = (0.6, 1.2, 1.9)
SENSOR_GAIN = 1.24          # the turns 1 / 1.24 = 0.806 of the logged angle's


@pytest.fixture(scope="module")
def near_bound(tmp_path_factory):
    s = Study.load(study(tmp_path_factory.mktemp("small"), speeds=SPEEDS))
    frame, _ = make_log(2, "steering_sensor_gain", vehicle="small_ackermann", speeds=SPEEDS, duration=180.0,
                        values={"sensor_gain": SENSOR_GAIN})
    frame["yaw_rate"] += np.random.default_rng(2).normal(0.0, 0.015, len(frame))
    return identify_driving(frame.drop(columns=["x", "y"]), "near_bound.csv", s)


def test_a_turn_scale_whose_interval_reaches_its_bound_is_not_concluded(near_bound):
    """The truth's scale lies within the fit's interval of the bound: whether k is inside the bounds
    is not decided, so neither k nor K (which moves with it) is concluded."""
    check, K = near_bound["steering_gain_check"], near_bound["understeer_gradient"]
    k = check["yaw_gain"]
    assert TURN_GAIN.lower == 0.8 and k["interval"][0] <= TURN_GAIN.lower < 1 / SENSOR_GAIN <= k["interval"][1], k
    assert check["turn_scale"] is None and not check["kept"] and not k["identifiable"], check
    assert "at its bound 0.8; cannot decide" in check["verdict"], check["verdict"]
    assert not K["identifiable"] and "turn scale is not concluded" in K["note"], K
    text = summary(near_bound)
    assert "turn scale k (yaw rate per v tan(w) / L): not concluded" in text, text
