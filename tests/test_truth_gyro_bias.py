"""The truth's gyro bias is one its vehicle's gyro can have: a passenger car's CAN yaw rate (an
automotive sensor, its offset learnt at standstill) is drawn inside the car class's 1 deg/s
(identification.vehicle.CLASSES), a tractor's guidance gyro inside its 2 deg/s, so a planted bias is
one the diagnosis may conclude by its own bound.

Truth: harness.truth_tractor's drawn biases on 40 seeds of each vehicle; and the car's largest
draw of the quick benchmark's seeds (1005: 0.89 deg/s) named with its value."""
from __future__ import annotations

import math

import pytest

from agrobot.identification.vehicle import Vehicle
from harness.hidden_effects import diagnose_hidden, recovered
from harness.truth_tractor import make_log

SEEDS = range(1000, 1040)


@pytest.mark.parametrize("vehicle, kind", [("car", "car"), ("tractor", "tractor")])
def test_every_drawn_bias_lies_inside_its_class_bound(vehicle, kind):
    bound = Vehicle.from_table({"class": kind}).gyro_bias_bound
    biases = [abs(make_log(s, "yaw_rate_bias", duration=2.0, vehicle=vehicle)[1]["bias"]) for s in SEEDS]
    assert max(biases) < 0.95 * bound, (math.degrees(max(biases)), math.degrees(bound))
    assert min(biases) > 0.25 * bound          # still a bias worth naming, not a quarter of the class's drift


def test_the_car_keeps_the_tractors_draws_apart_from_the_bias():
    """Mapping the bias onto the car's range draws nothing more: the other truths of a seed stay."""
    frame_a, truth_a = make_log(1003, "yaw_rate_bias", duration=2.0, vehicle="car")
    frame_b, truth_b = make_log(1003, "yaw_rate_bias", duration=2.0, vehicle="car", values={"bias": 0.0})
    assert truth_a["C_f"] == truth_b["C_f"] and truth_a["tau"] == truth_b["tau"]
    assert (frame_a["v"] == frame_b["v"]).all()


@pytest.mark.slow
def test_the_cars_largest_drawn_bias_is_concluded_with_its_value(tmp_path):
    run = diagnose_hidden(("yaw_rate_bias", 1005, str(tmp_path), None, 120.0, None, "car"))
    res = run["result"]
    assert res["verdict"] == "yaw_rate_bias" and res["verdict_status"] == "conclusive", res["verdict_statement"]
    est, true, tol = recovered("yaw_rate_bias", run["truth"], res["effects"][0]["parameters"])
    assert abs(est - true) <= tol and math.degrees(abs(true)) > 0.8, (est, true)
