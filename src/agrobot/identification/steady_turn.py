"""A steady turn at a constant steering input (a circle test): the steady-state gain, and nothing of
the dynamics.

With the input held, the yaw rate asked for, v tan(u) / L, does not move (its std below
MIN_EXCITATION) while its mean is a turn: a delay, a lag, a cornering stiffness leave no trace
in such a log, but the steady-state (kinematic) gain does::

    k = mean(r - b) / mean(v tan(u) / L)        (ratio of means over the driving)

u the steering input, L the declared wheelbase (k is relative to it), b the gyro bias measured
standing still (a heading or a course has none; a gyro without a standstill: b = 0, said so). Its
standard error from the residuals e = r - b - k v tan(u) / L with their effective size
(estimation.effective_size): sd(k) = std(e) / (sqrt(n_eff) |mean(v tan(u) / L)|). k = 1 is a
vehicle turning as its input says; a negative k is a yaw turning against the input (the input's
or the gyro's sign convention is reversed).
"""
from __future__ import annotations

import math

import numpy as np

from agrobot.estimation import effective_size, interval
from agrobot.components.tractor_yaw_plant import steer_input

DYNAMICS = ("not identifiable from a steady turn: the input does not move, so a delay, a lag, the tyres' "
            "stiffness and the understeer gradient leave no trace; drive steps or a slalom for them")


def asked_yaw(log, L: float, segs) -> tuple[np.ndarray, np.ndarray]:
    """(v tan(u) / L [rad/s], the measured r) on the segments' scored samples (the driving)."""
    idx = segs.idx[segs.scored]
    return (log.v * steer_input(log.u, "tan") / L)[idx], log.r[idx]


def is_steady_turn(log, L: float, segs, min_excitation: float) -> bool:
    """The input asks for a turn (|mean| of v tan(u) / L at least ``min_excitation``) that hardly
    moves (its std below ``min_excitation``)."""
    kin = asked_yaw(log, L, segs)[0]
    return len(kin) > 0 and float(np.std(kin)) < min_excitation <= abs(float(np.mean(kin)))


def steady_turn_parts(log, L: float, segs, bias: dict | None, gyro: bool) -> dict:
    """The report's parts for a steady turn: the steady-state gain with its 95 % interval, the
    dynamics not identifiable (DYNAMICS), the bias used."""
    kin, r = asked_yaw(log, L, segs)
    b = bias["value"] if bias else 0.0
    k = float(np.mean(r - b) / np.mean(kin))
    e = r - b - k * kin
    per_segment = np.split(e, np.cumsum(segs.scored.sum(axis=1))[:-1])   # each segment's residuals, in order
    n_eff = effective_size(per_segment, updates=log.updates_in(segs))
    sd = float(np.std(e) / (math.sqrt(max(n_eff, 1.0)) * abs(np.mean(kin))))
    lo, hi = interval(k, sd)
    how = ("gyro bias measured standing still" if bias else "gyro bias taken as 0: no standstill of 2 s to measure it, "
           "and one steady input cannot tell a bias from the gain" if gyro else "no bias (a heading or a course)")
    gain = {"value": k, "std": sd, "interval": [lo, hi], "unit": "1", "identifiable": bool(math.isfinite(sd)),
            "meaning": f"r / (v tan(u) / L) in steady turns at a constant input (relative to the declared wheelbase "
                       f"{L:.3g} m); {how}", "n": int(len(e)), "n_eff": float(n_eff)}
    if k < 0:
        gain["note"] = ("negative: the yaw turns against the steering input; the input's mapping (or the gyro) "
                        "counts the other way round")
    nan = float("nan")
    none = {"value": nan, "std": nan, "interval": [nan, nan], "unit": "", "identifiable": False, "note": DYNAMICS}
    says = (f"steady turn: the input asks for {np.mean(kin):.3g} rad/s of yaw rate and moves by {np.std(kin):.2g} "
            f"rad/s (std); the steady-state gain r / (v tan(u) / L) is judged, the dynamics are {DYNAMICS}")
    return {"steady_turn_gain": gain, "says": says,
            "parameters": {"steer_gain": gain, "delay": {**none, "unit": "s"}, "lag": {**none, "unit": "s"}},
            "understeer_gradient": {**none, "unit": "rad/(m/s2)", "deg_per_g": nan},
            "characteristic_speed": {**none, "unit": "m/s", "kind": "characteristic or critical speed"},
            "cornering_stiffness": {"front": {**none, "unit": "N/rad"}, "rear": {**none, "unit": "N/rad"}},
            "tyre_saturation": {"found": False, "why_not": [DYNAMICS], "parameters": {}, "delta_bic": nan,
                                "held_out_gain": nan}}


def steady_turn_summary(report: dict) -> list[str]:
    """The steady turn's lines of the summary."""
    g = report["steady_turn_gain"]
    return [report["regime"]["says"],
            f"steady-state gain r / (v tan(u) / L): {g['value']:.4g} [{g['interval'][0]:.4g}, {g['interval'][1]:.4g}]"
            + (f"; {g['note']}" if "note" in g else ""),
            f"delay, lag, understeer gradient, cornering stiffness: {DYNAMICS}"]
