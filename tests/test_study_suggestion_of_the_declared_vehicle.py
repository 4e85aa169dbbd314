"""A shipped study is suggested for a log only when it is of the declared vehicle's class and size.

Independent truths: generated logs of the small Ackermann robot (wheelbase 1.27 m, 120 kg, 1.9 m x
1.1 m) and of the paper tractor (harness.truth_tractor.make_log), and a car turning kinematically,
r = v tan(delta) / L, on the 2.7 m wheelbase chosen here; the studies declare another wheelbase."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from agrobot.diagnosis.study_fit import study_check
from agrobot.identification.vehicle import Vehicle
from harness.truth_tractor import SMALL_ACKERMANN, make_log

SMALL = Vehicle.from_table({"class": "robot", "wheelbase": 0.9, "length": SMALL_ACKERMANN["length"],
                            "width": SMALL_ACKERMANN["width"]})
CAR = Vehicle.from_table({"class": "car", "wheelbase": 1.8, "length": 4.7, "width": 1.8})
TRACTOR = Vehicle.from_table({"class": "tractor", "wheelbase": 2.2, "length": 2.6, "width": 1.2})


def car_log(wheelbase: float = 2.7, seconds: float = 90.0) -> pd.DataFrame:
    rng = np.random.default_rng(5)
    t = np.arange(0, seconds, 0.05)
    v = 5.0 + 0.5 * np.sin(0.05 * t)
    delta = 0.1 * np.sin(0.3 * t)
    return pd.DataFrame({"t": t, "v": v, "delta": delta,
                         "yaw_rate": v * np.tan(delta) / wheelbase + 0.002 * rng.standard_normal(len(t))})


@pytest.fixture(scope="module")
def small_log():
    return make_log(1, None, duration=120.0, vehicle="small_ackermann")[0]


@pytest.fixture(scope="module")
def tractor_log():
    return make_log(1, None, duration=120.0, vehicle="tractor")[0]


def test_a_small_robot_is_not_pointed_to_a_tractor_of_its_wheelbase(small_log):
    """The robot's 1.27 m turns are within 30 % of the paper tractor's 1.4 m, but a tractor (700 kg,
    2.6 m long) is not a 120 kg robot: no study is suggested; the one to write is named."""
    mine, text = study_check(small_log, 0.9, "small.toml", 0.0, SMALL, SMALL_ACKERMANN["table"]["m"])
    assert mine["wheelbase"] == pytest.approx(1.27, rel=0.05)
    assert "try --study" not in text and "studies/figure8.toml at 1.4 m, is a tractor, not a robot" in text
    assert "no shipped study is of a robot" in text and 'class = "robot"' in text
    assert "length = 1.9, width = 1.1" in text


def test_a_car_is_pointed_to_the_car_study_and_a_tractor_sized_log_declared_a_car_to_none(tractor_log):
    mine, text = study_check(car_log(), 1.8, "my_car.toml", 0.0, CAR, 1500.0)
    assert mine["wheelbase"] == pytest.approx(2.7, rel=0.03)
    assert "try --study studies/passenger_car.toml" in text
    _, text = study_check(tractor_log, 1.8 * 1.6, "my_car.toml", 0.0, CAR, 1500.0)
    assert "try --study" not in text and "no shipped study is of a car" in text


def test_a_tractor_is_pointed_to_the_tractor_study(tractor_log):
    _, text = study_check(tractor_log, 2.2, "my_tractor.toml", 0.0, TRACTOR, 700.0)
    assert "try --study studies/figure8.toml" in text and "a tractor" in text


def test_a_study_of_another_mass_is_not_suggested(small_log):
    """A declared tractor of the robot's outline and mass: the 700 kg tractor study is 5.8 x heavier."""
    small_tractor = Vehicle.from_table({"class": "tractor", "length": 2.6, "width": 1.2})
    _, text = study_check(small_log, 0.9, "small.toml", 0.0, small_tractor, 120.0)
    assert "try --study" not in text and "no shipped study is of a tractor" in text
