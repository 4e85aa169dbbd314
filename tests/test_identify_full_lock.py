"""A car turning through large road-wheel angles at parking speeds (harness.full_lock_car: exact
single-track geometry, r = v tan w / L without slip; an OBD logger's held steering and speed
copies and a yaw rate in steps of 1.28 deg/s; the road wheel 0.04 s behind the steering-wheel
reading). Driven by w where tan w is 10 % larger, the small-angle model took the missing yaw for
soft tyres and a delay searched below zero; driven by tan w it finds the car's tyres, and a delay
below zero beside a lag is judged on their sum."""
from __future__ import annotations

import pytest

from agrobot.identification.delay_bound import traded_verdict
from agrobot.identification.ordinary_driving import identify_driving
from agrobot.orchestrator.study import Study
from agrobot.studies import shipped
from harness.full_lock_car import make_log


@pytest.fixture(scope="module")
def full_lock():
    frame, truth = make_log(0)
    return identify_driving(frame, "car.csv", Study.load(shipped("passenger_car.toml"))), truth


def test_the_tyres_at_full_lock_are_the_cars(full_lock):
    rep, truth = full_lock
    for name in ("c_f", "c_r"):
        got = rep["parameters"][name]["value"]
        assert abs(got / truth[name] - 1) < 0.25, (name, got, truth[name])
    assert any("driven by tan w" in n for n in rep["notes"]), rep["notes"]


def test_the_delay_is_not_said_to_be_below_the_planted_one(full_lock):
    rep, truth = full_lock
    d = rep["delay"]
    assert d.get("verdict") != "clock offset" and "cannot decide" not in d.get("verdict", ""), d
    assert d.get("upper_limit", d["interval"][1]) >= truth["delay"] + truth["lag"], d


def test_a_lead_traded_against_a_lag_is_judged_on_their_sum():
    on_bound = {"value": 0.0, "std": float("nan"), "interval": [float("nan")] * 2, "unit": "s"}
    lead = {"value": -0.08, "std": 0.03, "interval": [-0.14, -0.02], "unit": "s"}
    kept = traded_verdict(lead, on_bound, lag=0.1, net=0.02, net_std=0.01)
    assert kept["verdict"] == "below its upper limit" and kept["value"] == 0.0
    assert kept["upper_limit"] == pytest.approx(0.02 + 1.96 * 0.01)
    offset = traded_verdict(lead, on_bound, lag=0.1, net=-0.2, net_std=0.03)
    assert offset["verdict"] == "clock offset" and offset["clock_offset"] == pytest.approx(-0.2)
