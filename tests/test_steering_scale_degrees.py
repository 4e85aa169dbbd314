"""A road-wheel angle written in degrees but declared in radians is not taken for a handwheel's.

The car of test_identify_hard_driving (its linear-tyre drive: the yaw rate is 1 / (1 + K v^2 / L)
times v delta / L, the slope near 0.9) with its road-wheel angle written in degrees and declared
[rad]: read as radians its turns' slope is 1 / 57.3 of that, nearer a handwheel's 1 / 15.8 than a
road wheel's 1, yet nearest the road-wheel-in-degrees reading (57.3 x slope = 0.9). The study's
steering ratio 15.8 is not divided into it: the import refuses, naming the file, the column and
the unit to declare. Scored directly: the four readings of road_wheel_or_handwheel on slopes
planted at each.
"""
from __future__ import annotations

import math

import pytest

from agrobot.measurements.log import LogError
from agrobot.measurements.recording import import_recording
from agrobot.measurements.steering_scale import road_wheel_or_handwheel
from agrobot.orchestrator.study import load_study
from tests.test_identify_hard_driving import CAR, drive, options, write

DEG = 180 / math.pi


def test_a_road_wheel_angle_in_degrees_declared_radians_is_refused_not_divided(tmp_path):
    car = drive(60.0)
    degrees = dict(car, delta=DEG * car["delta"])
    with pytest.raises(LogError) as caught:
        import_recording(write(tmp_path / "deg", degrees), options().for_vehicle(load_study(CAR)))
    said = str(caught.value)
    assert "road wheel in degrees" in said and "--signal delta=COLUMN[deg]" in said, said
    assert str(tmp_path / "deg") in said and "delta (" in said, said
    assert "no steering ratio chosen" in said


@pytest.mark.parametrize("slope, reading", [(0.9, False), (0.9 / 15.8, True), (0.9 / DEG, "road wheel in degrees"),
                                            (0.9 / DEG / 15.8, "handwheel in degrees")])
def test_each_of_the_four_readings_is_told(slope, reading):
    if isinstance(reading, str):
        with pytest.raises(LogError, match=reading):
            road_wheel_or_handwheel((slope, 0.95, 500), 15.8, "log.csv: delta")
    else:
        assert road_wheel_or_handwheel((slope, 0.95, 500), 15.8)[0] is reading


def test_readings_as_near_as_each_other_are_left_undecided():
    between = math.sqrt(1 / DEG * 1 / 15.8)          # as near the handwheel's (1 / 15.8) as 1 / 57.3
    assert road_wheel_or_handwheel((between, 0.95, 500), 15.8)[0] is None
