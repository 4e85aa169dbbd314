"""Is the study this log's vehicle? The log's own kinematics give its wheelbase, L = v tan(delta) / r
- K v^2 in steady turning inside the tyres' linear range (selected on the steering input as well as
the yaw rate: a saturating tyre's turns would lengthen it), and its speed and steering ranges; they are
compared with the study's wheelbase, so that a log diagnosed against another vehicle's study says so,
and with the shipped studies: one is suggested only when it is of the declared vehicle's class and
size (wheelbase, outline, mass), else the study to write is named.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Callable

import numpy as np

from agrobot.estimation import effective_size, interval
from agrobot.identification.ordinary_driving import study_plant
from agrobot.identification.steady_state import held_input
from agrobot.identification.vehicle import Vehicle
from agrobot.orchestrator.study import StudyError, load_study
from agrobot.studies import shipped

STEADY = 0.5                 # s the steering input is held before a turn's sample counts as steady
LINEAR_LATERAL = 2.0         # m/s2 (0.2 g): a steady turn below it is in any tyre's linear range
MIN_TURNS = 15               # samples of steady linear turning needed to read a wheelbase
MISMATCH = math.log(1.3)     # the log's turns and the study's wheelbase more than 30 % apart: named before any verdict
SIZE = math.log(1.3)         # a shipped study is suggested only for a vehicle of its size: within 30 % of the log's
                             # wheelbase and of the declared length and width
MASS = math.log(2.0)         # and within a factor 2 of the declared mass (a class's masses spread wider than its lengths)


def driving(v: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """The samples ``ok`` moving forward above max(0.2 m/s, a tenth of their speed's 90th percentile)."""
    return ok & (v > max(0.2, 0.1 * float(np.percentile(v[ok], 90)))) if ok.any() else ok


def steady_turns(frame, wheelbase: float | None = None) -> dict | None:
    """The log's steady turns in the tyres' linear range (None: no v, yaw_rate and delta or
    delta_cmd, or under 50 moving samples): samples whose steering input has been held for STEADY s
    (the yaw rate has settled; identification.steady_state.held_input, the rule of the steady-state
    regression's windows), |input| above 0.03 rad, turning
    the input's way, with both the measured |v r| and the kinematic v^2 tan|delta| / L (L: the
    study's ``wheelbase`` when given) under LINEAR_LATERAL. Selected on the input as well as the
    yaw rate: a tyre that saturates turns less, and turns selected on the yaw rate alone lengthen
    the wheelbase read from them. Each gives L_i = v tan|delta| / |r| (= L + K v^2 in steady
    cornering). Returns {from, v, L_i, moving speeds, steering}. It reads the wheelbase the turns
    give, which measurements.steering_scale.turn_slope (the angle's scale, the yaw rate's slope on
    v delta / L over all the turns) does not: a steering angle's scale is judged there."""
    steer = "delta" if "delta" in frame else "delta_cmd" if "delta_cmd" in frame else None
    if steer is None or "v" not in frame or "yaw_rate" not in frame or "t" not in frame:
        return None
    t, v, d, r = (frame[c].to_numpy(float) for c in ("t", "v", steer, "yaw_rate"))
    moving = driving(v, np.isfinite(v) & np.isfinite(d) & np.isfinite(r))
    if moving.sum() < 50:
        return None
    held = held_input(d, np.zeros(len(d), int), max(2, int(round(STEADY / float(np.median(np.diff(t)))))))
    with np.errstate(invalid="ignore"):
        kin = v ** 2 * np.tan(np.abs(d)) / wheelbase if wheelbase else np.zeros_like(v)
        sel = (moving & held & (np.abs(d) > 0.03) & (np.sign(d) == np.sign(r))
               & (np.abs(r) > 0.01) & (np.abs(v * r) < LINEAR_LATERAL) & (kin < LINEAR_LATERAL))
    return {"from": steer, "v": v[sel], "L_i": v[sel] * np.tan(np.abs(d[sel])) / np.abs(r[sel]),
            "moving_speed": v[moving], "steering": np.abs(d[moving]), "lateral": np.abs(v * r)[moving]}


def log_vehicle(frame, wheelbase: float | None = None, understeer: float = 0.0) -> dict | None:
    """{wheelbase, speed_range (10-90th percentiles), steering_range (99th percentile of |input|),
    lateral_acceleration_p99, ...} of the log's vehicle while moving, its wheelbase from its steady turns
    (steady_turns; ``wheelbase``, ``understeer``: the study's L and K): the wheelbase that with
    the study's K gives each turn's L_i = L + K v^2, the median over the turns; ``wheelbase`` None
    with ``why`` when fewer than MIN_TURNS samples are steady linear turns. None: no turning
    channels or too little driving."""
    turns = steady_turns(frame, wheelbase)
    if turns is None:
        return None
    v = turns["moving_speed"]
    out = {"from": turns["from"], "samples": int(len(turns["L_i"])),
           "lateral_acceleration_p99": float(np.percentile(turns["lateral"], 99)),
           "speed_range": [float(np.percentile(v, 10)), float(np.percentile(v, 90))],
           "steering_range": float(np.percentile(turns["steering"], 99))}
    if len(turns["L_i"]) < MIN_TURNS:
        return {**out, "wheelbase": None,
                "why": (f"{len(turns['L_i'])} samples of steady turning under {LINEAR_LATERAL:g} m/s2 (need "
                        f"{MIN_TURNS}): the log's turns are too brief or too hard (tyres past their linear range) "
                        f"to tell its wheelbase")}
    each = turns["L_i"] - understeer * turns["v"] ** 2
    wheel = float(np.median(each))
    return {**out, "wheelbase": wheel, "wheelbase_interval": list(median_interval(each)),
            "turn_speeds": [float(np.percentile(turns["v"], 10)), float(np.percentile(turns["v"], 90))]}


def median_interval(x: np.ndarray) -> tuple[float, float]:
    """The 95 % interval of the median of ``x``: its standard error sqrt(pi / 2) std / sqrt(n_eff),
    n_eff the samples' effective size (estimation.effective_size: consecutive samples of one turn
    are not independent)."""
    sd = math.sqrt(math.pi / 2) * float(np.std(x)) / math.sqrt(max(effective_size(x), 1.0))
    return interval(float(np.median(x)), sd)


def study_check(frame, wheelbase: float, study_name: str, understeer: float = 0.0,
                declared: Vehicle | None = None, mass: float | None = None) -> tuple[dict | None, str | None]:
    """(the log's vehicle, a warning) when its wheelbase is off the study's by more than MISMATCH in
    log ratio, naming a shipped study of the declared vehicle's class and size (suggestion) or,
    when none is, what study to write; (vehicle, None) otherwise. ``understeer``: the study's K
    [rad/(m/s2)], allowed for in each turn; ``declared``: the study's [vehicle] table, ``mass``
    [kg] its plant's (None: no vehicle declared, a study matched on the log's wheelbase alone)."""
    mine = log_vehicle(frame, wheelbase, understeer)
    if mine is not None:
        mine |= {"study_wheelbase": float(wheelbase), "linear_lateral": LINEAR_LATERAL}
    if mine is None or not (mine["wheelbase"] or 0.0) > 0:
        return mine, None
    off = abs(math.log(mine["wheelbase"] / wheelbase))
    if off <= MISMATCH:
        return mine, None
    ratio = wheelbase / mine["wheelbase"]
    text = (f"the log's turns are not the study's vehicle: wheelbase {mine['wheelbase']:.3g} m from "
            f"v tan({mine['from']}) / yaw_rate in {mine['samples']} samples of steady turns under "
            f"{LINEAR_LATERAL:g} m/s2 (at {mine['turn_speeds'][0]:.2g}-{mine['turn_speeds'][1]:.2g} m/s, the study's "
            f"understeer allowed for; a steering map's gain lengthens it; the log's speeds {mine['speed_range'][0]:.3g}-{mine['speed_range'][1]:.3g} m/s, "
            f"|{mine['from']}| up to {math.degrees(mine['steering_range']):.3g} deg) against the study's {study_name} "
            f"{wheelbase:.3g} m ({100 * (ratio - 1):+.0f} %): either the study is another vehicle, or its steering "
            f"map is off (the wheels turn {ratio:.2g} x the angle the log says; the steering_gain the verdict "
            f"judges tells)")
    mine["suggestion"] = suggestion(mine["wheelbase"], study_name, declared, mass)
    text += "; " + mine["suggestion"]
    mine["mismatch"] = text
    return mine, text


def suggestion(log_wheelbase: float, study_name: str, declared: Vehicle | None, mass: float | None,
               unfit: Callable[[ShippedVehicle], str] | None = None) -> str:
    """The shipped study to try for a log of wheelbase ``log_wheelbase`` whose study declares
    ``declared`` and ``mass``: of those not unlike it and able to do what the log shows (``unfit``:
    why a shipped vehicle cannot, '' when it can; given, the study's limits are what the log exceeds,
    so a steering map is not offered as the other reading), the nearest in size (nearness: wheelbase, outline
    and mass in log ratio; an exact tie goes to the first name, said), the others it passed over
    named; else what to write."""
    kind = declared.kind if declared is not None else None
    fits = sorted((round(nearness(c, log_wheelbase, declared, mass), 9), c.name, c) for c in shipped_vehicles()
                  if c.name != study_name and not unlike(c, log_wheelbase, declared, mass)
                  and not (unfit and unfit(c)))
    if fits:
        c = fits[0][2]
        basis = (f"a {c.kind} like the declared one" if kind else
                 "no vehicle class declared: matched on the log's wheelbase alone")
        return (f"studies/{c.name} (wheelbase {c.wheelbase:.3g} m), a {c.kind} of {c.length:g} x {c.width:g} m and "
                f"{c.mass:.3g} kg ({basis}), is of the log's size: try --study studies/{c.name}"
                + (f" (or any of the {len(c.same)} other shipped studies of this vehicle, e.g. studies/{c.same[0]}: "
                   f"they differ in what they simulate, not in the vehicle)" if c.same else "")
                + passed_over(fits, "the declared vehicle's" if declared is not None else "the log's wheelbase"))
    near = min(shipped_vehicles(), key=lambda c: (abs(math.log(log_wheelbase / c.wheelbase)), c.name))
    passed = (f" (the nearest in wheelbase, studies/{near.name} at {near.wheelbase:.3g} m, is "
              f"{unlike(near, log_wheelbase, declared, mass) or (unfit and unfit(near)) or 'the study given'})")
    outline = (declared.length, declared.width) if declared is not None else (None, None)
    table = (f'class = "{kind or "..."}", wheelbase = {log_wheelbase:.3g}'
             + (", length = {:g}, width = {:g}".format(*outline) if all(outline) else ", length, width"))
    either = "" if unfit else "if the study's wheelbase is the vehicle's, the steering map is the cause, else "
    return (f"no shipped study is of {'a ' + kind if kind else 'a vehicle'} of the log's size{passed}: {either}"
            f"write a study with the log's "
            f"wheelbase {log_wheelbase:.3g} m (its plant's l_f + l_r) and its [vehicle] table ({table})")


def nearness(c: ShippedVehicle, log_wheelbase: float, declared: Vehicle | None, mass: float | None) -> float:
    """How far shipped vehicle ``c`` is from the log's: sqrt(sum ((ln(mine / theirs)) / tol)^2) over
    the wheelbase (the log's), the declared length and width (tol SIZE) and mass (tol MASS; a
    class's masses spread wider than its lengths), each only where known: 1 is one tolerance off."""
    pairs = [(log_wheelbase, c.wheelbase, SIZE)]
    if declared is not None:
        pairs += [(declared.length, c.length, SIZE), (declared.width, c.width, SIZE), (mass, c.mass, MASS)]
    return math.sqrt(sum((math.log(mine / theirs) / tol) ** 2 for mine, theirs, tol in pairs if mine and theirs))


def passed_over(fits: list, against: str) -> str:
    """The studies of the vehicle's class and size not suggested, each with its nearness (the
    suggested one's first), and the tie-break when two are as near."""
    if len(fits) < 2:
        return ""
    tie = fits[1][0] == fits[0][0]
    return ("; passed over: " + ", ".join(f"studies/{n} ({d:.2f})" for d, n, _ in fits[1:])
            + f" (their distance from {against} size, wheelbase, outline and mass in log ratio over 30 % and x2: "
              f"studies/{fits[0][1]} {fits[0][0]:.2f}"
            + ("; as near: the first by name taken, --study names another" if tie else "") + ")")


@dataclass(frozen=True)
class ShippedVehicle:
    """A shipped study's vehicle: its [vehicle] table's class and outline, its plant's wheelbase and mass."""

    name: str
    kind: str
    wheelbase: float
    length: float
    width: float
    mass: float
    same: tuple[str, ...] = ()          # the other shipped studies of this very vehicle (they simulate other runs)


def unlike(c: ShippedVehicle, log_wheelbase: float, declared: Vehicle | None, mass: float | None) -> str:
    """Why shipped vehicle ``c`` is not the declared vehicle of wheelbase ``log_wheelbase`` ('' when
    it is): another class than the declared one, or a wheelbase, length or width more than SIZE
    off in log ratio, or a mass more than MASS off (the outline and mass only where declared)."""
    if declared is not None and declared.kind and c.kind != declared.kind:
        return f"a {c.kind}, not a {declared.kind}"
    pairs = [("wheelbase", log_wheelbase, c.wheelbase, SIZE, "m", "the log's")]
    if declared is not None:
        pairs += [("length", declared.length, c.length, SIZE, "m", "the declared"),
                  ("width", declared.width, c.width, SIZE, "m", "the declared"),
                  ("mass", mass, c.mass, MASS, "kg", "the study's")]
    return "; ".join(f"of {what} {theirs:.3g} {unit} against {whose} {mine:.3g} {unit}"
                     for what, mine, theirs, tol, unit, whose in pairs if mine and abs(math.log(mine / theirs)) > tol)


@lru_cache(maxsize=1)
def shipped_vehicles() -> tuple[ShippedVehicle, ...]:
    """One study per distinct vehicle among the shipped studies with a [vehicle] table and a yaw
    plant; studies of one vehicle (class, wheelbase, outline and mass all equal: nothing physical tells
    them apart) are one, named by the shortest name (figure8.toml for the paper's tractor), the others
    in its ``same``."""
    out: dict[tuple, ShippedVehicle] = {}
    for path in sorted(shipped().glob("*.toml"), key=lambda p: (len(p.name), p.name)):
        study = load_study(path)
        vehicle = Vehicle.of(study)
        if not vehicle.kind or not study.section("vehicle") or not vehicle.length or not vehicle.width:
            continue
        try:
            _, p = study_plant(study)
        except StudyError:                        # no yaw plant (a hardware layout, an emulator): no vehicle to fit
            continue
        c = ShippedVehicle(path.name, vehicle.kind, p.l_f + p.l_r, vehicle.length, vehicle.width, p.m)
        key = (c.kind, round(c.wheelbase, 3), c.length, c.width, round(c.mass, 1))
        out[key] = replace(out[key], same=out[key].same + (c.name,)) if key in out else c
    return tuple(out.values())
