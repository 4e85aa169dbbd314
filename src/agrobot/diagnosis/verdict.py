"""The verdict: one object that the console, ``diagnosis.json`` and ``report.md`` all print.

It is built from the judged effects and three checks an engineer makes before signing:

- **the recording before the vehicle**: an unresolved finding of the import audit
  (``frame.attrs["audit"]``: a clock offset of a channel group, a response that leads its input, a
  position that is an estimate, ...) can imitate vehicle effects (delays, lever arms, biases,
  latencies); while it stands, those are fitted and listed but not concluded;
- **causes that fit the vehicle**: a fitted value is judged against the ``[vehicle]`` table (a
  point outside the outline, a steering delay longer than a human reaction, a friction above what
  tyres give, a bias beyond the gyro class): such a value is not a mounting, an actuator or a tyre
  but a sign of something else, and the verdict says what, with the number;
- **no verdict on a range edge**: an effect whose parameter ends on its physical limit (the range
  was widened to it first, diagnosis.selection) is *not identifiable*, and the verdict says so
  rather than "none".
"""
from __future__ import annotations

import math

from agrobot.components.models.tyre import force_limit_share

HUMAN_REACTION = 0.3          # s: no steering actuator is slower; a longer "delay" is a clock
RECEIVER_LATENCY = 0.5        # s: a GNSS receiver or a localisation filter reports within this

# audit finding kind -> the effects it can imitate
IMITATES = {
    "clock_offset": ("actuator_delay", "gps_latency", "position_reference", "antenna_lever_arm", "steering_rate_limit"),
    "response_leads_input": ("actuator_delay", "gps_latency", "position_reference", "steering_rate_limit"),
    "stamp_vs_receive": ("actuator_delay", "gps_latency", "position_reference"),
    "gap_bridged": ("actuator_delay", "gps_latency", "steering_rate_limit"),
    "scale_disagreement": ("gyro_scale", "speed_scale", "yaw_rate_bias", "tyre_saturation",
                           "speed_dependent_cornering", "steering_ratio_curve"),
    "position_is_estimate": (),      # not a blocker: it renames (conclude says what a lever arm then is)
    "mislabelled_channel": ("*",),
}


def audit_findings(attrs: dict) -> list[dict]:
    """The import audit's findings a log carries (``attrs["audit"]``, a list of dicts with kind,
    channels, value, interval, unit, meaning, resolved), each with the effects it can imitate;
    none when the log was not audited."""
    out = []
    for f in attrs.get("audit") or []:
        if not isinstance(f, dict) or "kind" not in f:
            continue
        out.append({**{k: f.get(k) for k in ("kind", "channels", "value", "interval", "unit", "meaning")},
                    "resolved": bool(f.get("resolved", False)), "imitates": list(IMITATES.get(f["kind"], ()))})
    return out


def _finding_text(f: dict) -> str:
    value = f.get("value")
    number = f" {value:.3g} {f.get('unit') or ''}".rstrip() if isinstance(value, (int, float)) else ""
    channels = ", ".join(f.get("channels") or [])
    return f"{f['kind']}{number}" + (f" ({channels})" if channels else "") + (f": {f['meaning']}" if f.get("meaning") else "")


def outline(vehicle, wheelbase: float) -> tuple[tuple[float, float], tuple[float, float], str]:
    """((forward lo, hi), (left lo, hi)) of the vehicle from its rear axle, and how it is known:
    the [vehicle] table's length and width, else a wheelbase-sized box (overhangs of half a
    wheelbase, a width of one)."""
    arm = vehicle.lever_arm_bounds()
    if arm:
        return arm[0], arm[1], f"its outline ({vehicle.length:g} m long, {vehicle.width:g} m wide)"
    return ((-0.5 * wheelbase, 1.5 * wheelbase), (-0.5 * wheelbase, 0.5 * wheelbase),
            f"a {wheelbase:.3g} m wheelbase with half a wheelbase of overhang (the study has no [vehicle] length)")


def judge_values(effect: dict, vehicle, wheelbase: float, l_r: float, speed: float) -> list[str]:
    """What a fitted value that no vehicle of this class has suggests instead (empty when every
    value fits the vehicle). ``speed``: the log's median moving speed [m/s]."""
    p, out = effect.get("parameters", {}), []
    eid = effect["id"]
    if eid in ("antenna_lever_arm", "position_reference"):
        fwd = p.get("antenna_forward", 0.0) + p.get("position_forward", 0.0)
        left = p.get("antenna_left", 0.0) + p.get("position_left", 0.0)
        (f_lo, f_hi), (l_lo, l_hi), how = outline(vehicle, wheelbase)
        if not (f_lo <= fwd <= f_hi and l_lo <= left <= l_hi):
            lag = abs(fwd - l_r) / speed if speed > 0 else math.nan
            out.append(f"the point it puts the positions at, {fwd:.2f} m ahead of the rear axle and {left:.2f} m left, "
                       f"lies outside {how}: no antenna is mounted there; at the log's median speed "
                       f"{speed:.2g} m/s a clock offset of about {lag:.2g} s between the positions and the gyro "
                       f"moves the track as far, or the positions are an estimate of another frame")
    if eid == "actuator_delay" and p.get("command_delay", 0.0) > HUMAN_REACTION:
        out.append(f"a steering delay of {p['command_delay']:.2f} s is longer than a human reaction "
                   f"({HUMAN_REACTION:g} s): no steering actuator is that slow; the steering channels are probably "
                   f"stamped on a clock that lags the gyro's (a recording problem)")
    if eid == "gps_latency" and p.get("gps_latency", 0.0) > RECEIVER_LATENCY:
        out.append(f"a position latency of {p['gps_latency']:.2f} s is longer than a receiver or a localisation "
                   f"filter takes ({RECEIVER_LATENCY:g} s): the positions' clock is offset")
    if eid == "position_reference" and abs(p.get("position_clock", 0.0)) > 2.0:
        out.append(f"a clock offset of {p['position_clock']:.2f} s is more than a stamping delay: the channel groups "
                   f"were recorded on different clocks")
    if eid == "tyre_saturation":
        mu = p.get("tyre_friction", 0.0) * force_limit_share(p.get("tyre_shape", 1.3))   # the force it reaches
        hi = vehicle.friction_range[1]
        if mu > hi:
            out.append(f"a friction of {mu:.2f} is above what tyres give on this vehicle's ground "
                       f"({hi:g} for a {vehicle.kind or 'vehicle'}): the lateral acceleration is overstated (a speed or "
                       f"gyro scale factor) or the mass and inertia are not this vehicle's")
    if eid == "yaw_rate_bias" and vehicle.gyro_bias_bound and abs(p.get("yaw_rate_bias", 0.0)) > vehicle.gyro_bias_bound:
        out.append(f"a gyro bias of {math.degrees(p['yaw_rate_bias']):.2f} deg/s is beyond what a gyro of this class "
                   f"drifts ({math.degrees(vehicle.gyro_bias_bound):g} deg/s): a steering offset or a side slope "
                   f"seen through the yaw rate, or a gyro mounted tilted")
    for key, what in (("gyro_scale", "gyro"), ("speed_scale", "speed")):
        s = p.get(key)
        if s is not None and not 0.7 <= s <= 1.4:
            out.append(f"a {what} scale factor of {s:.3g} is no sensor error: a unit or a channel is wrong")
    k = p.get("steering_gain")
    if eid == "steering_gain" and k is not None and not 0.7 <= k <= 1.4:
        if abs(k * 180 / math.pi - 1.0) < 0.1 or abs(k * math.pi / 180 - 1.0) < 0.1:
            out.append(f"a steering command gain of {k:.3g} is a unit: the command is in degrees where radians "
                       f"are expected, or the other way round")
        elif 1 / 30 <= k <= 1 / 8:
            out.append(f"a steering command gain of {k:.3g} is a steering ratio (1:{1 / k:.0f}): the command is the "
                       f"handwheel's angle, not the road wheels'")
        else:
            out.append(f"a steering command gain of {k:.3g} is no calibration error: the command is another quantity "
                       f"or in another unit")
    if eid == "steering_offset" and abs(p.get("steer_angle_offset", 0.0)) > math.radians(8):
        out.append(f"a steering offset of {math.degrees(p['steer_angle_offset']):.1f} deg is more than a misaligned "
                   f"zero: the steering channel is another quantity (a handwheel angle, a command in another unit)")
    return out


def conclude(effects: list[dict], unexplained: dict | None, unidentifiable: list[dict], inconclusive: list[dict],
             audit: list[dict], vehicle, wheelbase: float, l_r: float, speed: float) -> dict:
    """The verdict object: ``id`` (an effect id, 'unexplained' or 'none'), ``status`` (conclusive,
    inconclusive, implausible, not concluded, not identifiable), ``statement`` (one line) and
    ``bullets``, each judged effect's ``judgement`` (filled in here) included."""
    blockers = [f for f in audit if not f["resolved"]]
    bullets = []
    for f in blockers:
        if f["kind"] == "position_is_estimate":
            bullets.append(f"the positions are an estimate ({_finding_text(f)}): a lever arm found is the point the "
                           f"estimate refers to and a latency the estimator's, not an antenna's mounting or a receiver's")
            continue
        bullets.append(f"unresolved recording finding {_finding_text(f)}; it can imitate "
                       f"{', '.join(f['imitates']) or 'nothing the catalogue holds'}: those are not concluded while it stands")
    for e in effects:
        e["judgement"] = judge_values(e, vehicle, wheelbase, l_r, speed)
        e["blocked_by"] = [f["kind"] for f in blockers if "*" in f["imitates"] or e["id"] in f["imitates"]]
    answers = [e for e in effects if e not in unidentifiable]
    if answers:
        top = answers[0]
        value = ", ".join(f"{k} {v:.4g}" for k, v in top["parameters_display"].items())
        if top["blocked_by"]:
            status = "not concluded"
            statement = (f"{top['id']} fits ({value}) but is not concluded: the unresolved recording finding "
                         f"{', '.join(top['blocked_by'])} can imitate it; resolve the recording first")
        elif top["judgement"]:
            status = "implausible"
            statement = f"{top['id']} fits ({value}), but not as a property of this vehicle: {top['judgement'][0]}"
        elif any(t["effects"][0] == top["id"] for t in inconclusive):
            status = "inconclusive"
            rivals = ", ".join(t["effects"][1] for t in inconclusive if t["effects"][0] == top["id"])
            statement = f"{top['id']} ({value}), or equally well {rivals}"
        else:
            status = "conclusive"
            statement = f"{top['id']}: {top['hypothesis']} ({value})"
        verdict = top["id"]
    elif unidentifiable:
        top = unidentifiable[0]
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
            tag = ("not concluded (" + ", ".join(e["blocked_by"]) + ")" if e["blocked_by"] else
                   "not identifiable" if e in unidentifiable else "also")
            bullets.append(f"{tag}: {e['id']} " + ", ".join(f"{k} {v:.4g}" for k, v in e["parameters_display"].items())
                           + (f"; {e['judgement'][0]}" if e["judgement"] else ""))
    if unexplained and verdict != "unexplained":
        bullets.append("also unexplained: " + unexplained["summary"])
    return {"id": verdict, "status": status, "statement": statement, "bullets": bullets}
