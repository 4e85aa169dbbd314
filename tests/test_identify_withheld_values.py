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

from agrobot.identification.driving import DrivingLog
from agrobot.identification.ordinary_driving import TURN_GAIN, identify_driving, one_speed, summary
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


def lap_log(turn_speeds: tuple[float, ...], straight_speed: float, radius: float, wheelbase: float,
            weave: float = 0.0, gyro_noise: float = 0.002, seed: int = 4) -> DrivingLog:
    """20 Hz laps of a 20 s straight (its speed ``straight_speed``, the steering weaving ``weave``
    rad at 0.3 Hz) and a 15 s turn of ``radius`` m, each lap's turn at the next of ``turn_speeds``:
    the wheel angle L / R (+ the weave), the gyro v kappa with its white noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 420.0, 0.05)
    lap, phase = (t // 35.0).astype(int), t % 35.0
    in_turn = phase >= 20.0
    v = np.where(in_turn, np.array(turn_speeds)[lap % len(turn_speeds)], straight_speed)
    weaving = weave * np.sin(2 * np.pi * 0.3 * t) * ~in_turn
    kappa = np.where(in_turn, 1.0 / radius, weaving / wheelbase)
    u = wheelbase * kappa
    r = v * kappa + rng.normal(0.0, gyro_noise, len(t))
    return DrivingLog(t, u, v, r, np.zeros(len(t), int), 0.05, "delta", measured=np.ones(len(t), bool))


@pytest.mark.parametrize("turns,straights,radius,L,weave,alike", [
    ((20.0,), 20.0, 330.0, 2.97, 0.0, True),          # a racecar's oval at one speed: 0.009 rad of road wheel
    ((15.0, 25.0), 20.0, 330.0, 2.97, 0.0, False),   # ... its turns at 15 and 25 m/s
    ((1.0,), 2.5, 5.0, 2.5, 0.035, True),            # a tractor turning at the headlands at 1 m/s, its rows weaving
])
def test_one_speed_is_read_from_the_log_s_own_turns(turns, straights, radius, L, weave, alike):
    """Turns at one speed fix only the ratio of a steering gain to L + K v^2, whatever the machine's
    scale: a racecar's gentle oval turns count as turns, a tractor's weave along its rows does not."""
    why = one_speed(lap_log(turns, straights, radius, L, weave), 0.5)
    assert (why is not None) is alike, why
    if alike:
        lo, hi = (float(x) for x in why.split("(")[1].split(" m/s")[0].split("-"))
        assert lo <= turns[0] <= hi, why


def test_a_k_withheld_for_disagreeing_keeps_its_disagreement_said():
    """A K identify withholds because its two estimates disagree is judged in its pair (DISAGREE and
    what it suggests); a K withheld for another reason (one speed) is not compared."""
    from agrobot.identification.comparisons import mark_not_concluded, pair_line
    pair = {"quantity": "understeer gradient K", "unit": "rad/(m/s2)", "agree": False, "suggests": "a bank",
            "estimates": {"dynamic fit": {"value": 0.004, "interval": [0.0035, 0.0045]},
                          "steady-state regression": {"value": 0.001, "interval": [0.0008, 0.0012]}}}
    disagreeing = mark_not_concluded([dict(pair)], {"identifiable": False, "withheld": True, "note": "x"}, {})
    assert "DISAGREE: a bank" in pair_line(disagreeing[0])
    one_speed = mark_not_concluded([dict(pair)], {"identifiable": False, "note": "one speed"}, {})
    assert "not compared" in pair_line(one_speed[0]) and "DISAGREE" not in pair_line(one_speed[0])
