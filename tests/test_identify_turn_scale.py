"""A scale of the turns is not understeer, and no value is concluded past what the log supports.
Truths from harness.truth_tractor's small Ackermann machine (wheelbase 1.27 m, linear tyres of
known stiffness) driven at 0.6-1.9 m/s: its wheel-angle sensor reading 4 % more than the wheels
turn (the tyres see 1/1.04 of the logged angle); and a steering offset of 0.15 rad (8.6 deg, more
than a robot's angle sensor can be off) on a log that begins with 5 s standing still; the passenger
car with its tyres saturating F = C alpha / (1 + |alpha| / alpha_s) (a bend the Magic Formula does not
take exactly) and no scale of the turns, and healthy; the F1TENTH study driven at one speed, its
angle taken as measured.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from agrobot.identification.ordinary_driving import characteristic_speed, identify_driving, summary
from agrobot.orchestrator.study import Study
from harness.truth_tractor import SMALL_ACKERMANN, make_log
from harness.vehicle_classes import study
from tests.test_understeer_at_one_speed import STUDY as F1TENTH, one_speed_log
from tests.vehicle_logs import ROOT_STUDIES as STUDIES

SPEEDS = (0.6, 1.2, 1.9)
SENSOR_GAIN = 1.04


def true_k(truth: dict) -> float:
    """K = m / L (l_r / C_f - l_f / C_r) of the truth's stiffnesses [rad/(m/s2)]."""
    t = SMALL_ACKERMANN["table"]
    L = t["l_f"] + t["l_r"]
    return t["m"] / L * (t["l_r"] / truth["C_f"] - t["l_f"] / truth["C_r"])


@pytest.fixture(scope="module")
def scaled(tmp_path_factory):
    s = Study.load(study(tmp_path_factory.mktemp("small"), speeds=SPEEDS))
    frame, truth = make_log(1, "steering_sensor_gain", vehicle="small_ackermann", speeds=SPEEDS, duration=180.0,
                            values={"sensor_gain": SENSOR_GAIN})
    return identify_driving(frame.drop(columns=["x", "y"]), "scaled.csv", s), truth


def test_a_turn_scale_is_not_read_as_understeer(scaled):
    rep, truth = scaled
    K = rep["understeer_gradient"]
    check = rep["steering_gain_check"]
    assert check["yaw_gain"]["value"] == pytest.approx(1 / SENSOR_GAIN, abs=0.015), check
    assert check["held_out_gain"]["mean"] > 1.96 * check["held_out_gain"]["std_error"], check     # borne out
    if K["identifiable"]:
        assert K["interval"][0] <= true_k(truth) <= K["interval"][1], (K, true_k(truth))
    else:        # withheld for the scale it carries (the truth's), not for anything else
        assert "scale of the turns" in K["note"] and check["turn_scale"] is None, (K, check)


def test_no_characteristic_speed_far_past_the_log(scaled):
    rep, _ = scaled
    text = summary(rep)
    assert not any(line.startswith(("characteristic speed:", "critical speed:")) for line in text.splitlines()), text
    assert not rep["characteristic_speed"]["identifiable"]


def test_characteristic_speed_only_within_twice_the_top_speed():
    """sqrt(L / K): 1.27 m at K 0.005 gives 15.9 m/s, past 2 x 1.9 m/s; at K 0.1, 3.56 m/s, within."""
    far = characteristic_speed(0.005, 0.001, 1.27, top_speed=1.9)
    near = characteristic_speed(0.1, 0.01, 1.27, top_speed=1.9)
    assert not far["identifiable"] and "not identifiable at these speeds" in far["note"]
    assert near["identifiable"] and near["value"] == pytest.approx(math.sqrt(1.27 / 0.1))


def test_linear_range_is_at_least_the_largest_lateral_acceleration(scaled):
    """The truth's tyres are linear: the bend is not reached, the range is "at least" the log's top."""
    rep, _ = scaled
    lr = rep["linear_range"]
    assert lr["at_least"] and not rep["tyre_saturation"]["found"]
    assert f"at least up to {lr['value']:.3g} m/s2" in summary(rep)
    assert "[" not in summary(rep).split("linear model holds")[1].splitlines()[0].split("(")[0]


def test_bias_and_offset_without_a_standstill_are_not_concluded(scaled):
    rep, _ = scaled
    for name in ("gyro_bias", "steer_offset"):
        assert rep["parameters"][name]["concluded"] is False, rep["parameters"][name]
    assert "--time-range" in rep["parameters"]["gyro_bias"]["note"]


def with_standstill(frame: pd.DataFrame, seconds: float = 5.0, rate: float = 20.0, noise: float = 0.005) -> pd.DataFrame:
    """``frame`` after ``seconds`` standing still (v = 0, the gyro reading its noise around no bias)."""
    n = int(seconds * rate)
    head = pd.DataFrame({c: np.repeat(frame[c].iloc[0], n) for c in frame.columns})
    head["t"] = frame["t"].iloc[0] - seconds + np.arange(n) / rate
    head["v"] = 0.0
    head["yaw_rate"] = np.random.default_rng(5).normal(0.0, noise, n)
    return pd.concat([head, frame], ignore_index=True)


@pytest.mark.slow
def test_offset_outside_the_class_flagged_and_standstill_bias_measured(tmp_path):
    s = Study.load(study(tmp_path, speeds=SPEEDS))
    frame, truth = make_log(2, "steering_offset", vehicle="small_ackermann", speeds=SPEEDS, duration=150.0,
                            values={"offset": 0.15})
    rep = identify_driving(with_standstill(frame.drop(columns=["x", "y"])), "offset.csv", s)
    ss = rep["steady_state_regression"]
    flag = ss["steer_offset"].get("implausible", "")
    assert abs(ss["steer_offset"]["value"]) > math.radians(5) and flag, ss
    assert "OUTSIDE the class's range" in summary(rep)
    # its cause is the steering's own offset (the truth's), which the dynamic fit sees beyond the range too
    assert "a fault to check" in flag and "straight-line model misses" not in flag, flag
    # the offset the model cannot reach is not read as a scale of the turns (the truth has none)
    assert rep["steering_gain_check"]["turn_scale"] in (None, 1.0), rep["steering_gain_check"]
    bias = rep["parameters"]["gyro_bias"]
    assert "standing still" in bias["how"] and bias["interval"][0] <= 0.0 <= bias["interval"][1], bias
    assert "concluded" not in rep["parameters"]["steer_offset"]


@pytest.mark.slow
def test_a_saturation_misfit_is_not_a_turn_scale():
    """The car's tyres bend from the first degree (harness.truth_tractor's tyre_saturation), its
    turns at their true scale: a turn scale fitted on that misfit does not predict the held-out
    segments better, so k = 1 is kept and K is not withheld for a scale."""
    rep = identify_car("tyre_saturation")[0]
    check = rep["steering_gain_check"]
    assert check["turn_scale"] == 1.0 and not check["kept"], check
    K = rep["understeer_gradient"]
    assert K["identifiable"] or "scale of the turns" not in K.get("note", ""), K


def identify_car(effect: str | None) -> tuple[dict, dict]:
    """identify on the passenger car's log of seed 1006 with ``effect``, its measured angle the input."""
    frame, truth = make_log(1006, effect, vehicle="car")
    car = Study.load(STUDIES / "passenger_car.toml")
    return identify_driving(frame.drop(columns=["x", "y", "delta_cmd"]), "car.csv", car), truth


def test_the_steady_regression_takes_a_measured_angle_at_its_declared_scale():
    """The healthy car's turns are at their declared scale: the regression holds its gain at 1, as the
    dynamic fit does, and its K (less its structural bias) holds the truth's m / L (l_r / C_f - l_f / C_r)."""
    rep, truth = identify_car(None)
    ss = rep["steady_state_regression"]
    assert ss["steer_gain"]["value"] == 1.0 and "gain_held" in ss, ss
    t = {"m": 1500.0, "l_f": 1.2, "l_r": 1.5}          # harness.truth_tractor's car
    K_true = t["m"] / 2.7 * (t["l_r"] / truth["C_f"] - t["l_f"] / truth["C_r"])
    steady = next(c for c in rep["comparisons"] if c["quantity"] == "understeer gradient K")["estimates"]
    lo, hi = steady["steady-state regression less its structural bias"]["interval"]
    assert lo <= K_true <= hi, (lo, K_true, hi)
    assert rep["steering_gain_check"]["turn_scale"] == 1.0


def test_at_one_speed_the_turn_scale_is_not_refitted():
    """At one speed a scale of the turns and K give the same yaw rate: K is not identifiable (one
    speed) and no refit with k free is spent on it."""
    rep = identify_driving(one_speed_log().rename(columns={"delta_cmd": "delta"}), "one speed", Study.load(F1TENTH))
    check, K = rep["steering_gain_check"], rep["understeer_gradient"]
    assert check["verdict"].startswith("not fitted") and "yaw_gain" not in check, check
    assert not K["identifiable"] and "one speed" in K["note"], K
