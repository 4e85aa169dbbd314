"""Two shipped studies of the declared class both of the log's size: the one suggested is the nearer
in the vehicle's dimensions (wheelbase, outline, mass, in log ratio), whatever their names or the
order they are found in, and the other is named as passed over.

Truth: two robots written here, both of the log's 1.27 m wheelbase; one of the declared robot's
1.9 x 1.1 m and 120 kg, the other (the shorter, alphabetically first name) 25 % longer and 1.9 x
heavier, still within the 30 % / x2 that admit a study."""
from __future__ import annotations

import pytest

from agrobot.diagnosis import study_fit
from agrobot.diagnosis.study_fit import ShippedVehicle, suggestion
from agrobot.identification.vehicle import Vehicle

ROBOT = Vehicle.from_table({"class": "robot", "wheelbase": 0.9, "length": 1.9, "width": 1.1})
SAME = ShippedVehicle("robot_of_the_log.toml", "robot", 1.27, 1.9, 1.1, 120.0)
BIGGER = ShippedVehicle("a.toml", "robot", 1.27, 1.9 * 1.25, 1.1, 120.0 * 1.9)
TRACTOR = ShippedVehicle("b.toml", "tractor", 1.27, 1.9, 1.1, 120.0)


@pytest.mark.parametrize("order", [(BIGGER, SAME, TRACTOR), (TRACTOR, SAME, BIGGER)])
def test_the_nearer_in_size_is_suggested_and_the_other_passed_over(monkeypatch, order):
    monkeypatch.setattr(study_fit, "shipped_vehicles", lambda: order)
    text = suggestion(1.27, "mine.toml", ROBOT, 120.0)
    assert "try --study studies/robot_of_the_log.toml" in text, text
    assert "passed over: studies/a.toml" in text
    assert "b.toml" not in text                      # another class is not a candidate at all


def test_an_exact_tie_is_broken_the_same_way_in_any_order_and_said(monkeypatch):
    twin = ShippedVehicle("twin.toml", "robot", 1.27, 1.9, 1.1, 120.0)
    picks = set()
    for order in ((SAME, twin), (twin, SAME)):
        monkeypatch.setattr(study_fit, "shipped_vehicles", lambda order=order: order)
        text = suggestion(1.27, "mine.toml", ROBOT, 120.0)
        picks.add(text.split("try --study ")[1].split()[0].rstrip(";"))
        assert "as near" in text and "--study names another" in text
    assert picks == {"studies/robot_of_the_log.toml"}


def test_studies_of_the_very_same_vehicle_are_one_candidate_and_the_others_named():
    """The shipped car studies passenger_car.toml and passenger_car_identification.toml are one car
    (2.7 m, 4.7 x 1.8 m, 1500 kg): nothing physical tells them apart, so one is suggested and the
    other named beside it."""
    car = Vehicle.from_table({"class": "car", "length": 4.7, "width": 1.8})
    text = suggestion(2.7, "mine.toml", car, 1500.0)
    assert "try --study studies/passenger_car.toml" in text
    assert "studies/passenger_car_identification.toml: they differ in what they simulate" in text
