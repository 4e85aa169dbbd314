"""Without a gyro, a heading measures yaw: identify (and diagnose) fit the yaw stage on a dual-antenna
heading held between its 5 Hz updates, or on the GNSS course above a stated speed, with the heading's
own update rate in the noise model, and say which measurement they used. Checked against generated
recordings whose truth is known (harness.small_ackermann: a 1.27 m machine, its heading noise and
update rate; harness.truth_tractor: the tractor's stiffnesses, so its understeer gradient in closed form)."""
from __future__ import annotations

import math
import re

import numpy as np
import pytest

from agrobot.identification.driving import understeer_gradient
from agrobot.identification.ordinary_driving import identify_driving, summary
from agrobot.identification.yaw_measurement import with_yaw_rate
from agrobot.measurements import LogError
from agrobot.orchestrator.study import Study
from agrobot.studies import shipped
from harness.small_ackermann import make_small_log, write_study
from harness.truth_tractor import TABLE, make_log

DEG = math.pi / 180


@pytest.fixture(scope="module")
def small_study(tmp_path_factory):
    return write_study(tmp_path_factory.mktemp("small"))


def covers(q: dict, truth: float) -> bool:
    return q["interval"][0] <= truth <= q["interval"][1]


def test_a_held_heading_is_read_on_its_own_updates():
    """5 Hz updates held in 20 Hz rows: the update rate is 5 Hz, not the rows' 20, and the yaw-rate
    noise on the rows is the heading's noise over its update interval (0.3 deg / 0.2 s)."""
    frame, truth = make_small_log(3, duration=120.0)
    _, m = with_yaw_rate(frame.drop(columns=["x", "y"]), "small.csv")
    assert m.kind == "dual-antenna heading"
    assert abs(m.update_hz - truth["heading_rate"]) < 0.05
    expected = 0.3 * DEG * truth["heading_rate"]
    assert 0.7 * expected < m.noise < 1.5 * expected
    assert "5 Hz updates" in m.text and "dual-antenna heading" in m.text


def test_identify_fits_the_yaw_on_a_dual_antenna_heading(small_study):
    frame, truth = make_small_log(1, duration=180.0)
    assert "yaw_rate" not in frame
    rep = identify_driving(frame.drop(columns=["x", "y"]), "small.csv", Study.load(small_study))
    text = summary(rep)
    assert "yaw measured by: dual-antenna heading, 5 Hz updates" in text
    assert rep["yaw_measurement"]["kind"] == "dual-antenna heading"
    smap = rep["steering_map"]
    assert covers(smap["gain"], truth["gain"]) and covers(smap["steer_offset"], truth["offset"])
    # the effective sample size never exceeds the heading's own updates on the scored samples
    assert rep["fit"]["n_eff"] <= rep["fit"]["n"] / 4 + 1


@pytest.mark.slow
def test_identify_fits_the_tractor_on_the_gnss_course():
    """The tractor's gyro dropped: the course above 1 m/s gives an understeer gradient whose interval
    holds the truth's, K = m / L (l_r / C_f - l_f / C_r)."""
    frame, truth = make_log(1, None, duration=240.0)
    rep = identify_driving(frame.drop(columns="yaw_rate"), "tractor.csv", Study.load(shipped("figure8.toml")))
    assert "yaw measured by: GNSS course above 1 m/s" in summary(rep)
    m, lf, lr = TABLE["m"], TABLE["l_f"], TABLE["l_r"]
    k_true = m / (lf + lr) * (lr / truth["C_f"] - lf / truth["C_r"])
    K = rep["understeer_gradient"]
    assert covers(K, k_true), (K, k_true)
    assert understeer_gradient(1.0, 2.0) > 0          # the formula's sign: understeer positive


def test_a_slow_robot_reads_its_course_at_its_own_speeds(small_study):
    """A robot at 0.5-0.9 m/s tracked at 120 Hz to 1 mm, positions only: the course is read where
    0.5 s chords keep its noise sqrt(2) sigma / chord within 0.05 rad (a few cm/s here), the 1 m/s
    passed over and said; the steering map's intervals hold the truth's (a machine without understeer:
    the kinematic map's gain is g L / (L + K v^2), which millimetre positions tell from g). An explicit
    course_speed wins."""
    frame, truth = make_small_log(4, duration=150.0, truth={"understeer": 0.0}, speeds=(0.5, 0.9), rate=120.0,
                                  positions=(120.0, 0.001))
    frame = frame.drop(columns="heading")
    rep = identify_driving(frame, "robot.csv", Study.load(small_study))
    measured = rep["yaw_measurement"]
    assert measured["kind"] == "GNSS course" and measured["course_speed"] < 0.2
    assert "passed over the 1 m/s default" in measured["course_choice"] and "--course-speed" in measured["course_choice"]
    assert "mm across the track" in summary(rep)
    smap = rep["steering_map"]
    assert covers(smap["gain"], truth["gain"]) and covers(smap["steer_offset"], truth["offset"]), smap
    with pytest.raises(LogError, match="move forward at 1 m/s or more"):
        identify_driving(frame, "robot.csv", Study.load(small_study), course_speed=1.0)


def test_a_receivers_course_at_walking_pace_is_refused_with_its_noise(small_study):
    """Fixes at 10 Hz with 2 cm noise: the course needs about 1.1 m/s on 0.5 s chords for 0.05 rad,
    held at the 1 m/s (and 5-update chords) of before; at 0.5 m/s it is refused, the noise, the bound
    and the option said, with the longer chord a --course-speed at its own speed would read it on."""
    frame, _ = make_small_log(4, duration=60.0, speeds=(1.1, 1.5))
    _, m = with_yaw_rate(frame.drop(columns="heading"), "tractor.csv")
    assert (m.course_speed, m.chord_updates) == (1.0, 5) and "held at the 1 m/s default" in m.course_choice
    slow, _ = make_small_log(4, duration=90.0, speeds=(0.45, 0.55))
    with pytest.raises(LogError) as err:
        identify_driving(slow.drop(columns="heading"), "walk.csv", Study.load(small_study))
    text = str(err.value)
    assert "walk.csv" in text and "too few to read the GNSS course" in text
    assert all(s in text for s in ("mm across the track at 10 Hz", "within 0.05 rad", "held at the 1 m/s default",
                                   "--course-speed changes it")), text
    assert re.search(r"--course-speed 0\.[45]\d?, its median speed, reads it on chords of 0\.5 m, 1\.\d+ s", text), text


@pytest.mark.parametrize("case, expect", [("frozen", "never updates"), ("degrees", "expected radians"),
                                          ("compass", "a compass heading")])
def test_a_heading_that_cannot_measure_yaw_is_named(small_study, case, expect):
    frame, _ = make_small_log(3, duration=60.0)
    frame = frame.drop(columns=["x", "y"])
    if case == "compass":                   # clockwise from north: the yaw rate's sign reversed
        frame["heading"] = np.angle(np.exp(1j * (math.pi / 2 - frame["heading"])))
    else:
        frame["heading"] = 0.3 if case == "frozen" else np.degrees(frame["heading"]) + 180.0
    with pytest.raises(LogError) as err:
        identify_driving(frame, "small.csv", Study.load(small_study))
    assert "small.csv" in str(err.value) and "'heading'" in str(err.value) and expect in str(err.value)


@pytest.mark.slow
def test_diagnose_judges_the_yaw_stage_on_the_heading(small_study, tmp_path):
    from agrobot.diagnosis.pipeline import diagnosis

    frame, truth = make_small_log(2, duration=150.0)
    path = tmp_path / "small.csv"
    frame.to_csv(path, index=False)
    result, _ = diagnosis(path, small_study, plots=False)
    assert result["yaw_measurement"]["kind"] == "dual-antenna heading"
    assert "yaw" in result["stages_judged"]
    # the yaw stage's floor is at least the heading's own noise, not the interpolated rows' top band
    assert result["noise_floor"]["yaw"] >= 0.99 * result["yaw_measurement"]["noise"]


def test_a_command_held_for_seconds_is_driving_not_a_multisine(small_study, tmp_path):
    """The machine's path-follower command (random steps held 1.5-4 s) repeats itself at short lags
    inside its holds, but has no period: identify takes the log as ordinary driving."""
    from agrobot.identification.experiment import detect_period
    from agrobot.identification.from_log import choose_method

    frame, _ = make_small_log(5, duration=120.0)
    with pytest.raises(LogError):
        detect_period(frame["delta_cmd"].to_numpy(float))
    path = tmp_path / "small.csv"
    frame.drop(columns=["x", "y"]).to_csv(path, index=False)
    assert choose_method(path, study=Study.load(small_study)) == "driving"
