"""A 'measured' log of the small Ackermann machine (harness.truth_tractor.VEHICLES["small_ackermann"]:
a converted riding mower, wheelbase 1.27 m) at 0.3-1.5 m/s, written from its own kinematic equations,
not the project's code path.

The machine: a steering motor closing a first-order loop (time constant 0.15 s) on a
potentiometer's reading u, which tracks the command delta_cmd; the wheels turn the steering map
of the reading (harness.steering_maps.wheel_angle), w = g (1 + a sign u) u + offset (a gain error,
a left/right asymmetry, a zero moved); the yaw from the kinematic single track with a small understeer,
r = v tan(w) / (L + K v^2), integrated at 200 Hz (Heun). Sensors, in 20 Hz rows: the reading
``delta`` (0.1 deg noise), the speed ``v`` (2 cm/s noise), a dual-antenna ``heading`` updated at
5 Hz and held between its updates (0.3 deg noise), the positions ``x``, ``y`` at 10 Hz, held
(2 cm noise); no gyro. Driving: a path follower's steering, steps and ramps whose size keeps the
lateral acceleration mostly below 0.4 m/s2 at each speed (larger at walking pace).

The study beside a log: harness.vehicle_classes.study (the machine's baseline study).

Imported where used: harness.vehicle_classes (only for the study written beside a log; it loads
the diagnosis).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from harness.steering_maps import wheel_angle
from harness.truth_tractor import DEG, SMALL_WHEELBASE as WHEELBASE

TRUTH = dict(gain=0.85, asymmetry=0.15, offset=0.035, understeer=0.01, servo=0.15)


def _plan(rng: np.random.Generator, duration: float, rate: float, speeds: tuple[float, float] = (0.3, 1.5)):
    """(t, command, speed) at ``rate``: speed held 8-20 s within ``speeds`` [m/s]; steering changed every
    1.5-4 s to a value whose steady lateral acceleration stays below about 0.4 m/s2."""
    n = int(round(duration * rate))
    t = np.arange(n) / rate
    speed, cmd = np.empty(n), np.empty(n)
    k, v = 0, 0.8
    while k < n:
        m = min(n, k + int(rng.uniform(8.0, 20.0) * rate))
        v_new = rng.uniform(*speeds)
        speed[k:m] = v + (v_new - v) * np.clip(np.arange(m - k) / (1.5 * rate), 0, 1)
        v = v_new
        k = m
    k, c = 0, 0.0
    while k < n:
        m = min(n, k + int(rng.uniform(1.5, 4.0) * rate))
        top = min(0.6, math.atan(0.35 * WHEELBASE / max(float(speed[k:m].max()), 0.3) ** 2))
        c_new = rng.uniform(-1.0, 1.0) * top
        cmd[k:m] = c + (c_new - c) * np.clip(np.arange(m - k) / (0.5 * rate), 0, 1)
        c = c_new
        k = m
    return t, cmd, speed


def make_small_log(seed: int, duration: float = 240.0, truth: dict | None = None, heading_rate: float = 5.0,
                   speeds: tuple[float, float] = (0.3, 1.5), rate: float = 20.0,
                   positions: tuple[float, float] = (10.0, 0.02)) -> tuple[pd.DataFrame, dict]:
    """The log and its truth (``truth`` replaces entries of TRUTH); ``speeds``: the range the speed
    is held in [m/s]; ``rate``: the rows' [Hz] (integrated at ``rate`` x the divisor nearest 200 Hz);
    ``positions``: the positions' update rate [Hz] (a divisor of ``rate``) and white noise [m]."""
    tr = {**TRUTH, **(truth or {})}
    rng = np.random.default_rng(seed)
    sub = max(1, int(round(200.0 / rate)))
    t, cmd, speed = _plan(rng, duration, rate, speeds)
    h = 1.0 / (rate * sub)
    n = len(t)
    u, psi, x, y = 0.0, rng.uniform(-math.pi, math.pi), 0.0, 0.0
    rec = np.empty((n, 5))
    for i in range(n):
        rec[i] = (u, psi, x, y, speed[i])
        v = speed[i]
        for _ in range(sub):
            def deriv(s):
                uu, pp = s[0], s[1]
                w = float(wheel_angle(uu, tr["gain"], tr["asymmetry"], offset=tr["offset"]))
                r = v * math.tan(w) / (WHEELBASE + tr["understeer"] * v * v)
                return ((cmd[i] - uu) / tr["servo"], r, v * math.cos(pp), v * math.sin(pp))
            s0 = (u, psi, x, y)
            k1 = deriv(s0)
            s1 = tuple(a + h * b for a, b in zip(s0, k1))
            k2 = deriv(s1)
            u, psi, x, y = (a + 0.5 * h * (b + c) for a, b, c in zip(s0, k1, k2))
    noise = rng.standard_normal((6, n))
    hold_h = np.floor(t * heading_rate + 1e-9) / heading_rate          # the last 5 Hz update at or before t
    k_h = np.round(hold_h * rate).astype(int)
    heading = np.angle(np.exp(1j * (rec[k_h, 1] + 0.3 * DEG * noise[2][k_h])))
    position_hz, sigma_p = positions
    k_p = np.round(np.floor(t * position_hz + 1e-9) / position_hz * rate).astype(int)
    frame = pd.DataFrame({"t": t, "delta_cmd": cmd, "delta": rec[:, 0] + 0.1 * DEG * noise[0],
                          "v": rec[:, 4] + 0.02 * noise[1], "heading": heading,
                          "x": rec[k_p, 2] + sigma_p * noise[3][k_p], "y": rec[k_p, 3] + sigma_p * noise[4][k_p]})
    return frame, {**tr, "wheelbase": WHEELBASE, "gain_left": tr["gain"] * (1 + tr["asymmetry"]),
                   "gain_right": tr["gain"] * (1 - tr["asymmetry"]), "heading_rate": heading_rate}


def make_circle_log(seed: int, command: float = 0.25, speed: float = 0.8, duration: float = 90.0,
                    bias: float = 0.004) -> tuple[pd.DataFrame, dict]:
    """A circle test of the machine: 5 s standing, then the speed ramped to ``speed`` in 2 s with
    the steering command held at ``command`` throughout; a gyro ``yaw_rate`` (bias ``bias`` rad/s,
    0.5 deg/s noise) and ``delta_cmd``, ``v`` at 50 Hz. The truth's steady-state gain
    k = r / (v tan(command) / L) = tan(w(command)) L / (tan(command) (L + K v^2)) from the steering map."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration * 50)) / 50.0
    v = speed * np.clip((t - 5.0) / 2.0, 0.0, 1.0)
    w = float(wheel_angle(command, TRUTH["gain"], TRUTH["asymmetry"], offset=TRUTH["offset"]))
    r = v * math.tan(w) / (WHEELBASE + TRUTH["understeer"] * v * v)
    frame = pd.DataFrame({"t": t, "delta_cmd": np.full_like(t, command), "v": v + 0.01 * rng.standard_normal(len(t)),
                          "yaw_rate": r + bias + 0.5 * DEG * rng.standard_normal(len(t))})
    k = math.tan(w) * WHEELBASE / (math.tan(command) * (WHEELBASE + TRUTH["understeer"] * speed ** 2))
    return frame, {"steady_gain": k, "wheelbase": WHEELBASE, "bias": bias}


def write_study(folder) -> Path:
    """The machine's baseline study in ``folder`` (harness.vehicle_classes.study)."""
    from harness.vehicle_classes import study

    return study(folder)
