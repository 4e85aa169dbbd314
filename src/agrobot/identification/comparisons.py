"""Two independent estimates of one quantity, side by side: the understeer gradient from the
dynamic fit and from steady states in their linear range (understeer_pair, withheld_understeer),
the command-to-yaw delay from the fit and from a cross-correlation, the gyro bias from the fit and
from the GNSS course. Each pair is reported with its intervals; intervals that do not overlap are
flagged with what the disagreement suggests. A pair whose dynamic fit's value identify does not
conclude (mark_not_concluded) says so and is not judged: its value is printed as fitted, not
concluded, and its agreement or disagreement concludes nothing (pair_line).

The understeer gradient, like with like. The two K come from models of different structure: the
steady-state regression reads K from windows that are only nearly steady (the yaw settling, the
speed drifting within 10 %, the v^2 r regressor of the measured yaw), the dynamic fit from two
stiffnesses simulated through time. Set bare side by side, a bias of the regression's own would
read as a disagreement. So the regression is run a second time, on the same windows, on the
final dynamic model's own simulated yaw rate (model_steady_state): its K there, K_sim, against
the model's K_dyn measures the regression's structural bias b = K_sim - K_dyn on this log's
windows, and the steady turns' estimate set beside the dynamic fit is K_ss - b; its std is the
regression's (b is read on noise-free yaw rates, and the fit's uncertainty moves K_sim and K_dyn
alike, so cancels in it to first order). They
agree when measured steady and simulated steady do: |K_ss - K_sim| <= 1.96 sqrt(sd_ss^2 +
sd_dyn^2) (K_sim carries the dynamic fit's uncertainty 1:1), one test of one difference; two 95 %
intervals that merely overlap would let estimates 2.8 standard errors apart pass.

Where these still disagree, the dynamic model does not hold the measured steady turns. Then (the
rule of withheld_understeer): if the dynamic fit spans |a_y| beyond the steady turns' linear range
(ended by a bend in the turns, or tyres saturating in the dynamic fit), or that range was not read
from the turns, the tyres' bend weighs on one estimate and not the other: no single K is concluded
(both numbers and why). If both span linear |a_y| only (neither finds a bend), K,
defined by steady cornering (delta = L / R + K a_y), is what the steady turns measure directly, and
b shows the regression unbiased for the dynamic model's behaviour: the steady turns' K_ss - b is
concluded, the dynamic fit's beside it with the share by which its model misses the steady turns
(its transients held to the study's relaxation lengths and inertia, or stepped coarsely, pull
its stiffnesses).
"""
from __future__ import annotations

import math

import numpy as np

from agrobot.components.models.yaw_dynamics import GRAVITY
from agrobot.estimation import Z95, compare

from .driving import cut_segments
from .steady_state import same_regression, steady_windows

pair = compare           # the shared rule (agrobot.estimation.compare): intervals that overlap agree
CORRECTED = "steady-state regression less its structural bias"     # K_ss - b, beside the dynamic fit's


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


def model_yaw(model, values: dict, log, min_speed: float, burn_in: float = 2.0) -> np.ndarray:
    """The dynamic model's gyro reading under ``values`` on every sample: each stretch of driving
    simulated in one piece from ``burn_in`` s before it (the measured yaw rate elsewhere)."""
    segs = cut_segments(log, min_speed, length=float(log.t[-1] - log.t[0]) + 1.0, burn_in=burn_in, min_length=0.0)
    out = np.array(log.r, float)
    if not len(segs.idx):
        return out
    sim = model.simulate(values, segs)
    for only_scored in (False, True):              # burn-ins first: a stretch's own samples win
        for i, row in enumerate(segs.idx):
            n = int(np.argmax(row == row[-1])) + 1          # the row's own samples (then its padding)
            keep = segs.scored[i, :n] if only_scored else np.ones(n, bool)
            out[row[:n][keep]] = sim[i, :n][keep]
    return out


def model_steady_state(model, values: dict, log, min_speed: float, delay: float, windows: dict, ss, u=None):
    """The steady-state regression ``ss`` (on ``windows``, steady_state.steady_windows with
    ``delay`` and the input ``u``, log.u unless given) run again on the dynamic model's own yaw rate
    (model_yaw) over the same windows: (K_sim, std), or None (no regression there). The windows are
    chosen on the input and the speed alone and kept by the measured |a_y|, so they are the same ones."""
    if ss is None:
        return None
    u = log.u if u is None else u
    w = steady_windows(log.t, u, log.v, model_yaw(model, values, log, min_speed), log.run, min_speed, delay=delay)
    if len(w["u"]) != len(windows["u"]):
        return None
    fit = same_regression(ss, {**w, "a_y": windows["a_y"]}, model.L)
    return None if fit is None else (fit.K, fit.K_std)


def understeer_pair(understeer: dict, ss, linear_range: dict, lateral_p99: float,
                    low: tuple[float, float] | None = None, twin: tuple[float, float] | None = None) -> dict:
    """The understeer gradient K of the dynamic fit beside the steady-state regression's (``ss``,
    steady_state.in_linear_range) less its structural bias b (``twin``: model_steady_state's K_sim,
    b = K_sim - K_dyn; 0 when not measured), with why they differ: saturation not modelled (the
    dynamic fit spans |a_y| up to ``lateral_p99`` beyond the steady turns' linear limit, and the same
    model fitted where the tyres are linear, ``low`` (K, std), agrees with the steady turns),
    different stretches (the |a_y| spans differ, or the steady turns' linear range was not read),
    else a different model structure over the same |a_y|: then ``steady_concluded`` (the module's
    rule)."""
    d = ss.as_dict()
    k_m, sd = d["understeer_gradient"]["value"], d["understeer_gradient"]["std"]
    bias = twin[0] - understeer["value"] if twin and math.isfinite(understeer["value"]) else 0.0
    k_ss, lim = k_m - bias, ss.max_lateral
    measured = (f"the regression's {_text(k_m, sd)} on the measured yaw less its structural bias {bias:+.2g} (the same "
                f"regression on the dynamic model's own yaw rate over the same windows gives {twin[0]:.3g})" if twin
                else "the regression's bias on the dynamic model's yaw rate not measured")
    span = (f"the steady turns: {ss.used} windows at a held input with |a_y| <= {lim:.3g} m/s2 ({ss.limit_how}); the "
            f"dynamic fit: every segment, |a_y| up to {lateral_p99:.3g} m/s2 (99th percentile)")
    # beyond the steady turns' range the dynamic fit weighs tyres that may bend, unless neither side
    # found a bend: the turns linear up to their top, the dynamic fit's tyres linear over the whole log
    past = lateral_p99 > 1.05 * lim and (ss.limit_bent or linear_range.get("saturation", True))
    same_span = False
    if low is not None and past and compare("K", "", ("low", *low), ("ss", k_ss, sd), "")["agree"]:
        why = (f"saturation not modelled: {span}, past the linear range; the same linear model fitted where the tyres "
               f"are linear gives K {_text(*low)}, agreeing with the steady turns: the tyres' bend, which the final "
               f"model lacks ({linear_range.get('how', '')}), reads there as more or less understeer")
    elif not ss.limit_derived:
        why = (f"different stretches: {span}: with too few steady turns where the tyres are surely linear, their "
               f"linear range is not read and their K takes in the tyres' bend, weighted by {ss.used} held turns "
               f"where the dynamic fit weighs every segment alike (saturation not modelled: "
               f"{linear_range.get('how', '')})")
    elif past:
        why = (f"different stretches: {span}; beyond the linear range the tyres' bend (modelled or not: "
               f"{linear_range.get('how', '')}) or a stiffness varying with speed weighs on the dynamic fit alone")
    else:
        same_span = twin is not None
        miss = 100 * (k_ss - understeer["value"]) / abs(k_ss) if k_ss else math.nan
        why = (f"a different model structure over the same linear |a_y| ({span}; neither finds a bend): the dynamic "
               f"model's steady turns miss the "
               f"measured ones by {miss:+.1f} % in K: its K comes from two stiffnesses fitted to transients through "
               f"a fitted front relaxation length, held inertia and rear relaxation, a delay and a lag (a held "
               f"value off, a stiffness varying with speed or a steering ratio varying with the angle pull it)")
    out = compare("understeer gradient K", "rad/(m/s2)", ("dynamic fit", understeer["value"], understeer["std"]),
                  (CORRECTED, k_ss, sd), f"{why}; steady turns: {measured}")
    gap_sd = math.hypot(sd, understeer["std"])        # of K_ss - K_sim: the regression's and the fit's, carried 1:1
    if math.isfinite(gap_sd) and math.isfinite(k_ss - understeer["value"]):
        out["agree"] = bool(abs(k_ss - understeer["value"]) <= Z95 * gap_sd)
        out["suggests"] = "" if out["agree"] else f"{why}; steady turns: {measured}"
        out["rule"] = (f"measured steady against simulated steady: {k_m:.4g} - {k_m - k_ss + understeer['value']:.4g} "
                       f"= {k_ss - understeer['value']:+.2g}, its std {gap_sd:.2g}")
    out["structural_bias"] = {"value": bias, "measured": twin is not None, "K_measured": k_m,
                              "K_on_model": twin[0] if twin else math.nan}
    out["steady_concluded"] = bool(same_span and not out["agree"])
    return out


def withheld_understeer(understeer: dict, char: dict, comparisons: list[dict], char_of=None) -> tuple[dict, dict]:
    """(K, the characteristic speed): unchanged where the dynamic fit's K and the steady turns'
    agree (understeer_pair). Where they disagree over the same linear |a_y| (``steady_concluded``),
    the steady turns' K less its structural bias is concluded, the dynamic fit's beside it in the
    note (``char_of(K, std)``: the characteristic speed of that K); else no single K is concluded:
    both numbers and why, ``withheld``."""
    c = next((c for c in comparisons if c["quantity"] == "understeer gradient K"), None)
    if c is None or c["agree"] or not understeer.get("identifiable", True):
        return understeer, char
    both = " and ".join(f"{m} {_text(e['value'], e['std'])}" for m, e in c["estimates"].items())
    if c.get("steady_concluded") and char_of is not None:
        e = c["estimates"][CORRECTED]
        note = (f"from the steady turns, where K is defined: {both} rad/(m/s2) disagree over the same linear |a_y|: "
                f"{c['suggests']}")
        return ({**understeer, "value": e["value"], "std": e["std"], "interval": e["interval"],
                 "deg_per_g": math.degrees(e["value"]) * GRAVITY, "from": "the steady-state regression less its "
                 "structural bias (the dynamic fit's disagrees)", "note": note}, char_of(e["value"], e["std"]))
    note = f"no single value: {both} rad/(m/s2) disagree: {c['suggests']}"
    return {**understeer, "identifiable": False, "withheld": True, "note": note}, {**char, "withheld": True}


def mark_not_concluded(comparisons: list[dict], understeer: dict, params: dict) -> list[dict]:
    """``comparisons``, each pair whose dynamic fit's value identify does not conclude (its K
    ``understeer``, its delay or gyro bias among ``params``: not ``identifiable``, or ``concluded``
    False) marked ``concluded`` False, with that quantity's note as ``why_not``. A K withheld because
    the pair disagrees (withheld_understeer) keeps its pair judged: the disagreement is why."""
    own = {"understeer gradient K": None if understeer.get("withheld") else understeer,
           "command-to-yaw delay": params.get("delay"),
           "gyro bias": params.get("gyro_bias")}
    for c in comparisons:
        q = own.get(c["quantity"])
        if q and (not q.get("identifiable", True) or q.get("concluded") is False):
            c["concluded"], c["why_not"] = False, q.get("note", "")
    return comparisons


def pair_line(c: dict) -> str:
    """One pair as a person reads it: both estimates with their 95 % intervals and DISAGREE with what
    it suggests; a pair not concluded (mark_not_concluded) gives the dynamic fit's value as fitted
    and is not judged."""
    out = c.get("concluded", True) is not False

    def one(m, e):
        text = f"{e['value']:.4g} [{e['interval'][0]:.4g}, {e['interval'][1]:.4g}]"
        return f"{m} {text}" if out or m != "dynamic fit" else f"{m} not concluded (fitted {text})"
    line = f"{c['quantity']}: " + "; ".join(one(m, e) for m, e in c["estimates"].items()) + " " + c["unit"]
    if not out:
        return line + ": not compared, the dynamic fit's value is not concluded (its own line says why)"
    return line + ("" if c["agree"] else f"  DISAGREE: {c['suggests']}")
