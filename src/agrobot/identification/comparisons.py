"""Two independent estimates of one quantity, side by side: the understeer gradient from the
dynamic fit and from steady states in their linear range (understeer_pair; when they disagree no
single value is concluded, withheld_understeer), the command-to-yaw delay from the fit and from a
cross-correlation, the gyro bias from the fit and from the GNSS course. Each pair is reported with
its intervals; intervals that do not overlap are flagged with what the disagreement suggests.
"""
from __future__ import annotations

import math

import numpy as np

from agrobot.estimation import Z95, compare

pair = compare           # the shared rule (agrobot.estimation.compare): intervals that overlap agree


def course_bias(t: np.ndarray, x: np.ndarray, y: np.ndarray, r: np.ndarray, v: np.ndarray,
                min_speed: float, chord: float = 1.0) -> tuple[float, float] | None:
    """(bias, std) of the gyro against the GNSS course: the course psi_c of 1 s chords of the
    track, b = mean(r - d psi_c / dt) where moving (the course turns with the body when the
    side-slip is steady); std from the spread over 20 s blocks. None without 60 s of moving track."""
    h = float(np.median(np.diff(t)))
    k = max(1, int(round(0.5 * chord / h)))
    if len(t) < 4 * k + 10:
        return None
    dx, dy = x[2 * k:] - x[:-2 * k], y[2 * k:] - y[:-2 * k]
    course = np.unwrap(np.arctan2(dy, dx))
    rate = np.gradient(course, h)
    ok = (np.hypot(dx, dy) > min_speed * 2 * k * h) & (v[k:-k] > min_speed)
    ok &= np.abs(rate) < 2.0
    if ok.sum() * h < 60.0:
        return None
    diff = (r[k:-k] - rate)[ok]
    block = max(2, int(round(20.0 / h)))
    means = [diff[i:i + block].mean() for i in range(0, len(diff) - block + 1, block)]
    sd = float(np.std(means) / math.sqrt(len(means))) if len(means) > 1 else math.nan
    return float(np.median(diff)), sd


def _text(value: float, std: float) -> str:
    return f"{value:.3g} [{value - Z95 * std:.3g}, {value + Z95 * std:.3g}]"


def understeer_pair(understeer: dict, ss, linear_range: dict, lateral_p99: float,
                    low: tuple[float, float] | None = None) -> dict:
    """The understeer gradient K of the dynamic fit beside the steady-state regression's (``ss``,
    steady_state.in_linear_range), with why they differ: saturation not modelled (the dynamic fit
    spans |a_y| up to ``lateral_p99`` beyond the steady turns' linear limit, and the same model
    fitted where the tyres are linear, ``low`` (K, std), agrees with the steady turns), different
    stretches (the |a_y| spans differ, or the steady turns' linear range was not read), else a
    different model structure."""
    d = ss.as_dict()
    k_ss, lim = d["understeer_gradient"], ss.max_lateral
    span = (f"the steady turns: {ss.used} windows at a held input with |a_y| <= {lim:.3g} m/s2 ({ss.limit_how}); the "
            f"dynamic fit: every segment, |a_y| up to {lateral_p99:.3g} m/s2 (99th percentile)")
    if low is not None and lateral_p99 > 1.05 * lim and \
            compare("K", "", ("low", *low), ("ss", k_ss["value"], k_ss["std"]), "")["agree"]:
        why = (f"saturation not modelled: {span}, past the linear range; the same linear model fitted where the tyres "
               f"are linear gives K {_text(*low)}, agreeing with the steady turns: the tyres' bend, which the final "
               f"model lacks ({linear_range.get('how', '')}), reads there as more or less understeer")
    elif not ss.limit_derived:
        why = (f"different stretches: {span}: with too few steady turns where the tyres are surely linear, their "
               f"linear range is not read and their K takes in the tyres' bend, weighted by {ss.used} held turns "
               f"where the dynamic fit weighs every segment alike (saturation not modelled: "
               f"{linear_range.get('how', '')})")
    elif lateral_p99 > 1.05 * lim:
        why = (f"different stretches: {span}; beyond the linear range the tyres' bend (modelled or not: "
               f"{linear_range.get('how', '')}) or a stiffness varying with speed weighs on the dynamic fit alone")
    else:
        why = (f"a different model structure over the same |a_y| ({span}): the steady turns fit one gain, offset and K "
               f"without dynamics, the dynamic fit K from two stiffnesses with a delay and a lag: a stiffness varying "
               f"with speed, a steering ratio varying with the angle, or a timing the dynamic fit cannot hold (the "
               f"steering channels on another clock than the gyro)")
    return compare("understeer gradient K", "rad/(m/s2)", ("dynamic fit", understeer["value"], understeer["std"]),
                   ("steady-state regression", k_ss["value"], k_ss["std"]), why)


def withheld_understeer(understeer: dict, char: dict, comparisons: list[dict]) -> tuple[dict, dict]:
    """(K, the characteristic speed): unchanged unless the dynamic fit's K and the steady turns'
    disagree (understeer_pair); then no single K is concluded: both numbers and why, ``withheld``."""
    c = next((c for c in comparisons if c["quantity"] == "understeer gradient K"), None)
    if c is None or c["agree"] or not understeer.get("identifiable", True):
        return understeer, char
    both = " and ".join(f"{m} {_text(e['value'], e['std'])}" for m, e in c["estimates"].items())
    note = f"no single value: {both} rad/(m/s2) disagree: {c['suggests']}"
    return {**understeer, "identifiable": False, "withheld": True, "note": note}, {**char, "withheld": True}
