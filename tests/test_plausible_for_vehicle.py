"""Every concluded value is checked against the declared vehicle: its class, dimensions and speeds.

Independent truths: logs turning kinematically, r = v tan(delta) / L, with the wheelbase chosen
here; fitted values placed by hand where a vehicle of the class cannot have them."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from agrobot.components.models.yaw_dynamics import TractorParameters
from agrobot.diagnosis.plausibility import slip_share, understeer
from agrobot.diagnosis.study_fit import study_check
from agrobot.diagnosis.verdict import conclude, judge_values
from agrobot.identification.vehicle import Vehicle

ROBOT = Vehicle.from_table({"class": "robot", "wheelbase": 1.27})             # no length, no width
RACECAR = Vehicle.from_table({"class": "car", "wheelbase": 2.97, "length": 4.9, "width": 1.9})


def kinematic_log(wheelbase: float, speed: float = 0.7, seconds: float = 60.0) -> pd.DataFrame:
    rng = np.random.default_rng(3)
    t = np.arange(0, seconds, 0.05)
    v = speed + 0.1 * np.sin(0.1 * t)
    delta = 0.3 * np.sin(0.4 * t)
    return pd.DataFrame({"t": t, "v": v, "delta": delta,
                         "yaw_rate": v * np.tan(delta) / wheelbase + 0.002 * rng.standard_normal(len(t))})


def effect(eid, **params):
    return {"id": eid, "parameters": params, "parameters_display": {f"{k} [SI]": v for k, v in params.items()},
            "hypothesis": "h", "not_identifiable": None}


def test_a_study_is_suggested_only_for_a_vehicle_of_the_logs_size():
    """A 1.27 m machine whose steering map turns the wheels twice the reading turns like a 0.62 m one:
    the f1tenth study (0.32 m) is not of its size and is not suggested; the mismatch is named with both
    wheelbases and the steering map as the other reading."""
    mine, text = study_check(kinematic_log(0.62), 1.27, "small.toml")
    assert mine["wheelbase"] == pytest.approx(0.62, rel=0.03)
    assert "f1tenth" not in text.split("nearest")[0] and "try --study" not in text
    assert "1.27 m" in text and "steering map" in text


def test_a_study_30_percent_off_the_logs_turns_is_named():
    assert study_check(kinematic_log(1.27 * 1.35), 1.27, "small.toml")[1] is not None
    assert study_check(kinematic_log(1.27 * 1.2), 1.27, "small.toml")[1] is None


def test_a_declared_vehicle_without_dimensions_gets_its_class_defaults_named_and_judged_against():
    """A robot of wheelbase 1.27 m: its default outline reaches 0.3 wheelbase ahead of the front axle,
    1.65 m from the rear one; a point 1.85 m ahead is outside it (a wheelbase-and-a-half box would not say so)."""
    v = conclude([effect("antenna_lever_arm", antenna_forward=1.85, antenna_left=0.0)], None, [], [], [], ROBOT,
                 1.27, 0.67, 0.7)
    assert any("robot" in b and "defaults" in b and "1.65" not in b for b in v["before"]), v["before"]
    assert v["status"] == "implausible" and "default outline" in v["statement"]


def test_a_reference_point_is_placed_from_the_studys_antenna():
    """A localisation filter's point 3.42 m ahead of a study antenna at the centre of gravity (1.5 m ahead
    of the rear axle) is 4.92 m ahead of the rear axle: outside a 4.9 m racecar whose rear overhang is
    1.2 m (Vehicle.lever_arm_bounds)."""
    ref = effect("position_reference", position_forward=3.42, position_left=0.0, position_clock=0.2)
    v = conclude([ref], None, [], [], [], RACECAR, 2.97, 1.5, 20.0, antenna=(1.5, 0.0))
    assert v["status"] == "implausible" and "4.92 m ahead of the rear axle" in v["statement"]
    assert judge_values(ref, RACECAR, 2.97, 1.5, 20.0) == []       # 3.42 + a study antenna at the axle: inside


def test_a_side_slope_on_its_limit_is_no_slope_of_the_class():
    pull = 9.81 * math.sin(math.radians(30.0))
    notes = judge_values(effect("side_slope", slope_east=pull, slope_north=0.0), ROBOT, 1.27, 0.67, 0.7)
    assert len(notes) == 1 and "30.0 deg is steeper" in notes[0]


def test_an_understeer_gradient_is_not_concluded_in_the_kinematic_regime_nor_off_its_class():
    """The small machine (120 kg, C = 3000 N/rad per axle) at 0.2 m/s2 with 0.5 rad of steering: its
    tyres slip 0.9 % of the steering angle, the kinematic regime; -3.1 rad/(m/s2) there is not identifiable
    at these speeds; on a log that reaches the tyres, not of the class; 1.5 deg/g on a car is one."""
    machine = TractorParameters(m=120.0, I=30.0, l_f=0.6, l_r=0.67, C_f=3000.0, C_r=3000.0, sigma_f=0.02, sigma_r=0.0)
    share = slip_share(machine, 0.2, 0.5)
    assert share == pytest.approx(120 * 0.2 * 0.67 / (1.27 * 3000) / 0.5)
    assert "not identifiable at these speeds" in understeer(-3.1, ROBOT, share)
    assert "is not of a robot" in understeer(-3.1, ROBOT, 0.1)
    assert understeer(math.radians(1.5) / 9.81, RACECAR, 0.5) is None
