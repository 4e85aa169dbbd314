"""A 'measured' field log from a truth model that is not the project's code path.

Written from the paper's equations of motion (section III, RLF: relaxation length at the front
axle) in scalar form, integrated with Heun's method at 200 Hz (the project's plant uses exact ZOH
steps with matrix exponentials), with its own steering loop (first order, rate limit, a 15 ms
spool lag the baseline does not model), its own parameters drawn around the paper's values, and
its own sensors sampled at 20 Hz. One catalogue effect can be injected; the diagnosis under test
is not told which. Tests and benchmarks both use it (diagnosis.hidden_effects runs the diagnosis
on its logs).
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

DEG = math.pi / 180
G = 9.81
TABLE = dict(m=700.0, I=280.0, l_f=1.0, l_r=0.4, C_f=8000.0, C_r=90000.0, sigma_f=0.1942)
STEERING_TIME_CONSTANT = 0.0667     # the paper tractor's closed-loop steering (components.models.steering_equivalent)
STEERING_RATE = 60 * DEG
STEERING_DEADBAND = 0.5 / 150       # valve dead-band / kp of the paper tractor

EFFECTS = ("actuator_delay", "steering_deadband", "steering_rate_limit", "steering_offset", "yaw_rate_bias",
           "gps_latency", "speed_dependent_cornering", "side_slope", "antenna_lever_arm")


def draw_effect(effect: str | None, rng: np.random.Generator) -> dict[str, float]:
    """A magnitude a real tractor shows."""
    sign = 1.0 if rng.random() < 0.5 else -1.0
    u = rng.uniform
    return {
        None: {},
        "actuator_delay": {"delay": u(0.10, 0.25)},
        "steering_deadband": {"deadband": u(1.0, 3.0) * DEG},
        "steering_rate_limit": {"rate": u(10.0, 25.0) * DEG},
        "steering_offset": {"offset": sign * u(1.0, 3.0) * DEG},
        "yaw_rate_bias": {"bias": sign * u(0.01, 0.03)},
        "gps_latency": {"latency": u(0.10, 0.30)},
        "speed_dependent_cornering": {"k": sign * u(0.15, 0.30)},
        "side_slope": {"slope": u(3.0, 6.0) * DEG, "downhill": u(-math.pi, math.pi)},
        "antenna_lever_arm": {"forward": u(0.4, 1.0), "left": sign * u(0.1, 0.4)},
    }[effect]


def driving_plan(rng: np.random.Generator, duration: float, rate: float = 20.0):
    """Steering command (held at ``rate``) and a smooth speed profile: 20 s segments cycling
    through a multisine, steps, a headland-like turn and small corrections, at 1, 2 and 3 m/s."""
    n = int(round(duration * rate))
    t = np.arange(n) / rate
    cmd = np.zeros(n)
    seg = int(20 * rate)
    speeds = []
    for i, a in enumerate(range(0, n, seg)):
        b = min(n, a + seg)
        tt = t[a:b] - t[a]
        kind = i % 4
        if kind == 0:
            f = rng.uniform(0.05, 1.0, 6)
            x = np.sum(np.sin(2 * np.pi * f[:, None] * tt[None, :] + rng.uniform(0, 2 * np.pi, 6)[:, None]), axis=0)
            cmd[a:b] = 6 * DEG * x / np.sqrt(3.0)
        elif kind == 1 or kind == 3:
            span, amp = ((1.5, 3.0), 20 * DEG) if kind == 1 else ((1.0, 2.0), 3 * DEG)
            k = a
            while k < b:
                m = min(b, k + int(rng.uniform(*span) * rate))
                cmd[k:m] = rng.uniform(-amp, amp)
                k = m
        else:
            peak = rng.choice([-1, 1]) * rng.uniform(15, 25) * DEG
            cmd[a:b] = np.interp(tt, [0, 2, 8, 10, 14, 16, 20], [0, peak, peak, -0.5 * peak, -0.5 * peak, 0, 0])
        speeds.append((1.0, 2.0, 3.0)[i % 3])
    cmd = np.clip(cmd, -30 * DEG, 30 * DEG)

    def speed(time: float) -> float:
        i = min(int(time // 20.0), len(speeds) - 1)
        v1 = speeds[i]
        v0 = speeds[i - 1] if i > 0 else 0.0
        s = min(max((time - 20.0 * i) / 3.0, 0.0), 1.0)
        return v0 + (v1 - v0) * 0.5 * (1 - math.cos(math.pi * s))

    return t, cmd, speed


def make_log(seed: int, effect: str | None = None, duration: float = 240.0,
             scale: dict[str, float] | None = None) -> tuple[pd.DataFrame, dict]:
    """The log and the truth; ``scale`` multiplies entries of TABLE (m, I, l_f, l_r, C_f, C_r,
    sigma_f) to stress the diagnosis with a truth further from the baseline."""
    rng = np.random.default_rng(seed)
    e = draw_effect(effect, rng)
    p = dict(TABLE)
    for key, factor in (scale or {}).items():
        p[key] *= factor
    for k, lo, hi in (("C_f", 0.85, 1.15), ("C_r", 0.85, 1.15), ("sigma_f", 0.9, 1.1)):
        p[k] *= rng.uniform(lo, hi)
    tau = STEERING_TIME_CONSTANT * rng.uniform(0.8, 1.2)
    tau_spool = 0.015
    rate = e.get("rate", STEERING_RATE)
    dead = STEERING_DEADBAND + e.get("deadband", 0.0)
    delay, offset = e.get("delay", 0.0), e.get("offset", 0.0)
    k_corner = e.get("k", 0.0)
    slope, downhill = e.get("slope", 0.0), e.get("downhill", 0.0)
    t_log, cmd, speed_of = driving_plan(rng, duration)
    m, I, lf, lr, sf = p["m"], p["I"], p["l_f"], p["l_r"], p["sigma_f"]
    g_slope = G * math.sin(slope)

    def deriv(time, s):
        delta, spool, vy, r, af, psi, x, y = s
        k = int(math.floor((time - delay) * 20.0 + 1e-9))
        c = cmd[min(max(k, 0), len(cmd) - 1)]
        err = c - delta
        err = err - dead if err > dead else (err + dead if err < -dead else 0.0)
        want = max(-rate, min(rate, err / tau))
        v = speed_of(time)
        scale = max(0.2, 1.0 + k_corner * (v - 2.0))
        cf, cr = p["C_f"] * scale, p["C_r"] * scale
        vv = max(v, 0.8)          # the slip equations divide by v; below 0.8 m/s scaled (v / vv)
        ar = (vy - lr * r) / vv
        a_lat = g_slope * math.sin(downhill - psi)
        dvy = -vv * r + (-cf * af - cr * ar) / m + a_lat
        dr = (-lf * cf * af + lr * cr * ar) / I
        daf = (vy + lf * r - vv * (delta + offset + af)) / sf
        c_, s_ = math.cos(psi), math.sin(psi)
        return (spool, (want - spool) / tau_spool, dvy * (v / vv), dr * (v / vv), daf * (v / vv), r,
                v * c_ - vy * s_, v * s_ + vy * c_)

    sub = 10                                  # 200 Hz internal steps per 20 Hz sample
    h = 0.05 / sub
    n = len(t_log)
    state = (0.0,) * 5 + (rng.uniform(-math.pi, math.pi), 0.0, 0.0)
    rec = np.empty((n * sub, 8))
    times = np.arange(n * sub) * h
    for i in range(n * sub):
        rec[i] = state
        t0 = times[i]
        k1 = deriv(t0, state)
        s1 = tuple(a + h * b for a, b in zip(state, k1))
        k2 = deriv(t0 + h, s1)
        state = tuple(a + 0.5 * h * (b + c) for a, b, c in zip(state, k1, k2))
    delta, r, psi, x, y = rec[:, 0], rec[:, 3], rec[:, 5], rec[:, 6], rec[:, 7]
    fwd, left = e.get("forward", 0.0), e.get("left", 0.0)
    c, s = np.cos(psi), np.sin(psi)
    ax = x - lr * c + fwd * c - left * s
    ay = y - lr * s + fwd * s + left * c
    idx = np.arange(n) * sub
    lat = e.get("latency", 0.0)
    gx, gy = np.interp(t_log - lat, times, ax), np.interp(t_log - lat, times, ay)
    noise = rng.standard_normal((6, n))
    q = 0.1 * DEG
    frame = pd.DataFrame({
        "t": t_log,
        "delta_cmd": cmd,
        "delta": q * np.round((delta[idx] + 0.05 * DEG * noise[0]) / q),
        "v": np.array([speed_of(tt) for tt in t_log]) + 0.02 * noise[1],
        "yaw_rate": r[idx] + e.get("bias", 0.0) + 0.005 * noise[2],
        "x": gx + 0.02 * noise[3],
        "y": gy + 0.02 * noise[4],
    })
    truth = {"effect": effect or "none", **e, "tau": tau, "C_f": p["C_f"], "C_r": p["C_r"]}
    return frame, truth
