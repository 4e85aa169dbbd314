"""A passenger car turning through large road-wheel angles at parking speeds, as its OBD logger
writes it, with a known truth.

The truth: the single-track model with its exact geometry (not the project's small-angle one): the
road wheel at angle w turns the front tyre's force, F_f cos w across the car and l_f F_f cos w about
the centre of gravity, and the slip angles are alpha_f = atan((v_y + l_f r) / v) - w (relaxed over
``sigma_f``: sigma_f d alpha_f / dt = v (that - alpha_f)) and alpha_r = atan((v_y - l_r r) / v),
linear tyres F = -C alpha; with no slip it turns on r = v tan w / L. The road wheel follows the
steering-wheel reading through a first-order ``lag`` (an electric power steering) after a pure
``delay``; the car's numbers are studies/passenger_car.toml's. Driving: 1.5-6.5 m/s, turns held at a
wheel angle of up to 0.5 rad where the speed allows (|a_y| <= 2.5 m/s2), with small faster
steering on top. Integrated with Heun's method at 500 Hz.

The log (50 Hz rows, as the THI OBD logger writes a car's CAN): ``delta`` [rad] the steering-wheel
reading / the steering ratio, read in steps of 0.5 deg at the steering wheel and polled at uneven
times (mostly every other row: a held copy in between); ``v`` [m/s] the wheel speed in steps of
0.05 km/h, polled alike; ``yaw_rate`` [rad/s] read in steps of 1.28 deg/s.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

CAR = dict(m=1500.0, I=2500.0, l_f=1.2, l_r=1.5, C_f=80000.0, C_r=100000.0, sigma_f=0.5)
RATIO = 15.0
ROW = 0.02                   # s: the logger's rows
H = 0.002                    # s: integration step
YAW_STEP = math.radians(1.28)
SW_STEP = math.radians(0.5) / RATIO
SPEED_STEP = 0.05 / 3.6


def steering(t: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The steering-wheel reading / the ratio [rad]: turns of period 12 s, each held at its lock
    atan(min(tan 0.5, 2.5 L / v^2)) for about half of it, and 0.03 rad at 0.55 Hz and 0.015 rad at
    1.3 Hz."""
    L = CAR["l_f"] + CAR["l_r"]
    reach = np.arctan(np.minimum(math.tan(0.5), 2.5 * L / v ** 2))
    return (reach * np.clip(1.6 * np.sin(2 * math.pi * t / 12.0), -1.0, 1.0) + 0.03 * np.sin(2 * math.pi * 0.55 * t)
            + 0.015 * np.sin(2 * math.pi * 1.3 * t + 1.0))


def _rates(s, w: float, v: float) -> np.ndarray:
    vy, r, af = s
    p = CAR
    Ff, Fr = -p["C_f"] * af, -p["C_r"] * math.atan((vy - p["l_r"] * r) / v)
    return np.array([(Ff * math.cos(w) + Fr) / p["m"] - v * r, (p["l_f"] * Ff * math.cos(w) - p["l_r"] * Fr) / p["I"],
                     v * (math.atan((vy + p["l_f"] * r) / v) - w - af) / p["sigma_f"]])


def make_log(seed: int = 0, duration: float = 60.0, delay: float = 0.0, lag: float = 0.04) -> tuple[pd.DataFrame, dict]:
    """(the log, the truth): the module's car and logger; ``delay`` and ``lag`` [s] of the road
    wheel behind the steering-wheel reading."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration, H)
    v = 4.0 + 2.5 * np.sin(2 * math.pi * t / 30.0)
    u = steering(t, v)
    u_late = np.interp(t - delay, t, u)
    w, s = np.empty_like(t), np.zeros(3)
    r = np.empty_like(t)
    wk = u_late[0]
    for i in range(len(t)):
        w[i], r[i] = wk, s[1]
        k1 = _rates(s, wk, v[i])
        k2 = _rates(s + H * k1, wk, v[min(i + 1, len(t) - 1)])
        s = s + 0.5 * H * (k1 + k2)
        wk += (u_late[i] - wk) * (1.0 - math.exp(-H / lag)) if lag > 0 else u_late[i] - wk
    rows = np.arange(0, len(t), int(round(ROW / H)))
    polled = np.maximum.accumulate(np.where(rng.random(len(rows)) < 0.5, np.arange(len(rows)), 0))
    frame = pd.DataFrame({
        "t": t[rows],
        "delta": SW_STEP * np.round(u[rows][polled] / SW_STEP),
        "v": SPEED_STEP * np.round(v[rows][polled] / SPEED_STEP),
        "yaw_rate": YAW_STEP * np.round(r[rows] / YAW_STEP),
    })
    return frame, {"delay": delay, "lag": lag, **CAR,
                   "c_f": CAR["C_f"] / (CAR["m"] * 9.81 * CAR["l_r"] / (CAR["l_f"] + CAR["l_r"])),
                   "c_r": CAR["C_r"] / (CAR["m"] * 9.81 * CAR["l_f"] / (CAR["l_f"] + CAR["l_r"]))}
