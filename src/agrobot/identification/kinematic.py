"""The kinematic regime: turns too gentle for the tyres to matter, and the steering map from them.

Regime: the 95th percentile of the lateral acceleration |v r| while driving below
KINEMATIC_LATERAL (0.5 m/s2). There a tyre's slip angle is a few tenths of a degree on any vehicle
(F_y / C_alpha with C_alpha / F_z >= 4 /rad on a tractor's soft tyres: a_y / (4 g) <= 0.013 rad),
so an understeer gradient, a critical or a characteristic speed are not identifiable at these
speeds, and the model is the kinematic one::

    r = v tan(w(t - tau)) / L + b          w(u) = g_left u (u > 0), g_right u (u <= 0), + delta_0

u the steering input (measured wheel angle, else the command), L the declared wheelbase (the gain
and the wheelbase are one quantity from turns, g / L: the gain is relative to it), tau the delay,
b the gyro bias (a heading has none; a bias measured standing still is held). Reported: the gain
(g_left + g_right) / 2, the asymmetry (g_left - g_right) / (g_left + g_right), the offset delta_0,
each with its 95 % interval (estimation.covariance on the fit segments, n_eff of the residuals,
never more than the yaw measurement's own updates), and the turn radius each side at the largest
input of the log.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import least_squares

from agrobot.estimation import Parameter, covariance, effective_size, forward_jacobian, interval
from agrobot.components.tractor_yaw_plant import steer_input

from .delay_bound import DELAY_LIMIT, delay_verdict
from .driving import DrivingLog, Segments

KINEMATIC_LATERAL = 0.5        # m/s2: 95th percentile of |v r| below which the tyres do not matter
NOT_AT_THESE_SPEEDS = "not identifiable at these speeds"


def lateral_p95(log: DrivingLog, min_speed: float) -> float:
    """The 95th percentile of |v r| [m/s2] over the driving where the yaw rate is measured."""
    m = (log.v >= min_speed) & (log.measured if log.measured is not None else True)
    return float(np.percentile(np.abs(log.v * log.r)[m], 95)) if m.any() else 0.0


def map_parameters(fit_bias: bool) -> list[Parameter]:
    out = [Parameter("gain_left", "1", 0.2, 0.3, 2.0, meaning="wheel angle per unit input, turning left (u > 0)"),
           Parameter("gain_right", "1", 0.2, 0.3, 2.0, meaning="wheel angle per unit input, turning right (u < 0)"),
           Parameter("steer_offset", "rad", 0.02, -0.2, 0.2, meaning="wheel angle at zero input"),
           Parameter("delay", "s", 0.1, 0.0, 0.5, limit=DELAY_LIMIT, meaning="delay from the input to the yaw")]
    if fit_bias:
        out.append(Parameter("gyro_bias", "rad/s", 0.01, -0.1, 0.1, meaning="gyro bias"))
    return out


def predicted(log: DrivingLog, values: dict, L: float) -> np.ndarray:
    """r = v tan(w(t - tau)) / L + b on every sample (u before its run's start: its first value), as
    the yaw measurement sees it (DrivingLog.as_measured)."""
    u = log.delayed_input(values["delay"])
    w = np.where(u > 0, values["gain_left"], values["gain_right"]) * u + values["steer_offset"]
    return log.as_measured(log.v * steer_input(w, "tan") / L) + values.get("gyro_bias", 0.0)


def fit_map(log: DrivingLog, fit_segs: Segments, L: float, fixed: dict, free: list[Parameter] | None = None) -> dict:
    """Least squares of the measured yaw rate on the fit segments' scored samples; returns the
    values, the standard deviations (nan on a bound), n, n_eff and the parameters (``free``:
    map_parameters unless given)."""
    free = free or map_parameters("gyro_bias" not in fixed)
    idx, mask = fit_segs.idx, fit_segs.scored
    y = log.r[idx][mask]
    lo = np.array([p.lower / p.scale for p in free])
    hi = np.array([p.upper / p.scale for p in free])

    def values_of(x):
        return {**fixed, **{p.name: float(xi) * p.scale for p, xi in zip(free, x)}}

    def fun(x):
        return y - predicted(log, values_of(x), L)[idx][mask]

    best = None
    for delay in (0.05, 0.25) + ((-0.2,) if free[3].lower < 0 else ()):
        x0 = np.array([1.0 / 0.2, 1.0 / 0.2, 0.0, delay / 0.1] + ([0.0] if len(free) > 4 else []))
        sol = least_squares(fun, x0, bounds=(lo, hi), x_scale=1.0,
                            jac=lambda x: forward_jacobian(lambda xs: [fun(xi) for xi in xs], x, lo, hi, floor=1.0))
        if best is None or sol.cost < best.cost:
            best = sol
    values = values_of(best.x)
    rows = [(log.r[idx[i]] - predicted(log, values, L)[idx[i]])[mask[i]] for i in range(len(idx))]
    n, n_eff = len(best.fun), effective_size(rows, updates=log.updates_in(fit_segs))
    span = hi - lo
    held = (np.abs(best.x - lo) <= 2e-3 * span) | (np.abs(best.x - hi) <= 2e-3 * span)
    scale = np.array([p.scale for p in free])
    cov = covariance(best.jac, 2 * best.cost, n, n_eff, held) * np.outer(scale, scale)
    return {"values": values, "cov": cov, "free": free, "n": n, "n_eff": n_eff}


def _quantity(value: float, std: float, unit: str, meaning: str) -> dict:
    lo, hi = interval(value, std)
    return {"value": float(value), "std": float(std), "interval": [float(lo), float(hi)], "unit": unit,
            "identifiable": bool(math.isfinite(std)), "meaning": meaning}  # on a bound: no interval, not identifiable


def steering_map(fitted: dict, log: DrivingLog, L: float) -> dict:
    """Gain, asymmetry, offset, delay (and bias) with their 95 % intervals (delta method on the
    fit's covariance), the turn radius each side at the log's largest input."""
    v, cov = fitted["values"], np.nan_to_num(fitted["cov"], nan=0.0)
    names = [p.name for p in fitted["free"]]
    gl, gr = v["gain_left"], v["gain_right"]

    def sd(grad: dict) -> float:
        if any(not math.isfinite(fitted["cov"][names.index(n), names.index(n)]) for n in grad if n in names):
            return float("nan")          # a parameter on its bound: no interval
        g = np.array([grad.get(n, 0.0) for n in names])
        return float(math.sqrt(max(g @ cov @ g, 0.0)))

    s = gl + gr
    out = {"gain": _quantity(s / 2, sd({"gain_left": 0.5, "gain_right": 0.5}), "1",
                             f"wheel angle per unit input, mean of both sides (relative to the declared wheelbase "
                             f"{L:.3g} m: gain and wheelbase are one quantity from turns)"),
           "asymmetry": _quantity((gl - gr) / s, sd({"gain_left": 2 * gr / s ** 2, "gain_right": -2 * gl / s ** 2}), "1",
                                  "(g_left - g_right) / (g_left + g_right): positive turns more to the left"),
           "gain_left": _quantity(gl, sd({"gain_left": 1.0}), "1", "gain turning left (u > 0)"),
           "gain_right": _quantity(gr, sd({"gain_right": 1.0}), "1", "gain turning right (u < 0)"),
           "steer_offset": _quantity(v["steer_offset"], sd({"steer_offset": 1.0}), "rad",
                                     "wheel angle at zero input (positive: to the left)"),
           "delay": _quantity(v["delay"], sd({"delay": 1.0}), "s", "delay from the input to the yaw")}
    if "gyro_bias" in names:
        out["gyro_bias"] = _quantity(v["gyro_bias"], sd({"gyro_bias": 1.0}), "rad/s", "gyro bias")
    radii = {}
    for side, u in (("left", float(np.max(log.u))), ("right", float(np.min(log.u)))):
        w = (gl if u > 0 else gr) * u + v["steer_offset"]
        radii[side] = {"input": u, "radius": float(L / abs(math.tan(w))) if abs(w) > 1e-6 else math.inf, "unit": "m"}
    out["turn_radius_at_largest_input"] = radii
    for p in fitted["free"]:
        if not math.isfinite(fitted["cov"][names.index(p.name), names.index(p.name)]) and p.name in out:
            out[p.name]["note"] = f"on its bound [{p.lower:g}, {p.upper:g}] {p.unit}: no interval"
    return out


def _not_here(unit: str, why: str) -> dict:
    nan = float("nan")
    return {"value": nan, "std": nan, "interval": [nan, nan], "unit": unit, "identifiable": False,
            "note": f"{NOT_AT_THESE_SPEEDS}: {why}"}


def kinematic_report(log: DrivingLog, segs: Segments, L: float, fixed: dict, p95: float) -> dict:
    """The report's parts in the kinematic regime: the steering map fitted on the fit segments,
    judged on the held-out ones; no understeer gradient, critical or characteristic speed, tyre
    stiffness or saturation ("not identifiable at these speeds", with the lateral acceleration)."""
    fit_segs, test_segs = segs.take(~segs.held_out), segs.take(segs.held_out)
    fitted = fit_map(log, fit_segs, L, fixed)
    wide = fitted["free"][3].widened(fitted["values"]["delay"])     # on its zero bound: searched below it
    if wide is not None:
        fitted = fit_map(log, fit_segs, L, fixed, [wide if p.name == "delay" else p for p in fitted["free"]])
    smap = steering_map(fitted, log, L)
    if wide is not None:
        smap["delay"] = delay_verdict(smap["delay"], [p.name for p in fitted["free"][:2]
                                                      if p.at_bound(fitted["values"][p.name])])
    pred = predicted(log, fitted["values"], L)[test_segs.idx]
    y, yhat = log.r[test_segs.idx][test_segs.scored], pred[test_segs.scored]
    fit_pct = float(100.0 * (1.0 - np.linalg.norm(y - yhat) / max(np.linalg.norm(y - y.mean()), 1e-12)))
    why = (f"95 % of the driving turns at |v r| <= {p95:.2g} m/s2, below {KINEMATIC_LATERAL:g} m/s2: the tyres' slip "
           f"is a few tenths of a degree, inside what the steering map and the noise leave")
    regime = {"kinematic": True, "lateral_acceleration_p95": p95, "threshold": KINEMATIC_LATERAL,
              "model": "r = v tan(w(t - tau)) / L + b, w = g_left u (u > 0) | g_right u (u <= 0) + delta_0",
              "says": f"kinematic regime: {why}; the model is r = v tan(delta) / L (wheelbase {L:.3g} m declared)"}
    return {"regime": regime, "steering_map": smap,
            "understeer_gradient": {**_not_here("rad/(m/s2)", why), "deg_per_g": float("nan")},
            "characteristic_speed": {**_not_here("m/s", why), "kind": "characteristic or critical speed"},
            "cornering_stiffness": {"front": _not_here("N/rad", why), "rear": _not_here("N/rad", why)},
            "tyre_saturation": {"found": False, "why_not": [f"{NOT_AT_THESE_SPEEDS}: {why}"], "parameters": {},
                                "delta_bic": float("nan"), "held_out_gain": float("nan")},
            "held_out_fit": {"value": fit_pct, "std": 0.0, "interval": [fit_pct, fit_pct], "unit": "%",
                             "how": "100 (1 - |y - y_model| / |y - mean y|) on the held-out samples", "per_segment": [],
                             "linear_model": fit_pct, "saturation_model": float("nan")},
            "fit": {"n": fitted["n"], "n_eff": fitted["n_eff"]},
            "_plot": {"log": log, "test": test_segs, "test_pred": pred}}


def kinematic_summary(report: dict) -> list[str]:
    """The kinematic regime's lines of the summary."""
    def q(d, f="{:.4g}"):
        if not math.isfinite(d["std"]):
            return f.format(d["value"]) + " " + d["unit"] + " (on its bound)"
        return f.format(d["value"]) + " [" + ", ".join(f.format(x) for x in d["interval"]) + "] " + d["unit"]

    m = report["steering_map"]
    r = m["turn_radius_at_largest_input"]
    return [report["regime"]["says"],
            f"understeer gradient, critical and characteristic speed: {NOT_AT_THESE_SPEEDS}",
            f"steering map: gain {q(m['gain'])}, asymmetry {q(m['asymmetry'])} (left {m['gain_left']['value']:.3g}, "
            f"right {m['gain_right']['value']:.3g}), offset {q(m['steer_offset'])} "
            f"({math.degrees(m['steer_offset']['value']):.2f} deg), delay {q(m['delay'])}"
            + (f"; {m['delay']['note']}" if "note" in m["delay"] else ""),
            f"turn radius at the largest input: left {r['left']['radius']:.3g} m, right {r['right']['radius']:.3g} m",
            f"held-out fit: {report['held_out_fit']['value']:.1f} %"]
