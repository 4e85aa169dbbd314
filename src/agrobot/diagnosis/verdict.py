"""The verdict: one object that the console, ``diagnosis.json`` and ``report.md`` all print.

It is built from the judged effects and three checks an engineer makes before signing:

- **the recording before the vehicle**: an unresolved finding of the import audit
  (``frame.attrs["audit"]``: a clock offset of a channel group, a response that leads its input, a
  position that is an estimate, ...) can imitate vehicle effects (delays, lever arms, biases,
  latencies: each effect names the finding kinds that can imitate it, ``Effect.imitated_by``);
  while it stands, those are fitted and listed but not concluded;
- **causes that fit the vehicle**: each effect's fitted values are judged against the ``[vehicle]``
  table by the effect's own rule (``Effect.plausibility``: a point outside the outline, a steering
  delay longer than a human reaction, a friction above what tyres give, a bias beyond the gyro
  class): such a value is not a mounting, an actuator or a tyre but a sign of something else, and
  the verdict says what, with the number;
- **no verdict on a range edge**: an effect whose parameter ends on its physical limit (the range
  was widened to it first, diagnosis.selection) is *not identifiable*, and the verdict says so
  rather than "none"; but a parameter the effect reads as a lower limit there (``at_least``: a
  friction whose peak the log's turns do not reach) is said as "at least" its bound, and the effect
  stands; an effect whose secondary parameter (a tyre's shape) ends on its bound stands, but none of
  its values is concluded (the others were fitted with that one held there), and the verdict says why;
- **the study before the effects**: a study whose wheelbase the log's steady turns miss by more
  than 30 % is the verdict (``wrong_study``, plausibility.wrong_study, with the evidence and what to
  run instead); effects that rescale the yaw rate as a wheelbase does (plausibility.RESCALE_YAW)
  would only absorb it and are not concluded; what else was judged against the study follows. So is
  a study whose vehicle cannot do what the log shows (a turn, a wheel rate or angle, a speed or a
  lateral acceleration beyond its limits: plausibility.cannot_do), "cannot decide" where a wheel-angle
  reading that many times high is not ruled out. On a
  study that declares its vehicle, a steering gain inside a calibration error's range is the other
  reading of the same turns (steering_map_reading): it may be the verdict, the wrong study said beside it.
"""
from __future__ import annotations

from typing import Iterable, Mapping

from .catalogue import CATALOGUE
from .effect import Effect
from .plausibility import (MAP_GAIN, RESCALE_YAW, UNDECIDED, VehicleContext, steering_map_reading, wheelbase_off,
                           wrong_study)

# the audit's finding kinds that can imitate any effect (the others: each effect's ``imitated_by``)
IMITATES_ANY = ("mislabelled_channel",)
HELD = "the values fitted with it held there are not the effect's own"   # a secondary parameter on its bound


def imitated(kind: str, catalogue: Iterable[Effect] = CATALOGUE) -> list[str]:
    """The effects an audit finding of ``kind`` can imitate: those whose ``imitated_by`` names it, in
    the catalogue's order; ["*"] for a kind that imitates any (IMITATES_ANY)."""
    if kind in IMITATES_ANY:
        return ["*"]
    return [e.id for e in catalogue if kind in e.imitated_by]


def audit_findings(attrs: dict, catalogue: Iterable[Effect] = CATALOGUE) -> list[dict]:
    """The import audit's findings a log carries (``attrs["audit"]``, a list of dicts with kind,
    channels, value, interval, unit, meaning, resolved), each with the effects it can imitate
    (``imitated``); none when the log was not audited."""
    out = []
    for f in attrs.get("audit") or []:
        if not isinstance(f, dict) or "kind" not in f:
            continue
        out.append({**{k: f.get(k) for k in ("kind", "channels", "value", "interval", "unit", "meaning")},
                    "resolved": bool(f.get("resolved", False)), "imitates": imitated(f["kind"], catalogue)})
    return out


def _finding_text(f: dict) -> str:
    value = f.get("value")
    number = f" {value:.3g} {f.get('unit') or ''}".rstrip() if isinstance(value, (int, float)) else ""
    channels = ", ".join(f.get("channels") or [])
    return f"{f['kind']}{number}" + (f" ({channels})" if channels else "") + (f": {f['meaning']}" if f.get("meaning") else "")


def judge_values(effect: dict, vehicle, wheelbase: float, l_r: float, speed: float,
                 catalogue: Iterable[Effect] = CATALOGUE) -> list[str]:
    """What a fitted value that no vehicle of this class has suggests instead (empty when every
    value fits the vehicle): the rule of the catalogue's effect of that id (``Effect.plausibility``).
    ``speed``: the log's median moving speed [m/s]."""
    return _judge(effect, VehicleContext(vehicle, wheelbase, l_r, speed), {e.id: e for e in catalogue})


def _judge(effect: dict, ctx: VehicleContext, rules: Mapping[str, Effect]) -> list[str]:
    """The effect's plausibility rule on its values; none where a secondary parameter ended on its
    bound (on_secondary_bound): the values read beside it are not concluded, so nothing is claimed
    of them (a friction beside a shape on its bound is not the tyres')."""
    rule = rules.get(effect["id"])
    return rule.plausibility(effect.get("parameters", {}), ctx) if rule and not on_secondary_bound(effect) else []


def conclude(effects: list[dict], unexplained: dict | None, unidentifiable: list[dict], inconclusive: list[dict],
             audit: list[dict], vehicle, wheelbase: float, l_r: float, speed: float,
             catalogue: Iterable[Effect] = CATALOGUE, antenna: tuple[float, float] = (0.0, 0.0),
             before: Iterable[str] = (), turns: dict | None = None) -> dict:
    """The verdict object: ``id`` (an effect id, 'unexplained', 'none' or WRONG_STUDY), ``status`` (conclusive,
    inconclusive, implausible, not concluded, not identifiable), ``statement`` (one line),
    ``bullets``, each judged effect's ``judgement`` (its own rule's reasons, filled in here) included,
    and ``before``: what is said before any verdict (``before`` given: the study not being the log's
    vehicle; the log's ``turns``, study_fit.log_vehicle, off the study's wheelbase; the class's default
    outline where the study gives no dimensions). ``antenna``: the
    study's antenna from the rear axle [m] (a reference point's offset is from it)."""
    ctx = VehicleContext(vehicle, wheelbase, l_r, speed, antenna)
    wrong = wrong_study(turns)
    map_reading = wrong is not None and steering_map_reading(vehicle, turns)
    verdict = _verdict(effects, unexplained, unidentifiable, inconclusive, audit, ctx, catalogue,
                       tuple(e for e in RESCALE_YAW if not (map_reading and e == MAP_GAIN)) if wrong else ())
    if wrong and map_reading and verdict["id"] == MAP_GAIN:
        verdict["bullets"] = [f"the other reading of the same turns: {wrong}"] + verdict["bullets"]
    elif wrong:
        verdict = on_wrong_study(verdict, wrong)
    verdict["before"] = said_before(before, ctx, turns)
    return verdict


WRONG_STUDY = "wrong_study"



def on_wrong_study(verdict: dict, statement: str) -> dict:
    """The verdict on a study the log's turns are not (plausibility.wrong_study's ``statement``):
    what was judged against it, with the effects that rescale the yaw rate withheld, follows as a
    bullet (relative to the wrong study: to be judged again on the log's vehicle)."""
    judged = [] if verdict["id"] == "none" else [
        f"judged against this study (to be judged again on the log's vehicle): {verdict['id']} "
        f"({verdict['status']}): {verdict['statement']}"]
    status = "cannot decide" if statement.startswith(UNDECIDED) else "conclusive"     # plausibility.cannot_do
    return {"id": WRONG_STUDY, "status": status, "statement": statement, "bullets": judged + verdict["bullets"]}


BASELINE_BOUND = ("conclusive", "inconclusive", "implausible")    # statuses a refit on its bounds withdraws
FIT_THE_VEHICLE = ("diagnose again against a study of this vehicle (its own tyres: identify's cornering "
                   "stiffnesses and relaxation lengths in the study's yaw plant)")


def on_bounded_baseline(verdict: dict, summary: list[dict]) -> dict:
    """The verdict when the baseline refit left parameters on their bounds (baseline.refit_summary's
    ``at_bound``): the study cannot represent this vehicle there, so an effect fitted on top of it may
    absorb the misfit (or make it implausible); such an effect is then "cannot decide", with the
    parameters, their values and what to do; the effect's own statement follows as a bullet."""
    edge = [r for r in summary or () if r.get("at_bound")]
    if not edge or verdict["status"] not in BASELINE_BOUND or verdict["id"] in ("none", "unexplained", WRONG_STUDY):
        return verdict
    names = ", ".join(r["name"] for r in edge)
    values = ", ".join(f"{r['value']:.3g} on its {r['at_bound']} bound" for r in edge)
    ends = "end on their bounds" if len(edge) > 1 else "ends on its bound"
    statement = (f"cannot decide: the study's {names} {ends} ({values}), so {verdict['id']} may be "
                 f"absorbing the misfit; {FIT_THE_VEHICLE}")
    return {**verdict, "status": "cannot decide", "statement": statement,
            "bullets": [f"on that baseline ({verdict['status']}): {verdict['statement']}"] + verdict["bullets"]}


def said_before(before: Iterable[str], ctx: VehicleContext, turns: dict | None = None) -> list[str]:
    """What is said before any verdict, also before a refusal: ``before`` (the study not being the
    log's vehicle, a log in the kinematic regime), the log's steady ``turns`` (study_fit.log_vehicle)
    missing the study's wheelbase by more than 10 % (plausibility.wheelbase_off), then, for a study
    whose [vehicle] table gives no length and width, the class's default outline the values are
    judged against."""
    notes = [wheelbase_off(turns), ctx.defaults_note() if ctx.vehicle.declared else None]
    return list(before) + [n for n in notes if n]


def _bound(p: dict) -> float:
    return p["bounds"][0 if p["at_bound"] == "lower" else 1]


def _at_least(e: dict, rule: Effect | None) -> dict[str, dict]:
    """The parameters of ``e`` that ended on their upper bound and that the effect reads as a lower
    limit there (Effect ``at_least``: a friction the log's turns do not reach the peak of)."""
    names = getattr(rule, "at_least", ())
    return {n: p for n, p in (e.get("fitted") or {}).items() if n in names and p.get("at_bound") == "upper"}


def _only_at_least(e: dict, rule: Effect | None) -> bool:
    """Every primary parameter of ``e`` on a bound is an "at least" (then ``e`` is an answer)."""
    edge = {n for n, p in (e.get("fitted") or {}).items() if p.get("at_bound") and not p.get("secondary")}
    return bool(edge) and edge <= set(_at_least(e, rule))


def on_secondary_bound(e: dict) -> dict[str, dict]:
    """The secondary parameters of ``e`` (Effect.secondary) that ended on a bound: the effect stands,
    but no value read with them held there is concluded."""
    return {n: p for n, p in (e.get("fitted") or {}).items() if p.get("at_bound") and p.get("secondary")}


def undecided_text(held: dict[str, dict], rule: Effect | None) -> str:
    """Why the values of an effect with secondary parameters on their bounds are not concluded
    (the effect's ``undecided`` reason per parameter, else HELD)."""
    why = getattr(rule, "undecided", {})
    return "its values are not concluded: " + "; ".join(
        f"{n} ended on its {p['at_bound']} bound {_bound(p):g} (its physical limit): {why.get(n, HELD)}"
        for n, p in held.items())


def values_text(e: dict, rule: Effect | None) -> str:
    """The effect's values as the verdict says them: an "at least" parameter as "at least" its
    bound, a secondary one on its bound as not identifiable and the others as fitted beside it."""
    names = {k: next((n for n in (e.get("fitted") or {}) if k.startswith(n + " [")), None)
             for k in e["parameters_display"]}
    low, held = _at_least(e, rule), on_secondary_bound(e)
    beside = f" (fitted with {', '.join(held)} on its bound)" if held else ""
    return ", ".join(f"{k} at least {v:.4g}" if names[k] in low else
                     f"{k} not identifiable (on its {held[names[k]]['at_bound']} bound {v:.4g})" if names[k] in held
                     else f"{k} {v:.4g}{beside}" for k, v in e["parameters_display"].items())


def _verdict(effects: list[dict], unexplained: dict | None, unidentifiable: list[dict], inconclusive: list[dict],
             audit: list[dict], ctx: VehicleContext, catalogue: Iterable[Effect], withheld: Iterable[str] = ()) -> dict:
    """The verdict of the judged effects (``withheld``: effect ids listed but never concluded)."""
    blockers = [f for f in audit if not f["resolved"]]
    bullets = []
    for f in blockers:
        if f["kind"] == "position_is_estimate":
            bullets.append(f"the positions are an estimate ({_finding_text(f)}): a lever arm found is the point the "
                           f"estimate refers to and a latency the estimator's, not an antenna's mounting or a receiver's")
            continue
        bullets.append(f"unresolved recording finding {_finding_text(f)}; it can imitate "
                       f"{', '.join(f['imitates']) or 'nothing the catalogue holds'}: those are not concluded while it stands")
    rules = {e.id: e for e in catalogue}
    for e in effects:
        e["judgement"] = _judge(e, ctx, rules)
        e["blocked_by"] = [f["kind"] for f in blockers if "*" in f["imitates"] or e["id"] in f["imitates"]]
    unidentifiable = [e for e in unidentifiable if not _only_at_least(e, rules.get(e["id"]))]
    answers = [e for e in effects if e not in unidentifiable and e["id"] not in withheld]
    undecided = [e for e in unidentifiable if e["id"] not in withheld]
    if answers:
        top = answers[0]
        value = values_text(top, rules.get(top["id"]))
        held = on_secondary_bound(top)
        if top["blocked_by"]:
            status = "not concluded"
            statement = (f"{top['id']} fits ({value}) but is not concluded: the unresolved recording finding "
                         f"{', '.join(top['blocked_by'])} can imitate it; resolve the recording first")
        elif top["judgement"]:
            status = "implausible"
            statement = f"{top['id']} fits ({value}), but not as a property of this vehicle: {top['judgement'][0]}"
        elif any(t["effects"][0] == top["id"] for t in inconclusive):
            ties = [t for t in inconclusive if t["effects"][0] == top["id"]]
            rivals = ", ".join(t["effects"][1] for t in ties)
            status = "cannot decide" if any(t.get("undecided") for t in ties) else "inconclusive"
            statement = (f"{UNDECIDED}{top['id']} ({value}) or {rivals}: "
                         + "; ".join(t["why"] for t in ties if t.get("undecided"))
                         if status == "cannot decide" else f"{top['id']} ({value}), or equally well {rivals}")
        else:
            status = "conclusive"
            statement = f"{top['id']}: {top['hypothesis']} ({value})"
        if held:
            statement += "; " + undecided_text(held, rules.get(top["id"]))
        verdict = top["id"]
    elif undecided:
        top = undecided[0]
        verdict, status = top["id"], "not identifiable"
        statement = (f"{top['id']} explains part of the misfit but is not identifiable from this log: "
                     f"{top['not_identifiable']} (its physical limit)")
    elif unexplained:
        verdict, status = "unexplained", "conclusive"
        statement = unexplained["summary"]
    else:
        verdict, status = "none", "conclusive"
        statement = "the study explains the log to its noise floor"
    for e in effects:
        if e is not (answers[0] if answers else None):
            rival = next((t["effects"][1] for t in inconclusive if t.get("undecided") and t["effects"][0] == e["id"]), None)
            tag = ("not concluded (" + ", ".join(e["blocked_by"]) + ")" if e["blocked_by"] else
                   f"cannot decide (it or {rival})" if rival else
                   "not concluded (it rescales the yaw rate as the study's wheelbase does)" if e["id"] in withheld else
                   "not identifiable" if e in unidentifiable else "also")
            bullets.append(f"{tag}: {e['id']} " + values_text(e, rules.get(e["id"]))
                           + (f"; {e['judgement'][0]}" if e["judgement"] else ""))
    if unexplained and verdict != "unexplained":
        bullets.append("also unexplained: " + unexplained["summary"])
    return {"id": verdict, "status": status, "statement": statement, "bullets": bullets}
