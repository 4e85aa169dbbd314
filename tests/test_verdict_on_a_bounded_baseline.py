"""No effect is concluded on top of a baseline refit that ended on its bounds, and no lever arm is
concluded outside the declared car's outline.

Independent truths placed by hand: the refit's values put on the catalogue's own bounds (or inside
them), and a reference point 1.2 m ahead of a 2.7 m car's front axle whose body ends 0.92 m ahead
of it (4.7 m long: the 2 m beyond the wheelbase split as a car's overhangs, 0.35 : 0.30)."""
from __future__ import annotations

import pytest

from agrobot.diagnosis.baseline import refit_summary
from agrobot.diagnosis.pipeline import diagnose
from agrobot.diagnosis.catalogue import UNCERTAIN
from agrobot.diagnosis.verdict import conclude, judge_values, on_bounded_baseline
from agrobot.identification.vehicle import Vehicle
from harness.hidden_effects import BASELINES
from harness.truth_tractor import make_log

CAR = Vehicle.from_table({"class": "car", "wheelbase": 2.7, "length": 4.7, "width": 1.8})
STUDY = {"cornering_front_scale": 1.0, "cornering_rear_scale": 1.0, "relaxation_scale": 1.0}


def effect(eid, **params):
    return {"id": eid, "parameters": params, "parameters_display": {f"{k} [SI]": v for k, v in params.items()},
            "hypothesis": "h", "not_identifiable": None}


def verdict_on(refit: dict[str, float]) -> dict:
    arm = effect("yaw_rate_bias", yaw_rate_bias=0.01)
    v = conclude([arm], None, [], [], [], CAR, 2.7, 1.5, 20.0)
    assert v["status"] == "conclusive"
    return on_bounded_baseline(v, refit_summary(STUDY, refit, UNCERTAIN["yaw"]))


def test_an_effect_on_a_baseline_refit_on_its_bounds_cannot_be_decided():
    """The racecar's refit: the front scale on its lower bound 0.4, the rear on its upper 2.5."""
    v = verdict_on({"cornering_front_scale": 0.4, "cornering_rear_scale": 2.5, "relaxation_scale": 1.7})
    assert v["status"] == "cannot decide" and v["statement"].startswith("cannot decide")
    assert "cornering_front_scale, cornering_rear_scale end on their bounds" in v["statement"]
    assert "0.4 on its lower bound" in v["statement"] and "2.5 on its upper bound" in v["statement"]
    assert "relaxation_scale" not in v["statement"]
    assert "yaw_rate_bias may be absorbing the misfit" in v["statement"] and "study of this vehicle" in v["statement"]
    assert v["bullets"][0].startswith("on that baseline (conclusive): yaw_rate_bias")


@pytest.mark.parametrize("refit", [STUDY, {"cornering_front_scale": 0.42, "cornering_rear_scale": 2.4,
                                           "relaxation_scale": 2.9}])
def test_a_refit_inside_its_bounds_leaves_the_verdict(refit):
    v = verdict_on(refit)
    assert v["status"] == "conclusive" and v["statement"].startswith("yaw_rate_bias")


def test_a_reference_point_ahead_of_the_cars_nose_is_no_mounting():
    """4.18 m ahead of the rear axle of the 2.7 m car: 1.48 m ahead of its front axle, beyond the 0.92 m
    front overhang (the whole length, 4.7 m, ahead of the rear axle only without a rear overhang)."""
    outside = effect("antenna_lever_arm", antenna_forward=4.18, antenna_left=-0.15)
    notes = judge_values(outside, CAR, 2.7, 1.5, 20.0)
    assert len(notes) == 1 and "outside its outline" in notes[0] and "0.92 m ahead of the front one" in notes[0]
    assert judge_values(effect("antenna_lever_arm", antenna_forward=3.55, antenna_left=0.0), CAR, 2.7, 1.5, 20.0) == []
    assert judge_values(effect("antenna_lever_arm", antenna_forward=-1.0, antenna_left=0.0), CAR, 2.7, 1.5, 20.0) == []
    v = conclude([outside], None, [], [], [], CAR, 2.7, 1.5, 20.0)
    assert v["status"] == "implausible"


def test_a_lever_arm_outside_the_outline_on_a_bounded_refit_names_the_refit_first():
    """The full racecar log: the reference point outside the car and the three tyre scales on their bounds
    (0.4 lower, 2.5 and 10 upper): the refit that cannot represent the car is said first."""
    outside = effect("antenna_lever_arm", antenna_forward=4.18, antenna_left=-0.15)
    v = conclude([outside], None, [], [], [], CAR, 2.7, 1.5, 20.0)
    refit = {"cornering_front_scale": 0.4, "cornering_rear_scale": 2.5, "relaxation_scale": 3.0}
    v = on_bounded_baseline(v, refit_summary(STUDY, refit, UNCERTAIN["yaw"]))
    assert v["status"] == "cannot decide" and "relaxation_scale" in v["statement"]
    assert "antenna_lever_arm may be absorbing" in v["statement"]
    assert v["bullets"][0].startswith("on that baseline (implausible)") and "outside its outline" in v["bullets"][0]


def _diagnosed(tmp_path, effect_id: str, scale: dict | None) -> tuple[dict, dict]:
    frame, truth = make_log(3, effect_id, duration=120.0, vehicle="car", scale=scale)
    frame.to_parquet(tmp_path / "car.parquet")
    result = diagnose(tmp_path / "car.parquet", tmp_path / "out", plots=False, study_path=BASELINES["car"],
                      identify=False, workers=1)
    return result, truth


@pytest.mark.slow                       # about 7 s of CPU, near 20 s on a loaded machine
def test_a_racing_tyre_the_study_cannot_hold_is_searched_out_to_its_limit(tmp_path):
    """A car on tyres three times as stiff as the study's (C_f x 3, C_r x 3, drawn around that): the rear
    scale the yaw rate and the track ask for together lies beyond the prior range [0.4, 2.5]; searched
    again out to its limit it ends near the truth's C_r / 100000 N/rad, on no bound."""
    result, truth = _diagnosed(tmp_path, "antenna_lever_arm", {"C_f": 3.0, "C_r": 3.0})
    rows = {r["name"]: r for r in result["baseline_refit_summary"]}
    rear = rows["cornering_rear_scale"]
    assert rear["at_bound"] is None and rear["bounds"][1] > 2.5
    assert rear["value"] == pytest.approx(truth["C_r"] / 100000.0, rel=0.15)


@pytest.mark.slow                       # a whole diagnosis of a 60 s car log: 7 s
def test_an_ordinary_car_log_keeps_its_verdict(tmp_path):
    """The study's own car with a gyro bias: the refit ends on no bound and the bias is concluded."""
    result, truth = _diagnosed(tmp_path, "yaw_rate_bias", None)
    assert not any(r["at_bound"] for r in result["baseline_refit_summary"])
    assert result["verdict"] == "yaw_rate_bias" and result["verdict_status"] == "conclusive"
