"""A bank under the turns is neither a scale of the turns nor understeer.

Truth: the passenger car of studies/passenger_car.toml (m 1500 kg, I 2500 kg m2, l_f 1.2 m,
l_r 1.5 m, C_f 80 kN/rad, C_r 100 kN/rad: K = m / L (l_r / C_f - l_f / C_r) = 0.00375 rad/(m/s2),
front relaxation length 0.5 m) lapping an oval whose turns are banked BANK_TURNS into them and its
straights BANK_STRAIGHTS, at 8, 12 and 16 m/s in turn: gravity's lateral share g sin(bank) acts
on the body beside the tyres' forces (m (dv_y/dt + v r) = F_f + F_r + m g sin(bank)), simulated
here by Heun's method at 200 Hz. The driver steers delta = L kappa + K (v^2 kappa - g sin(bank))
(the steer that holds the turn of curvature kappa on the bank) plus a small multisine. The log
carries the body's roll (right side down positive: -bank in these left turns). The same car on a
level oval, its body rolling out of the turns (4 deg/g), is the control: a lean against the turns
is not a bank.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from agrobot.identification.ordinary_driving import identify_driving, summary
from agrobot.orchestrator.study import Study
from tests.vehicle_logs import ROOT_STUDIES as STUDIES

G = 9.81
CAR = dict(m=1500.0, I=2500.0, l_f=1.2, l_r=1.5, C_f=80000.0, C_r=100000.0, sigma_f=0.5)
L = CAR["l_f"] + CAR["l_r"]
K_TRUE = CAR["m"] / L * (CAR["l_r"] / CAR["C_f"] - CAR["l_f"] / CAR["C_r"])
BANK_TURNS, BANK_STRAIGHTS = math.radians(9.0), math.radians(2.0)
SPEEDS = (8.0, 12.0, 16.0)
RADIUS = 60.0             # m: 1.1-4.3 m/s2 in the turns
RATE = 20.0               # Hz


def oval_plan(duration: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t, speed, curvature) at 200 Hz: laps of a 12 s straight and a 14 s turn (2 s ramps), one
    speed per lap (SPEEDS in turn, 1 s of change between laps)."""
    t = np.arange(int(duration * 200)) / 200.0
    lap = 26.0
    phase = t % lap
    kappa = np.clip(np.minimum(phase - 12.0, 26.0 - phase) / 2.0, 0.0, 1.0) / RADIUS
    which = (t // lap).astype(int) % len(SPEEDS)
    v = np.array(SPEEDS)[which]
    v = np.convolve(np.pad(v, (100, 99), mode="edge"), np.ones(200) / 200, mode="valid")
    return t, v, kappa


def banked_oval_log(banked: bool, duration: float = 156.0, seed: int = 3, imu: bool = False) -> pd.DataFrame:
    """The log (t, delta, v, yaw_rate, roll) of the truth car lapping the oval: banked (the turns
    BANK_TURNS, the straights BANK_STRAIGHTS into the turns) or level, its body rolling out of the
    turns by 4 deg per g either way; ``imu``: with a_y, the tyres' lateral specific force
    (F_f + F_r) / m = dv_y/dt + v r - g sin(bank)."""
    rng = np.random.default_rng(seed)
    t, v, kappa = oval_plan(duration)
    m, I, lf, lr, cf, cr, sf = (CAR[k] for k in ("m", "I", "l_f", "l_r", "C_f", "C_r", "sigma_f"))
    bank = (BANK_STRAIGHTS + (BANK_TURNS - BANK_STRAIGHTS) * kappa * RADIUS) if banked else np.zeros_like(t)
    g_lat = G * np.sin(bank)                                    # gravity's share towards the turn's inside (left)
    freqs = np.array([0.13, 0.31, 0.57, 0.91])
    dither = sum(0.002 * np.sin(2 * math.pi * f * t + p) for f, p in zip(freqs, rng.uniform(0, 2 * math.pi, 4)))
    delta = L * kappa + K_TRUE * (v ** 2 * kappa - g_lat) + dither

    def deriv(i, s):
        vy, r, af = s
        ar = (vy - lr * r) / v[i]
        return np.array([-v[i] * r + (-cf * af - cr * ar) / m + g_lat[i],
                         (-lf * cf * af + lr * cr * ar) / I,
                         (vy + lf * r - v[i] * (delta[i] + af)) / sf])

    h, s = 1 / 200.0, np.zeros(3)
    r_true, force = np.empty(len(t)), np.empty(len(t))
    for i in range(len(t)):
        r_true[i] = s[1]
        k1 = deriv(i, s)
        force[i] = k1[0] + v[i] * s[1] - g_lat[i]
        k2 = deriv(min(i + 1, len(t) - 1), s + h * k1)
        s = s + 0.5 * h * (k1 + k2)
    keep = slice(0, None, int(200 / RATE))
    n = len(t[keep])
    body_roll = math.radians(4.0) / G * (v * r_true)[keep]     # out of the turn: right side down in a left turn
    frame = pd.DataFrame({"t": t[keep], "delta": delta[keep] + rng.normal(0, 2e-4, n), "v": v[keep],
                          "yaw_rate": r_true[keep] + rng.normal(0, 0.002, n), "roll": body_roll - bank[keep]})
    return frame.assign(a_y=force[keep] + rng.normal(0, 0.05, n)) if imu else frame


@pytest.fixture(scope="module")
def car():
    return Study.load(STUDIES / "passenger_car.toml")


def test_the_bank_under_the_turns_withholds_the_scale_and_k(car):
    rep = identify_driving(banked_oval_log(True), "banked.csv", car)
    check, K = rep["steering_gain_check"], rep["understeer_gradient"]
    assert not check["kept"] and check["turn_scale"] is None and "yaw_gain" not in check, check
    assert not K["identifiable"] and "bank of" in K["note"], K
    bank = float(K["note"].split("bank of ")[1].split(" deg")[0])
    # the planted 9 deg, less the body's roll out of the turns and the ramps in the top third of |v r|
    assert math.degrees(BANK_TURNS) - 3.0 < bank <= math.degrees(BANK_TURNS), K["note"]
    text = summary(rep)
    assert "bank of" in text and "left out of the log" in text, text


def test_a_body_rolling_out_of_level_turns_is_not_a_bank(car):
    """On the level oval the same car's K is concluded and holds the truth's, no bank told."""
    rep = identify_driving(banked_oval_log(False), "level.csv", car)
    K = rep["understeer_gradient"]
    assert "bank" not in K.get("note", ""), K
    assert K["identifiable"] and K["interval"][0] <= K_TRUE <= K["interval"][1], (K, K_TRUE)


def test_the_lean_from_an_imu_is_gravity_s_share():
    """A lateral specific force a_y = v r - g sin(bank) gives back g sin(bank); the roll column -g sin(roll)."""
    from agrobot.identification.ground_lean import ground_lean, turns_lean

    t = np.arange(200) / 20.0
    v, r = np.full(200, 20.0), 0.1 * np.sin(t)
    g_lat = 2.0 * np.sin(t) + 0.3
    imu, _ = ground_lean(pd.DataFrame({"t": t, "a_y": v * r - g_lat}), t, v, r)
    roll, _ = ground_lean(pd.DataFrame({"t": t, "roll": -np.arcsin(g_lat / G)}), t, v, r)
    assert np.allclose(imu, g_lat) and np.allclose(roll, g_lat)
    assert turns_lean(g_lat, v, r, 0.05, np.ones(200, bool)) is not None           # 1 m/s2 per m/s2 into the turns
    assert turns_lean(-0.07 * v * r, v, r, 0.05, np.ones(200, bool)) is None     # a body's roll, out of them
    flipped, why = ground_lean(pd.DataFrame({"t": t, "ay": g_lat - v * r}), t, v, r)
    assert flipped is None and "runs against v r" in why                   # an a_y read right side positive
    wild, why = ground_lean(pd.DataFrame({"t": t, "roll": np.full(200, 1.9)}), t, v, r)
    assert wild is None and "not taken for the ground's lean" in why       # 109 deg: no ground's lean


def test_an_imu_on_a_log_without_turns_has_no_sign_to_read():
    """Driven straight (v r = 0 throughout) a lateral force column has nothing to be read against: said so,
    not called turned round; a lateral column of another name (lat_acc) is read as well."""
    from agrobot.identification.ground_lean import ground_lean

    t = np.arange(200) / 20.0
    v, r = np.full(200, 10.0), np.zeros(200)
    lean, why = ground_lean(pd.DataFrame({"t": t, "a_y": 0.2 * np.sin(t)}), t, v, r)
    assert lean is None and "no turns to read its sign against" in why and "-COLUMN" not in why
    r = 0.1 * np.sin(t)
    lean, why = ground_lean(pd.DataFrame({"t": t, "lat_acc": v * r - 0.5}), t, v, r)
    assert np.allclose(lean, 0.5) and "lat_acc" in why


def test_an_imus_lateral_force_on_the_bank_is_checked_as_a_specific_force(car):
    """The model's lateral acceleration less the lean the roll column tells is what an IMU on the
    banked oval reads (dv_y/dt + v r - g sin(bank)): it fits the a_y column on the held-out segments."""
    rep = identify_driving(banked_oval_log(True, imu=True), "banked.csv", car)
    check = rep["physical_checks"]["a_y"]
    assert check["fit_percent"] > 80.0, check
