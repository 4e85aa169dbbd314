"""Before any verdict the diagnosis checks that the study's vehicle can do what the log shows: its
steering actuator's full rate, its lock and the tightest turn it gives, its top speed, its tyres'
grip; a log beyond them by more than 1.25 x names the study as not this vehicle's, with both numbers,
and the verdict is the wrong study's, not "unexplained".

Independent truths: generated logs (harness.truth_tractor.make_log) of the small Ackermann robot
(its servo turns the wheels at up to 1.5 rad/s, VEHICLES["small_ackermann"]["rate"]; dual-antenna
heading, no gyro: harness.diagnosis_classes.heading_instead_of_gyro) and of the paper tractor
(60 deg/s, 1-3 m/s); the paper tractor's steering at full valve opening turns 60 deg/s (12 L/min
over the cylinder's volume per radian, components.steering_hydraulics)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from agrobot.diagnosis.pipeline import diagnose
from agrobot.diagnosis.plausibility import LIMIT_MARGIN, RATE_MARGIN
from agrobot.studies import shipped
from harness.diagnosis_classes import heading_instead_of_gyro
from harness.truth_tractor import STEERING_RATE, VEHICLES, make_log
from harness.vehicle_classes import study as small_study

CANNOT = "the study's vehicle cannot do what the log shows"


@pytest.fixture(scope="module")
def robot_log(tmp_path_factory):
    """The small robot at 0.5-0.85 m/s, heading from a dual antenna, no gyro (120 s: against the tractor study it ended "unexplained", the steering stage 7 x its floor)."""
    frame, truth = make_log(3, None, duration=120.0, vehicle="small_ackermann")
    frame = heading_instead_of_gyro(frame, np.random.default_rng([3, 11]), truth)
    path = tmp_path_factory.mktemp("robot") / "robot.parquet"
    frame.to_parquet(path)
    return path


@pytest.fixture(scope="module")
def tractor_log(tmp_path_factory):
    frame, _ = make_log(3, None, duration=90.0, vehicle="tractor")
    path = tmp_path_factory.mktemp("tractor") / "tractor.parquet"
    frame.to_parquet(path)
    return path, frame


def test_a_robot_log_against_the_default_tractor_study_notes_the_steering_rate(robot_log):
    """The robot's wheelbase is within 10 % of the tractor's, so the wheelbase check is silent; its
    steering turns the wheels 1.4 x faster than the tractor's hydraulics: said first among the
    warnings with both numbers and what else reads alike. An actuator's rate is a soft figure
    (healthy generated vehicles reach 1.33 x their study's), so under RATE_MARGIN it is not a
    wrong-study verdict."""
    result = diagnose(robot_log, None, None, plots=False, workers=1)
    said = result["study_limits"]["noted"]
    log_rate = result["study_limits"]["log"]["steering_rate"]
    assert log_rate == pytest.approx(VEHICLES["small_ackermann"]["rate"], rel=0.1)
    assert LIMIT_MARGIN < log_rate / STEERING_RATE < RATE_MARGIN
    assert f"{math.degrees(log_rate):.0f} deg/s" in said and f"{math.degrees(STEERING_RATE):.0f} deg/s" in said
    assert "sensor reading high" in said and "another vehicle" in said
    assert result["warnings"][0] == said and result["study_limits"]["beyond"] == []
    assert result["verdict"] != "wrong_study"


def test_the_same_log_against_a_robot_study_is_within_its_limits(robot_log, tmp_path):
    """The robot's own study (servo at 1.5 rad/s, lock 0.9 rad): nothing named, and what was
    compared is kept."""
    result = diagnose(robot_log, None, small_study(tmp_path), plots=False, identify=False, workers=1)
    assert result["study_limits"]["beyond"] == []
    assert result["study_limits"]["study"]["rate"] == pytest.approx(1.5, rel=0.01)
    assert not any(CANNOT in line for line in result["before_verdict"] + result["warnings"])
    assert result["verdict"] != "wrong_study"


def test_a_tractor_log_against_the_tractor_study_raises_no_alarm(tractor_log):
    """The paper tractor's log, its steering at the same 60 deg/s as the study's: no limit named."""
    result = diagnose(tractor_log[0], None, None, plots=False, identify=False, workers=1)
    limits = result["study_limits"]
    assert limits["beyond"] == [] and result["verdict"] != "wrong_study"
    assert limits["log"]["steering_rate"] == pytest.approx(STEERING_RATE, rel=0.1)
    assert "steering rate" in limits["compared"] and "turn radius" in limits["compared"]


def test_a_study_with_a_smaller_lock_and_top_speed_is_named_with_each(tractor_log, tmp_path):
    """The tractor study with its lock at 8 deg (tightest turn 1.4 m / tan 8 deg = 10 m) and its
    drivetrain's top speed at 2 m/s, declared by the user: the log's 3 m/s, its wheel angles and
    its tighter steady turns are each named, the study's limits are said as possibly not this
    vehicle's, and a shipped study is not suggested against them."""
    study = tmp_path / "slow_tractor.toml"
    study.write_text(f'extends = "{shipped("figure8.toml").as_posix()}"\n'
                     '[components.steering]\nparameters = { angle_limit = "8 deg" }\n'
                     '[components.drivetrain]\nparameters = { max_speed = 2.0 }\n')
    result = diagnose(tractor_log[0], None, study, plots=False, identify=False, workers=1)
    beyond = result["study_limits"]["beyond"]
    top = max(VEHICLES["tractor"]["speeds"])
    peak = float(np.max(np.abs(tractor_log[1]["delta"])))
    assert result["study_limits"]["log"]["speed"] == pytest.approx(top, rel=0.05)
    assert any(b.startswith("a speed of") and "top speed, 2 m/s" in b for b in beyond), beyond
    assert any(b.startswith(f"a wheel angle of {math.degrees(peak):.0f} deg") and "lock, 8 deg" in b for b in beyond)
    radius = result["study_limits"]["log"]["min_radius"]
    assert 1.4 / math.tan(peak) < radius < 1.4 / math.tan(math.radians(8)) / 1.2
    assert any("steady turn" in b and "= 10 m" in b for b in beyond)
    said = result["before_verdict"][0]
    assert said.startswith(CANNOT) and "the limits it declares are not this vehicle's" in said
    assert result["verdict"] == "wrong_study"


def test_a_wheel_angle_sensor_reading_high_is_said_beside_the_limit(tmp_path):
    """A tractor whose wheel-angle sensor reads 1.35 x the wheels (planted): its logged steering is
    1.35 x the hydraulics' full rate; a sensor's calibration error shows the same, so it is noted
    with that reading named, not judged a wrong study."""
    frame, _ = make_log(3, "steering_sensor_gain", duration=90.0, vehicle="tractor", values={"sensor_gain": 1.35})
    frame.to_parquet(tmp_path / "sensor.parquet")
    result = diagnose(tmp_path / "sensor.parquet", None, None, plots=False, identify=False, workers=1)
    limits = result["study_limits"]
    assert limits["log"]["steering_rate"] / STEERING_RATE == pytest.approx(1.35, rel=0.05)
    assert limits["beyond"] == [] and "a wheel-angle sensor reading high" in limits["noted"]
    assert not any(line.startswith(CANNOT) for line in result["before_verdict"])    # the rate makes no wrong study


def test_a_steering_rate_past_twice_the_study_s_is_a_wrong_study():
    """Past RATE_MARGIN x the actuator's full rate the log is not the study's vehicle: named."""
    from agrobot.diagnosis.plausibility import beyond_limits
    from agrobot.diagnosis.vehicle_limits import StudyLimits
    study = StudyLimits(wheelbase=1.4, lock=0.8, rate=1.0, top_speed=4.0, friction=0.8)
    log = {"speed": 2.0, "steering_rate": 2.3, "rate_window": 0.25, "angle_noise": 0.0}
    checked = beyond_limits(log, study)
    assert checked["beyond"] and checked["beyond"][0].startswith("the wheels turning at 132 deg/s")
    assert beyond_limits({**log, "steering_rate": 1.6}, study)["beyond"] == []


def test_an_unmeasured_reading_noise_adds_no_margin_and_hides_no_limit():
    """A wheel-angle reading noise that could not be measured (NaN) is no margin: a 3x steering rate
    and a lock half again the study's are still named (a NaN margin made every comparison false)."""
    from agrobot.diagnosis.plausibility import beyond_limits
    from agrobot.diagnosis.vehicle_limits import StudyLimits
    study = StudyLimits(wheelbase=1.4, lock=0.6, rate=1.0, top_speed=4.0, friction=0.8)
    log = {"speed": 2.0, "lateral_acceleration": 1.0, "steering_rate": 3.0, "rate_window": 0.25, "wheel_angle_third_largest": 0.9,
           "angle_noise": float("nan")}
    said = " ".join(b if isinstance(b, str) else str(b) for b in beyond_limits(log, study)["beyond"])
    assert "steering rate" in said or "turning at" in said, said
    assert "wheel angle" in said or "lock" in said, said
