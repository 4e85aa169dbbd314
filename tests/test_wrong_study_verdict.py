"""A study whose wheelbase the log's turns miss by more than 30 % is the verdict: the study is wrong,
said with the log's wheelbase, its interval and the study's; effects that rescale the yaw rate as a
wheelbase does (gyro_scale, steering_gain, speed_scale) are not concluded on top of it. Every
understeer gradient printed beside another is flagged where its class has no such value; the report
names the steering geometry.

Independent truths: logs turning kinematically, r = v tan(delta) / L, on the wheelbase chosen here;
the paper tractor with both axle distances scaled by 0.7 (wheelbase 0.98 m, harness.truth_tractor)
diagnosed against the 1.4 m paper study; understeer gradients placed by hand beyond a class's range."""
from __future__ import annotations

import math
import re

import pytest

from agrobot.diagnosis.pipeline import diagnose, off_class
from agrobot.diagnosis.plausibility import RESCALE_YAW, UNDERSTEER
from agrobot.diagnosis.report import markdown
from agrobot.diagnosis.study_fit import study_check
from agrobot.diagnosis.verdict import WRONG_STUDY, conclude
from agrobot.identification.vehicle import Vehicle
from harness.truth_tractor import TABLE, make_log
from tests.test_plausible_for_vehicle import kinematic_log

ROBOT = Vehicle.from_table({"class": "robot", "wheelbase": 1.4, "length": 1.9, "width": 1.1})


def fitted(eid: str, **params) -> dict:
    return {"id": eid, "parameters": params, "parameters_display": {f"{k} [-]": v for k, v in params.items()},
            "hypothesis": "h", "not_identifiable": None, "fitted": {}}


def test_a_gyro_scale_is_not_concluded_on_a_study_40_percent_long():
    """A 1.0 m machine judged against a 1.4 m study: a gyro scale of 1.4 fits, but the verdict is the
    study, with the log's wheelbase and its interval; gyro_scale is listed as not concluded."""
    turns, _ = study_check(kinematic_log(1.0), 1.4, "long.toml")
    v = conclude([fitted("gyro_scale", gyro_scale=1.4), fitted("actuator_delay", command_delay=0.1)], None, [], [], [],
                 ROBOT, 1.4, 0.7, 0.8, turns=turns)
    assert v["id"] == WRONG_STUDY and "gyro_scale [-]" not in v["statement"], v["statement"]
    L, lo, hi = map(float, re.search(r"wheelbase of ([0-9.]+) m \(95 % interval \[([0-9.]+), ([0-9.]+)\] m\)",
                                     v["statement"]).groups())
    assert L == pytest.approx(1.0, rel=0.03) and lo <= 1.0 <= hi and hi < 1.4 / 1.3
    assert "the study's 1.4 m" in v["statement"] and "diagnose again" in v["statement"]
    assert any(b.startswith("not concluded (it rescales") and "gyro_scale" in b for b in v["bullets"]), v["bullets"]
    assert any("judged against this study" in b and "actuator_delay" in b for b in v["bullets"]), v["bullets"]


def test_a_study_20_percent_off_leaves_the_verdict_to_the_effects():
    turns, _ = study_check(kinematic_log(1.4 / 1.2), 1.4, "near.toml")
    v = conclude([fitted("gyro_scale", gyro_scale=1.2)], None, [], [], [], ROBOT, 1.4, 0.7, 0.8, turns=turns)
    assert v["id"] == "gyro_scale"


@pytest.mark.slow
def test_a_tractor_of_a_shorter_wheelbase_diagnosed_against_the_paper_study(tmp_path):
    """The paper tractor with l_f and l_r x 0.7 (0.98 m) against studies/figure8.toml (1.4 m), no
    --study: the verdict names the study and the log's wheelbase, no yaw rescaling is concluded; the
    report names the steering geometry the yaw model was driven under."""
    frame, _ = make_log(2, None, duration=60.0, scale={"l_f": 0.7, "l_r": 0.7})
    log = tmp_path / "short_tractor.parquet"
    frame.to_parquet(log)
    res = diagnose(log, tmp_path, None, plots=False, identify=False)
    assert res["verdict"] == WRONG_STUDY and res["verdict"] not in RESCALE_YAW, res["verdict_statement"]
    L = float(re.search(r"wheelbase of ([0-9.]+) m", res["verdict_statement"]).group(1))
    assert L == pytest.approx(0.7 * (TABLE["l_f"] + TABLE["l_r"]), rel=0.05)
    assert "figure8.toml" in " ".join(res["before_verdict"]) and "1.4 m" in res["verdict_statement"]
    report = (tmp_path / "report.md").read_text()
    assert re.search(r"^Steering geometry: the yaw model is driven by (delta|tan\(delta\))", report, re.M), report[:800]


def test_an_understeer_gradient_off_its_class_is_flagged_wherever_it_is_printed():
    """A robot's class has -11 to 11 deg/g; a diagnosis's 13.1 deg/g beside identify's 9.4 is flagged on
    the shared quantity's line, an agreeing pair of identify's estimates with one at 12.6 deg/g too."""
    hi = UNDERSTEER["robot"][1]
    k = math.radians(1.0) / 9.81          # 1 deg/g in rad/(m/s2)
    pair = {"identify": {"value": 9.4 * k}, "diagnose": {"value": 13.1 * k}}
    assert 13.1 * k > hi > 9.4 * k
    result = {"shared_quantities": [{"quantity": "understeer gradient", "estimates": pair, "line": "understeer gradient"}],
              "identified_vehicle": {"comparisons": [{"quantity": "understeer gradient K", "agree": True, "estimates": {
                  "dynamic fit": {"value": 9.4 * k}, "steady-state regression": {"value": 12.6 * k}}}]}}
    off_class(result, ROBOT, None)
    q, c = result["shared_quantities"][0], result["identified_vehicle"]["comparisons"][0]
    assert "diagnose: an understeer gradient of 13.1 deg/g is not of a robot" in q["line"] and "identify:" not in q["line"]
    assert "steady-state regression: an understeer gradient of 12.6" in c["implausible"] and "dynamic fit" not in c["implausible"]


def test_the_report_names_the_steering_geometry():
    result = {"log": "x.csv", "study": "s.toml", "split_time": 10.0, "verdict": "cannot decide", "reason": "r",
              "steering_geometry": {"says": "steering geometry: the yaw model is driven by tan(delta) (--steering-geometry "
                                            "tan); passed over: delta; SETS"}}
    assert "Steering geometry: the yaw model is driven by tan(delta) (--steering-geometry tan)" in markdown(result, [])


def test_a_steering_gain_on_a_declared_vehicle_is_the_other_reading_of_a_30_percent_mismatch():
    """A declared 1.4 m robot whose turns give 1.9 m: the wheels turning 0.74 x the input (a steering
    map's gain error, inside a calibration's range) reads the same turns; a fitted steering gain of 0.74
    is the verdict, the wrong study named beside it. The same turns against an undeclared study, or the
    default study diagnose takes when no --study is given: the study."""
    turns, _ = study_check(kinematic_log(1.9), 1.4, "declared.toml")
    assert turns and turns.get("mismatch")
    v = conclude([fitted("steering_gain", steering_gain=0.74)], None, [], [], [], ROBOT, 1.4, 0.7, 0.8, turns=turns)
    assert ROBOT.declared and v["id"] == "steering_gain", v
    assert any(b.startswith("the other reading of the same turns: the study is wrong") for b in v["bullets"]), v["bullets"]
    w = conclude([fitted("steering_gain", steering_gain=0.74)], None, [], [], [], Vehicle(), 1.4, 0.7, 0.8, turns=turns)
    assert not Vehicle().declared and w["id"] == WRONG_STUDY, w
    default = conclude([fitted("steering_gain", steering_gain=0.74)], None, [], [], [], ROBOT, 1.4, 0.7, 0.8,
                       turns={**turns, "declared": False})       # the same study as the default, no --study given
    assert default["id"] == WRONG_STUDY, default
