"""Every quantity ``identify`` and ``diagnose`` both estimate on one log, side by side.

The table (SHARED): identify's report key, the diagnosis's parameter, and the conversion into the
diagnosis's terms. The diagnosis's wheels turn w = k (1 + a sign x) x + o (steering_gain k, then
steering_asymmetry a, steering_offset o), identify's kinematic map w = g_left u (u > 0), g_right u
(u <= 0), + delta_0, so::

    k = (g_left + g_right) / 2        a = (g_left - g_right) / (g_left + g_right)        o = delta_0

and a turn gives only g / L: identify's gain (relative to its declared wheelbase L_i) is k x
L_study / L_i in the diagnosis's (the study's yaw plant's l_f + l_r). The steering delay is
identify's delay from its input (the command: the whole chain; the measured angle: angle to yaw);
the diagnosis's is command_delay - steering_clock from the command, -steering_clock from the
measured angle (steering_clock > 0: the yaw answers the angle the log shows later). The gyro bias:
identify's gyro_bias, the diagnosis's yaw_rate_bias. The understeer gradient: identify's
K = (1/c_f - 1/c_r) / g, the diagnosis's m / L (l_r / (s_f C_f) - l_f / (s_r C_r)) from the
study's stiffnesses C and its refitted cornering scales s (the same K per unit axle load), its
interval by the delta method on the refitted parameters' covariance (yaw_covariance).

A diagnosis parameter whose effect was not kept is held at the study's value (no interval). Two
estimates agree when their 95 % intervals overlap (estimation.compare); otherwise every reason that
holds on the log is named with both numbers: the diagnosis holds it fixed; a different model
structure (a gain per side against one gain; a pure delay against a delay and a first-order lag;
a gain fitted beside free cornering stiffnesses); different stretches (each one's span).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from agrobot.components.models.yaw_dynamics import GRAVITY
from agrobot.estimation import (Z95, FitResult, compare, effective_size, forward_jacobian,
                                solution_covariance)

from .candidates import uncertain


@dataclass(frozen=True)
class Shared:
    """One quantity both tools estimate: its name, SI unit, display (factor, unit), identify's
    report key and the diagnosis's parameter (its effect's id)."""

    quantity: str
    unit: str
    display: tuple[float, str]
    identify_key: str
    parameter: str
    effect: str


SHARED = (Shared("steering gain", "1", (1.0, ""), "steer_gain", "steering_gain", "steering_gain"),
          Shared("steering asymmetry", "1", (1.0, ""), "asymmetry", "steering_asymmetry", "steering_asymmetry"),
          Shared("steering offset", "rad", (180 / math.pi, " deg"), "steer_offset", "steer_angle_offset",
                 "steering_offset"),
          Shared("steering delay", "s", (1.0, " s"), "delay", "command_delay", "actuator_delay"),
          Shared("gyro bias", "rad/s", (180 / math.pi, " deg/s"), "gyro_bias", "yaw_rate_bias", "yaw_rate_bias"),
          Shared("understeer gradient", "rad/(m/s2)", (GRAVITY * 180 / math.pi, " deg/g"), "understeer_gradient",
                 "understeer_gradient", "the baseline refit"))
SCALES = ("cornering_front_scale", "cornering_rear_scale")


def _estimate(q: dict | None) -> dict | None:
    """{value, std} of a report's quantity (std from its 95 % interval when not given), or None."""
    if not q or not isinstance(q.get("value"), (int, float)) or not math.isfinite(q["value"]):
        return None
    sd = q.get("std")
    if sd is None and q.get("interval"):
        sd = (q["interval"][1] - q["interval"][0]) / (2 * Z95)
    return {"value": float(q["value"]), "std": float(sd) if sd is not None else math.nan, "how": q.get("how", "")}


def identify_side(rep: dict) -> dict:
    """Identify's side of the table from its report: each shared quantity's {value, std, how} in its
    own terms, its input, final model, wheelbase, lag (dynamic model) and the span it fits on."""
    params = rep.get("parameters") or {}
    out = {k: e for k in ("steer_gain", "steer_offset", "delay", "gyro_bias") if (e := _estimate(params.get(k)))}
    smap = rep.get("steering_map") or {}
    if (a := _estimate(smap.get("asymmetry"))) is not None:
        out["asymmetry"] = {**a, "how": "(g_left - g_right) / (g_left + g_right)"}
    K = rep.get("understeer_gradient") or {}
    if (k := _estimate(K)) is not None:
        out["understeer_gradient"] = {**k, "how": "withheld: " + K.get("note", "") if K.get("withheld") else
                                      K.get("from", "")}
    if "delay" in out:
        out["delay"]["how"] = {"delta_cmd": "from the command delta_cmd", "delta": "from the measured angle delta"}.get(
            rep.get("input"), "") + " to the yaw"
    if smap and "steer_gain" in out:
        out["steer_gain"]["how"] = "(g_left + g_right) / 2"
    span = None
    plot, seg = rep.get("_plot") or {}, rep.get("segments") or {}
    if plot.get("log") is not None:
        log = plot["log"]
        t = log.t[log.v >= seg.get("min_speed", 0.0)]
        span = [float(t.min()), float(t.max())] if len(t) else None
    lag = _estimate(params.get("lag"))
    return {"quantities": out, "input": rep.get("input"), "final_model": rep.get("final_model"),
            "wheelbase": (rep.get("vehicle") or {}).get("wheelbase"), "lag": lag["value"] if lag else None,
            "span": span}


def yaw_covariance(replay, values: dict[str, float]) -> FitResult | None:
    """The covariance of the yaw stage's refitted baseline parameters (candidates.uncertain: the
    cornering and relaxation scales, the steering's time constant on a command-only log; those the
    refit held are left out) at the final model's ``values``: the forward-difference Jacobian of the
    yaw residuals on the fit part, and the one covariance rule, RSS / (n - k) x n / n_eff with a
    parameter on its bound held (estimation.solution_covariance). The selection's final fit scores
    the model without refitting, so keeps none. None: no yaw stage, or no cornering scale refitted."""
    if "yaw" not in getattr(replay, "stages", ()):
        return None
    free = [p for p in uncertain(replay, "yaw") if p.name in values]
    if not any(p.name in SCALES for p in free):
        return None

    def many(xs: list[np.ndarray]) -> list[np.ndarray]:
        sets = [{**values, **{p.name: float(x) * p.scale for p, x in zip(free, xi)}} for xi in xs]
        return [np.asarray(r, float) for r in replay.residuals_many("yaw", sets, "fit")]

    x = np.array([values[p.name] / p.scale for p in free])
    f0 = many([x])[0]
    lo, hi = (np.array([getattr(p, side) / p.scale for p in free]) for side in ("lower", "upper"))
    jac = forward_jacobian(many, x, lo, hi, rel_step=1e-3, f0=f0)
    rss, n, n_eff = float(f0 @ f0), len(f0), effective_size(f0, updates=replay.updates("yaw"))
    cov = solution_covariance(jac, 0.5 * rss, x, free, n, n_eff)
    return FitResult(dict(values), tuple(free), cov, {"yaw": rss}, {"yaw": n}, {"yaw": n_eff})


def understeer_of(final, tractor, covariance: FitResult | None = None) -> dict:
    """The diagnosis's understeer gradient K = m / L (l_r / (s_f C_f) - l_f / (s_r C_r)) from the
    study's stiffnesses C and its refitted cornering scales s, its std by the delta method,
    dK/ds_f = -m l_r / (L C_f s_f^2), dK/ds_r = m l_f / (L C_r s_r^2), on the scales' covariance:
    the final fit's where it keeps one, else ``covariance`` (yaw_covariance); held (the study's
    K, no interval) when neither scale is refitted."""
    p, v = tractor, final.values
    L, sf, sr = p.l_f + p.l_r, v.get(SCALES[0], 1.0), v.get(SCALES[1], 1.0)
    K = p.m / L * (p.l_r / (sf * p.C_f) - p.l_f / (sr * p.C_r))
    grad = {SCALES[0]: -p.m * p.l_r / (L * p.C_f * sf ** 2), SCALES[1]: p.m * p.l_f / (L * p.C_r * sr ** 2)}
    fits = [f for f in (final, covariance) if f is not None]
    fit = next((f for f in fits if any(n in f.names and math.isfinite(f.std(n)) for n in SCALES)), None)
    sd = fit.interval_of(grad) if fit is not None else math.nan
    moved = fit is not None or sf != 1.0 or sr != 1.0
    how = ("the study's stiffnesses x the refitted cornering scales" + (
        "" if fit is None else " (delta method on the final fit's covariance)" if fit is final else
        " (delta method on the yaw stage's covariance of the refitted parameters at the final values)")) \
        if moved else "the study's stiffnesses"
    return {"value": K, "std": sd, "fixed": not moved, "how": how,
            "held": "neither cornering scale refitted on this log (the baseline refit's line says why)"}


def diagnosis_side(effects: list[dict], sel, replay, tractor) -> dict:
    """The diagnosis's side: each shared parameter's {value, std, fixed, why} (an effect kept: its
    fit; else the study's value held, with what its trial alone said), its steering time constant,
    whether the yaw stage runs on the command, its wheelbase and the span it fits on."""
    kept = {e["id"]: e for e in effects}
    tried = {f.effect.id: f for f in getattr(sel, "first_step", ())}
    values = sel.final.values
    out = {}
    for s in SHARED[:-1] + (Shared("steering clock", "s", (1.0, " s"), "", "steering_clock", "steering_clock"),):
        if s.effect in kept:
            p = kept[s.effect]["fitted"][s.parameter]
            out[s.parameter] = {"value": p["value"], "std": p["std"], "fixed": False, "how": s.effect}
        elif s.parameter in values:
            f = tried.get(s.effect)
            why = ("not tried" if f is None else "; ".join(f.reasons) or "supported alone but not kept beside the others")
            out[s.parameter] = {"value": float(values[s.parameter]), "std": math.nan, "fixed": True,
                                "how": "the study's value", "held": f"{s.effect} not kept: {why}"}
    mask = replay.masks["yaw"]["fit"] if "yaw" in replay.masks else np.zeros(len(replay.t), bool)
    t = replay.t[mask]
    out["understeer_gradient"] = understeer_of(sel.final, tractor, yaw_covariance(replay, sel.final.values))
    return {"parameters": out, "time_constant": float(values.get("steering_time_constant", math.nan)),
            "command_only": bool(getattr(replay, "command_only", False)), "wheelbase": tractor.l_f + tractor.l_r,
            "effects": sorted(kept),
            "span": [float(t.min()), float(t.max())] if len(t) else None, "split": replay.split}


def _diagnosis_delay(diag: dict, command: bool) -> dict | None:
    """The diagnosis's delay from identify's input: command_delay - steering_clock from the
    command, -steering_clock from the measured angle (stds added in quadrature; fixed when both are)."""
    p = diag["parameters"]
    clock = p.get("steering_clock", {"value": 0.0, "std": math.nan, "fixed": True, "how": "", "held": ""})
    parts = [("-steering_clock", {**clock, "value": -clock["value"]})]
    if command and "command_delay" in p:
        parts.insert(0, ("command_delay", p["command_delay"]))
    free = [x for _, x in parts if not x["fixed"]]
    held = "; ".join(x["held"] for _, x in parts if x["fixed"] and x.get("held"))
    how = " ".join(n for n, _ in parts).replace(" -", " - ") + ("" if free else ", the study's values")
    act = p.get("command_delay")
    if not command and act and not act["fixed"]:
        how += f"; its command_delay {act['value']:.3g} s is from the command to the angle, which identify does not fit"
    return {"value": sum(x["value"] for _, x in parts), "std": math.sqrt(sum(x["std"] ** 2 for x in free)) if free
            else math.nan, "fixed": not free, "how": how, "held": held}


def _shown(value: float, sd: float, s: Shared) -> str:
    f, unit = s.display
    if not math.isfinite(sd):
        return f"{f * value:.3g}{unit}"
    return f"{f * value:.3g}{unit} [{f * (value - Z95 * sd):.3g}, {f * (value + Z95 * sd):.3g}]"


def _pair(s: Shared, ident: dict, diag: dict) -> tuple[dict, dict] | None:
    """(identify's, the diagnosis's) estimate of ``s`` in the diagnosis's terms, or None when one
    side does not estimate it on this log."""
    mine = ident["quantities"].get(s.identify_key)
    if mine is None:
        return None
    if s.parameter == "command_delay":
        theirs = _diagnosis_delay(diag, ident.get("input") == "delta_cmd")
    else:
        theirs = diag["parameters"].get(s.parameter)
    if theirs is None:
        return None
    mine = dict(mine)
    Li, Ls = ident.get("wheelbase"), diag.get("wheelbase")
    if s.parameter == "steering_gain" and Li and Ls and abs(Li - Ls) > 1e-6 * Ls:
        mine.update(value=mine["value"] * Ls / Li, std=mine["std"] * Ls / Li,
                    how=f"{mine['how']} x {Ls:.3g} m / {Li:.3g} m (the study's wheelbase against identify's)".strip())
    return mine, theirs


def _fmt_span(span) -> str:
    return f"t {span[0]:.0f}-{span[1]:.0f} s" if span else "no span"


MAP = SHARED[:3]                  # the steering map's gain, asymmetry and offset: they trade against each other


def _held_map_parts(s: Shared, ident: dict, diag: dict) -> list[str]:
    """The steering map's other parts the diagnosis holds at the study's value where identify's
    estimate of them lies outside its interval away from that value: a different model structure."""
    if s not in MAP:
        return []
    out = []
    for o in MAP:
        theirs, mine = diag["parameters"].get(o.parameter), ident["quantities"].get(o.identify_key)
        if o is s or not theirs or not theirs["fixed"] or not mine:
            continue
        sd = mine["std"] if math.isfinite(mine["std"]) else 0.0
        if abs(mine["value"] - theirs["value"]) > Z95 * sd:
            out.append(f"a different model structure: the diagnosis's map holds its {o.quantity} at the study's "
                       f"{_shown(theirs['value'], math.nan, o)}, identify's fits {_shown(mine['value'], mine['std'], o)} "
                       f"(the map's gain, asymmetry and offset trade against each other)")
    return out


def _delay_structure(ident: dict, diag: dict, mine: dict, theirs: dict) -> list[str]:
    """A delay beside a first-order lag on one side and a pure delay (or another lag) on the other:
    the two delays plus lags side by side (a lag T delays a slow input by about T)."""
    lag, T = ident.get("lag"), diag["time_constant"] if ident.get("input") == "delta_cmd" else 0.0
    if not (lag or T) or not math.isfinite(T):
        return []
    ours, yours = mine["value"] + (lag or 0.0), theirs["value"] + T
    sd = mine["std"] if math.isfinite(mine["std"]) else 0.0
    near = "apart by less" if abs(ours - yours) <= Z95 * sd else "apart by more"
    theirs_text = f"a first-order lag of {T:.3g} s beside its delay" if T else "no lag from the measured angle"
    mine_text = f"a lag of {lag:.3g} s beside its delay" if lag else "a pure delay (which takes up a lag)"
    return [f"a different model structure: the diagnosis's steering has {theirs_text}, identify's {mine_text}: delay "
            f"+ lag {ours:.3g} s identify's, {yours:.3g} s the diagnosis's, {near} than identify's 95 % half-width "
            f"{Z95 * sd:.2g} s"]


def _understeer_structure(ident: dict, diag: dict, mine: dict) -> list[str]:
    """Where the two models' tyres differ: one saturates, or the diagnosis's stiffness changes with
    speed; identify withholding its K (its two estimates disagree), or taking it from the steady
    turns, is said with it."""
    out = []
    kept = set(diag.get("effects", ()))
    if "speed_dependent_cornering" in kept:
        out.append("a different model structure: the diagnosis's cornering stiffness changes with speed "
                   "(speed_dependent_cornering): its K is the one at the reference speed")
    if (ident.get("final_model") == "tyre_saturation") != ("tyre_saturation" in kept):
        one = "identify's" if ident.get("final_model") == "tyre_saturation" else "the diagnosis's"
        out.append(f"a different model structure: {one} tyres saturate (K of their linear part), the other's are linear")
    if mine.get("how", "").startswith("withheld"):
        out.append(f"identify {mine['how']}")
    elif mine.get("how", "").startswith("the steady-state regression"):
        out.append(f"a different model structure: identify's K is {mine['how']}, read from steady turns; the "
                   f"diagnosis's from cornering scales fitted to the yaw dynamics")
    return out


def _reasons(s: Shared, ident: dict, diag: dict, mine: dict, theirs: dict) -> list[str]:
    """Every reason that holds on this log why the two estimates of ``s`` can differ."""
    out = []
    if theirs["fixed"]:
        out.append(f"the diagnosis holds it at the study's {_shown(theirs['value'], math.nan, s)} ({theirs['held']})")
    out += _held_map_parts(s, ident, diag)
    if s.parameter == "steering_gain" and ident.get("final_model") not in ("kinematic", "steady_turn"):
        out.append("a different model structure: identify fits the gain beside free cornering stiffnesses and a "
                   "lag, the diagnosis beside the study's stiffnesses (bounded scales)")
    if s.parameter == "steering_gain" and ident.get("final_model") == "steady_turn":
        out.append("a different model structure: identify's is the steady-state gain r / (v tan(u) / L) of one "
                   "steady turn, holding that side's gain, the offset and the understeer in one number")
    if s.parameter == "command_delay":
        out += _delay_structure(ident, diag, mine, theirs)
    if s.parameter == "understeer_gradient":
        out += _understeer_structure(ident, diag, mine)
    if s.parameter == "yaw_rate_bias" and "standing still" in mine.get("how", ""):
        out.append(f"different stretches: identify's is the {mine['how']}, the diagnosis's is fitted while driving "
                   f"({_fmt_span(diag['span'])})")
    elif diag.get("split") == "tail":
        out.append(f"different stretches: identify fits segments spread over {_fmt_span(ident.get('span'))} (every "
                   f"third held out), the diagnosis its fit part {_fmt_span(diag['span'])}")
    return out or ["no reason in the table holds (neither fixed, the same model structure, the same stretches): "
                   "an interval is too narrow; check the effective sample sizes"]


def shared_quantities(ident: dict | None, diag: dict) -> list[dict]:
    """Each quantity of SHARED both estimate on the log: the two estimates (estimation.compare, in the
    diagnosis's terms), whether they agree, the reasons when not, and the line said for it."""
    if not ident:
        return []
    out = []
    for s in SHARED:
        pair = _pair(s, ident, diag)
        if pair is None:
            continue
        mine, theirs = pair
        if s.parameter == "steering_asymmetry" and theirs["fixed"] and \
                abs(mine["value"]) <= Z95 * (mine["std"] if math.isfinite(mine["std"]) else 0.0):
            continue                 # neither finds an asymmetry: nothing to set side by side
        c = compare(s.quantity, s.unit, ("identify", mine["value"], mine["std"]),
                    ("diagnose", theirs["value"], theirs["std"]), "")
        reasons = [] if c["agree"] else _reasons(s, ident, diag, mine, theirs)
        text = (f"{s.quantity}: identify {_shown(mine['value'], mine['std'], s)}"
                + (f" ({mine['how']})" if mine.get("how") else "")
                + f"; diagnose {_shown(theirs['value'], theirs['std'], s)} ({theirs['how']}): "
                + ("they agree" if c["agree"] else "they differ: " + "; ".join(reasons)))
        out.append({**c, "suggests": "; ".join(reasons), "reasons": reasons, "identify_how": mine.get("how", ""),
                    "diagnose_how": theirs["how"], "diagnose_fixed": theirs["fixed"], "line": text})
    return out
