"""A 'measured' field log from a truth model that is not the project's code path.

Written from the paper's equations of motion (section III, RLF: relaxation length at the front
axle) in scalar form, integrated with Heun's method at 200 Hz (the project's plant uses exact ZOH
steps with matrix exponentials), with its own steering loop (first order, rate limit, a 15 ms
spool lag the baseline does not model), its own parameters drawn around the paper's values, and
its own sensors sampled at 20 Hz. Any combination of catalogue effects can be injected, and
faults the diagnosis catalogue does not list (UNLISTED); the diagnosis under test is not told which. Tests and benchmarks both use it (diagnosis.hidden_effects runs the diagnosis
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


# faults outside the diagnosis catalogue: the diagnosis must call them "unexplained"
UNLISTED = ("steering_sensor_gain", "gyro_scale_factor", "wheel_slip", "tyre_saturation")


def draw_unlisted(effect: str, rng: np.random.Generator) -> dict[str, float]:
    """Magnitudes of the unlisted faults:

    - steering_sensor_gain: the wheel-angle sensor reads g > 1 x the angle; the steering loop closes
      on the reading, so the wheels turn 1/g as far as the log says (g < 1 would also make the
      logged steering slower than its rate limit: a catalogued steering_rate_limit, rightly found);
    - gyro_scale_factor: the gyro reads s x the yaw rate;
    - wheel_slip: the logged speed (wheel speed) is (1 + slip) x the ground speed;
    - tyre_saturation: the tyre forces saturate, F = C alpha / (1 + |alpha| / alpha_s).
    """
    sign = 1.0 if rng.random() < 0.5 else -1.0
    u = rng.uniform
    return {"steering_sensor_gain": {"sensor_gain": 1.0 + u(0.12, 0.2)},
            "gyro_scale_factor": {"gyro_scale": 1.0 + sign * u(0.08, 0.15)},
            "wheel_slip": {"slip": u(0.06, 0.12)},
            "tyre_saturation": {"alpha_s": u(2.0, 4.0) * DEG}}[effect]


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


def driving_plan(rng: np.random.Generator, duration: float, rate: float = 20.0, speeds_cycle=(1.0, 2.0, 3.0)):
    """Steering command (held at ``rate``) and a smooth speed profile: 20 s segments cycling
    through a multisine, steps, a headland-like turn and small corrections, at 1, 2 and 3 m/s
    (``speeds_cycle``: other segment speeds, e.g. one speed for a log that cannot separate
    speed-dependent effects)."""
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
        speeds.append(speeds_cycle[i % len(speeds_cycle)])
    cmd = np.clip(cmd, -30 * DEG, 30 * DEG)

    def speed(time: float) -> float:
        i = min(int(time // 20.0), len(speeds) - 1)
        v1 = speeds[i]
        v0 = speeds[i - 1] if i > 0 else 0.0
        s = min(max((time - 20.0 * i) / 3.0, 0.0), 1.0)
        return v0 + (v1 - v0) * 0.5 * (1 - math.cos(math.pi * s))

    return t, cmd, speed


def effect_list(effect: str | tuple | list | None) -> list[str]:
    """None, one effect id, a '+'-joined string or a sequence of ids -> the list of ids."""
    if effect is None or effect == "none":
        return []
    if isinstance(effect, str):
        return [e for e in effect.split("+") if e]
    return list(effect)


def make_log(seed: int, effect: str | tuple | list | None = None, duration: float = 240.0,
             scale: dict[str, float] | None = None, speeds: tuple[float, ...] = (1.0, 2.0, 3.0)) -> tuple[pd.DataFrame, dict]:
    """The log and the truth; ``effect`` is None, one id, or several ('a+b' or a sequence) from
    EFFECTS and UNLISTED; ``scale`` multiplies entries of TABLE (m, I, l_f, l_r, C_f, C_r,
    sigma_f) to stress the diagnosis with a truth further from the baseline."""
    rng = np.random.default_rng(seed)
    ids = effect_list(effect)
    unknown = [i for i in ids if i not in EFFECTS and i not in UNLISTED]
    if unknown:
        raise ValueError(f"unknown truth effects {unknown}; known: {EFFECTS + UNLISTED}")
    e: dict[str, float] = {}
    for i in [i for i in ids if i in EFFECTS] or [None]:
        e.update(draw_effect(i, rng))
    side = np.random.default_rng([seed, 1])           # unlisted faults: the catalogue draws stay as they were
    for i in ids:
        if i in UNLISTED:
            e.update(draw_unlisted(i, side))
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
    t_log, cmd, speed_of = driving_plan(rng, duration, speeds_cycle=speeds)
    m, I, lf, lr, sf = p["m"], p["I"], p["l_f"], p["l_r"], p["sigma_f"]
    g_slope = G * math.sin(slope)
    sensor_gain = e.get("sensor_gain", 1.0)
    alpha_s = e.get("alpha_s", math.inf)

    def deriv(time, s):
        delta, spool, vy, r, af, psi, x, y = s
        k = int(math.floor((time - delay) * 20.0 + 1e-9))
        c = cmd[min(max(k, 0), len(cmd) - 1)]
        err = c - sensor_gain * delta           # the loop closes on the sensor's reading
        err = err - dead if err > dead else (err + dead if err < -dead else 0.0)
        want = max(-rate, min(rate, err / tau))
        v = speed_of(time)
        scale = max(0.2, 1.0 + k_corner * (v - 2.0))
        cf, cr = p["C_f"] * scale, p["C_r"] * scale
        vv = max(v, 0.8)          # the slip equations divide by v; below 0.8 m/s scaled (v / vv)
        ar = (vy - lr * r) / vv
        a_lat = g_slope * math.sin(downhill - psi)
        sat_f, sat_r = 1.0 + abs(af) / alpha_s, 1.0 + abs(ar) / alpha_s
        dvy = -vv * r + (-cf * af / sat_f - cr * ar / sat_r) / m + a_lat
        dr = (-lf * cf * af / sat_f + lr * cr * ar / sat_r) / I
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
        "delta": q * np.round((sensor_gain * delta[idx] + 0.05 * DEG * noise[0]) / q),
        "v": (1.0 + e.get("slip", 0.0)) * np.array([speed_of(tt) for tt in t_log]) + 0.02 * noise[1],
        "yaw_rate": e.get("gyro_scale", 1.0) * r[idx] + e.get("bias", 0.0) + 0.005 * noise[2],
        "x": gx + 0.02 * noise[3],
        "y": gy + 0.02 * noise[4],
    })
    truth = {"effect": "+".join(ids) or "none", "effects": ids, **e, "tau": tau, "C_f": p["C_f"], "C_r": p["C_r"]}
    return frame, truth
