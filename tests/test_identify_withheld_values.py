"""A value identify does not conclude is nowhere printed as concluded.

Truths: harness.truth_tractor's small Ackermann machine (wheelbase 1.27 m, linear tyres) driven at
0.6-1.9 m/s, its wheel-angle sensor reading 1.24 x the wheels' angle: its turns are 1 / 1.24 =
0.806 of what the logged angle asks, 0.6 % inside the turn scale's bound 0.8, and a gyro noisier
than the harness's (0.015 rad/s more) leaves the fitted scale's 95 % interval across that bound;
no standstill in its log, so its gyro bias is fitted and not concluded. The passenger car on the
banked oval of tests.test_identify_banked_turns: its K withheld for the bank under its turns.
"""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.identification.ordinary_driving import TURN_GAIN, identify_driving, summary
from agrobot.orchestrator.study import Study
from harness.truth_tractor import make_log
from harness.vehicle_classes import study
from tests.test_identify_banked_turns import banked_oval_log
from tests.vehicle_logs import ROOT_STUDIES as STUDIES

SPEEDS = (0.6, 1.2, 1.9)
SENSOR_GAIN = 1.24          # the turns 1 / 1.24 = 0.806 of the logged angle's


@pytest.fixture(scope="module")
def near_bound(tmp_path_factory):
    s = Study.load(study(tmp_path_factory.mktemp("small"), speeds=SPEEDS))
    frame, _ = make_log(2, "steering_sensor_gain", vehicle="small_ackermann", speeds=SPEEDS, duration=180.0,
                        values={"sensor_gain": SENSOR_GAIN})
    frame["yaw_rate"] += np.random.default_rng(2).normal(0.0, 0.015, len(frame))
    return identify_driving(frame, "near_bound.csv", s)


def test_a_turn_scale_whose_interval_reaches_its_bound_is_not_concluded(near_bound):
    """The truth's scale lies within the fit's interval of the bound: whether k is inside the bounds
    is not decided, so neither k nor K (which moves with it) is concluded."""
    check, K = near_bound["steering_gain_check"], near_bound["understeer_gradient"]
    k = check["yaw_gain"]
    assert TURN_GAIN.lower == 0.8 and k["interval"][0] <= TURN_GAIN.lower < 1 / SENSOR_GAIN <= k["interval"][1], k
    assert check["turn_scale"] is None and not check["kept"] and not k["identifiable"], check
    assert "at its bound 0.8; cannot decide" in check["verdict"], check["verdict"]
    assert not K["identifiable"] and "turn scale is not concluded" in K["note"], K
    text = summary(near_bound)
    assert "turn scale k (yaw rate per v tan(w) / L): not concluded" in text, text


def _pair_lines(rep: dict) -> dict[str, str]:
    text = summary(rep).splitlines()
    return {c["quantity"]: next(x for x in text if x.startswith(c["quantity"] + ": ") and "dynamic fit" in x)
            for c in rep["comparisons"]}


def test_a_withheld_k_is_not_compared_as_if_concluded():
    """K withheld for the bank: its comparison gives the dynamic fit's K as fitted, not concluded, and
    judges no agreement; no gain curve is drawn from it; the delay, decided a clock offset (not a
    delay), is compared alike."""
    rep = identify_driving(banked_oval_log(True), "banked.csv", Study.load(STUDIES / "passenger_car.toml"))
    K = rep["understeer_gradient"]
    assert not K["identifiable"] and "bank of" in K["note"], K
    lines = _pair_lines(rep)
    k_line = lines["understeer gradient K"]
    assert f"dynamic fit not concluded (fitted {K['value']:.4g}" in k_line and "DISAGREE" not in k_line, k_line
    pair = next(c for c in rep["comparisons"] if c["quantity"] == "understeer gradient K")
    assert pair["concluded"] is False and "bank of" in pair["why_not"], pair
    assert rep["steady_state_gain"]["rows"] == [], rep["steady_state_gain"]
    if not rep["delay"]["identifiable"]:
        assert "not concluded (fitted" in lines["command-to-yaw delay"], lines
        assert any(x.startswith("delay: not concluded (fitted") for x in summary(rep).splitlines())


def test_a_bias_fitted_without_a_standstill_is_not_compared_as_if_concluded(near_bound):
    bias = near_bound["parameters"]["gyro_bias"]
    assert bias["concluded"] is False, bias
    line = _pair_lines(near_bound)["gyro bias"]
    assert "dynamic fit not concluded (fitted" in line and "DISAGREE" not in line, line
    assert any(x.strip().startswith("gyro_bias: not concluded (fitted") for x in summary(near_bound).splitlines())
