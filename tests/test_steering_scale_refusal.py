"""A steering angle on the wrong scale is named as such, not as a steering that hardly moves: the
small Ackermann machine (harness.small_ackermann, wheelbase 1.27 m, its dual-antenna heading as
the yaw measurement) with its road-wheel angle divided by a car's steering ratio of 15.8 (a study's
[vehicle] steering_ratio applied to an angle that is the road wheel's already) turns 15.8 times
more than v delta / L asks for; the same machine driven straight (its heading constant) still
hardly moves its steering."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.identification.driving import NotEnoughDriving
from agrobot.identification.ordinary_driving import identify_driving
from harness.small_ackermann import make_small_log


@pytest.fixture(scope="module")
def small():
    frame, truth = make_small_log(3, duration=120.0)
    return frame.drop(columns=[c for c in ("delta_cmd",) if c in frame]), truth


def test_an_angle_divided_by_a_steering_ratio_is_named_not_called_still(small):
    frame, truth = small
    scaled = frame.assign(delta=frame["delta"] / 15.8)
    with pytest.raises(NotEnoughDriving, match="is not the road-wheel angle") as caught:
        identify_driving(scaled, "small", None, wheelbase=truth["wheelbase"])
    said = str(caught.value)
    times = float(said.split(" times what")[0].split(", ")[-1])
    assert 8.0 < times < 25.0, said                         # about the ratio planted (15.8)
    assert "--steering-ratio 1" in said and "hardly moves" not in said


def test_a_steering_held_straight_still_hardly_moves(small):
    frame, truth = small
    heading = frame["heading"].iloc[0] + 0.001 * np.sin(np.arange(len(frame)))
    straight = frame.drop(columns=["x", "y"]).assign(delta=0.001 * np.cos(np.arange(len(frame))), heading=heading)
    with pytest.raises(NotEnoughDriving, match="hardly moves|steady turn") as caught:
        identify_driving(straight, "small", None, wheelbase=truth["wheelbase"])
    assert "not the road-wheel angle" not in str(caught.value)
