"""The kinematic regime: where the lateral acceleration is too small for the tyres to matter, identify
fits r = v tan(delta) / L with the steering map (gain, left/right asymmetry, offset) and prints no
understeer gradient, critical or characteristic speed. Truths: the small Ackermann machine's map
(gain 0.85, asymmetry 0.15, offset +0.035 rad; harness.small_ackermann) and a tractor's steering
offset at walking pace (harness.truth_tractor), each on two runs of the same truth."""
from __future__ import annotations

import pytest

from agrobot.identification.ordinary_driving import identify_driving, summary
from agrobot.orchestrator.study import Study
from agrobot.studies import shipped
from harness.small_ackermann import make_small_log, write_study
from harness.truth_tractor import make_log


def covers(q: dict, truth: float) -> bool:
    return q["interval"][0] <= truth <= q["interval"][1]


def no_tyre_numbers(rep: dict) -> None:
    text = summary(rep)
    assert rep["final_model"] == "kinematic" and rep["regime"]["kinematic"]
    assert "not identifiable at these speeds" in text
    for word in ("critical speed:", "characteristic speed:", "understeer gradient K:", "cornering stiffness front:"):
        assert not any(line.startswith(word) for line in text.splitlines()), word
    assert not rep["understeer_gradient"]["identifiable"]


@pytest.fixture(scope="module")
def small_reports(tmp_path_factory):
    study = Study.load(write_study(tmp_path_factory.mktemp("small")))
    out = []
    for seed in (1, 2):
        frame, truth = make_small_log(seed, duration=180.0)
        out.append((identify_driving(frame.drop(columns=["x", "y"]), f"small_{seed}.csv", study), truth))
    return out


def test_small_machine_steering_map_not_oversteer(small_reports):
    for rep, truth in small_reports:
        no_tyre_numbers(rep)
        smap = rep["steering_map"]
        assert covers(smap["gain"], truth["gain"]), smap["gain"]
        assert covers(smap["asymmetry"], truth["asymmetry"]), smap["asymmetry"]
        assert rep["vehicle"]["wheelbase"] == pytest.approx(truth["wheelbase"])       # the declared one, not fitted


def test_small_machine_offset_same_sign_on_two_runs(small_reports):
    for rep, truth in small_reports:
        off = rep["steering_map"]["steer_offset"]
        assert off["interval"][0] > 0 and covers(off, truth["offset"]), off


def test_tractor_at_walking_pace_offset_on_two_runs():
    """A tractor driven at 0.8-1.2 m/s with a steering offset (drawn per seed), its yaw from the GNSS
    course above 0.7 m/s: kinematic, the offset of the truth's sign inside its interval, no
    asymmetry found where the truth has none."""
    study = Study.load(shipped("figure8.toml"))
    for seed in (1, 2):
        frame, truth = make_log(seed, "steering_offset", duration=240.0, speeds=(0.8, 1.0, 1.2))
        rep = identify_driving(frame.drop(columns="yaw_rate"), f"tractor_{seed}.csv", study, course_speed=0.7)
        no_tyre_numbers(rep)
        off = rep["steering_map"]["steer_offset"]
        assert covers(off, truth["offset"]) and (off["interval"][0] > 0) == (truth["offset"] > 0), (off, truth["offset"])
        assert covers(rep["steering_map"]["asymmetry"], 0.0)
        assert abs(rep["steering_map"]["gain"]["value"] - 1.0) < 0.1


def test_the_tractor_at_working_speed_is_not_kinematic():
    frame, _ = make_log(4, None, duration=60.0)
    rep = identify_driving(frame, "tractor.csv", Study.load(shipped("figure8.toml")), max_fit_seconds=30.0)
    assert not rep["regime"]["kinematic"] and rep["regime"]["lateral_acceleration_p95"] >= 0.5
    assert rep["understeer_gradient"]["unit"] == "rad/(m/s2)"
