"""The baseline model a diagnosis starts from, read from a study file through the Study API.

The steering enters the replay as its closed-loop first-order equivalent
(components.models.steering_equivalent), the yaw dynamics as the study's plant model at the
measured speed, driven by the wheel angle or its tangent (the plant's ``steering_geometry``,
components.tractor_yaw_plant.steer_input: the ``--steering-geometry`` option, else the study's
own, else the one ``identify`` chose on the same log, tan in the kinematic regime, else w; said
with what it passed over); every effect of the catalogue reads its own parameters' baseline
values (diagnosis.effect). Components are found by their declared roles.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from agrobot.components.models.steering_equivalent import FirstOrderSteering
from agrobot.components.models.yaw_dynamics import PHYSICAL_MODELS, TractorParameters
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study, StudyError

from agrobot.estimation import REPORTED_AT_BOUND, Z95
from agrobot.identification.vehicle import Vehicle

from .catalogue import CATALOGUE
from .effect import BaselineStudy, Parameter
from .plausibility import KINEMATIC, slip_share, study_understeer, understeer

ROLES = ("steering", "yaw_plant", "gps", "gyro")       # the first two are required


@dataclass(frozen=True)
class Baseline:
    """Every value the replay needs, SI units; ``values`` holds the extension parameters."""

    study_path: Path | None
    components: dict[str, str]                  # role -> component name in the study
    yaw_model: str
    tractor: TractorParameters
    values: dict[str, float] = field(default_factory=dict)
    study: BaselineStudy | None = None
    vehicle: Vehicle = field(default_factory=Vehicle)
    steering_geometry: str = "w"                # the plant's: "w" (delta drives the yaw model) or "tan"
    geometry_declared: bool = False             # the study sets steering_geometry itself


def baseline_from_study(study: Study) -> Baseline:
    model = resolve(study)
    found: dict[str, str] = {}
    for role in ROLES:
        names = model.find(role=role)
        if names:
            found[role] = names[0]
    for role in ROLES[:2]:
        if role not in found:
            raise StudyError(f"{study.where}: components: the diagnosis needs a component with role {role!r}; "
                             f"found {sorted(study.components)}")
    view = BaselineStudy(model, found)
    tp = view.parameters("yaw_plant")
    if tp["model"] not in PHYSICAL_MODELS:
        raise StudyError(f"{study.where}: components.{found['yaw_plant']}.parameters.model: the diagnosis needs a "
                         f"physical yaw model {PHYSICAL_MODELS}, got {tp['model']!r}")
    values = {"steering_time_constant": FirstOrderSteering.of(view.parameters("steering")).time_constant,
              "cornering_front_scale": 1.0, "cornering_rear_scale": 1.0, "relaxation_scale": 1.0}
    for effect in CATALOGUE:
        values.update(effect.baseline(view))
    spec = study.components.get(found["yaw_plant"])
    declared = spec is not None and "steering_geometry" in spec.parameters
    return Baseline(study.path, found, tp["model"], TractorParameters.of(tp), values, view, Vehicle.of(study),
                    str(tp.get("steering_geometry", "w")), declared)


def widened_ranges(params, values) -> dict[str, Parameter]:
    """{name: the parameter with the range widened to its limit} for each of ``params`` whose
    value ended on a prior bound that is not the limit (Parameter.widened)."""
    return {p.name: w for p in params if (w := p.widened(values[p.name])) is not None}


TYRE_SCALES = ("cornering_front_scale", "cornering_rear_scale", "relaxation_scale")
CORNERING_SCALES = TYRE_SCALES[:2]


def replay_lateral(replay) -> tuple[np.ndarray, float] | None:
    """(the moving samples, the lateral acceleration |v r| at their 99th percentile [m/s2]) of the
    replayed log; None under 50 moving samples with a gyro."""
    moving = np.isfinite(replay.speed) & (replay.speed > replay.min_speed) & np.isfinite(replay.gyro)
    if moving.sum() < 50:
        return None
    return moving, float(np.percentile(np.abs(replay.speed * replay.gyro)[moving], 99))


def replay_slip_share(replay) -> float | None:
    """plausibility.slip_share of the replayed log (None without a moving yaw stage)."""
    seen = replay_lateral(replay) if "yaw" in replay.stages else None
    if seen is None:
        return None
    moving, lateral = seen
    steering = float(np.nanpercentile(np.abs(replay.delta[moving]), 99))
    return slip_share(replay.baseline.tractor, lateral, steering)


@dataclass(frozen=True)
class Hold:
    """Why the baseline refit holds a parameter at the study's: ``kind`` (the rule) and ``detail``
    (its numbers); refit_statement groups the parameters held by one kind."""

    kind: str
    detail: str

    def as_dict(self) -> dict[str, str]:
        return {"kind": self.kind, "detail": self.detail}


KINEMATIC_HELD = Hold("the kinematic regime", "not identifiable at these speeds")
IMPLAUSIBLE = "implausible for the vehicle"     # Hold.kind of cornering scales the class does not have
PINNED = 0.5        # a refitted value the log pins: its 95 % interval within +-50 % of it


def held_tyres(replay) -> dict[str, Hold]:
    """{name: why} of the tyre scales the baseline refit holds at the study's: all of them on a log
    in the kinematic regime (slip_share below KINEMATIC: the yaw rate does not fix them, and freed
    they would take up a steering map's error as oversteer), none otherwise."""
    share = replay_slip_share(replay)
    return dict.fromkeys(TYRE_SCALES, KINEMATIC_HELD) if share is not None and share < KINEMATIC else {}


def unpinned(fit) -> dict[str, Hold]:
    """{name: why} of a refit's free parameters the log does not pin (estimation's covariance rule):
    a 95 % interval wider than PINNED x the value, none (on its bound) or infinite (the residuals do
    not depend on it). Moved, such a value is no estimate but whatever else the model lacks (a
    steering map's gain taken up as tyres): the refit holds it at the study's."""
    out = {}
    for p in fit.free:
        value, half = fit.values[p.name], Z95 * fit.std(p.name)
        if half <= PINNED * abs(value):
            continue
        out[p.name] = Hold("not pinned by the log", f"95 % interval +-{half:.2g} about {value:.3g}" if math.isfinite(half)
                           else "it ended on its bound" if math.isnan(half) else "the residuals do not depend on it")
    return out


def implausible_tyres(replay, values: dict[str, float], free) -> dict[str, Hold]:
    """{name: why} of the ``free`` cornering scales when with ``values`` they give the study's vehicle
    an understeer gradient K = m/L (l_r / (s_f C_f) - l_f / (s_r C_r)) its class does not have
    (plausibility.understeer): a steering map's gain or a wrong wheelbase taken up as tyres; else
    empty."""
    p = replay.baseline.tractor
    names = [n for n in CORNERING_SCALES if n in free]
    if not names:
        return {}
    sf, sr = values["cornering_front_scale"], values["cornering_rear_scale"]
    K = study_understeer(p, sf, sr)
    why = understeer(K, replay.baseline.vehicle, None)
    return dict.fromkeys(names, Hold(IMPLAUSIBLE, f"at {sf:.3g} and {sr:.3g}, {why}")) if why else {}


def refit_summary(start: dict[str, float], fitted: dict[str, float], params, held=()) -> list[dict]:
    """What the baseline refit did to each re-fitted parameter: its study value, the value fitted,
    whether it moved (by 2 % or more), the range it was searched in, and the bound it ended on
    (``at_bound``: 'lower'/'upper' of the last range searched, within 0.5 % of it; then the value is
    no estimate: the log does not fix it)."""
    why = held if isinstance(held, dict) else dict.fromkeys(held, KINEMATIC_HELD)
    out = []
    for p in (p for p in params if p.name not in why):
        a, b = float(start[p.name]), float(fitted[p.name])
        edge = p.at_bound(b, REPORTED_AT_BOUND)
        out.append({"name": p.name, "study": a, "value": b, "unit": p.unit,
                    "moved": abs(b - a) > 0.02 * max(abs(a), 1e-9), "bounds": [p.lower, p.upper], "at_bound": edge})
    by_name = {p.name: p for p in params}
    return out + [{"name": n, "study": float(start[n]), "value": float(fitted[n]),
                   "unit": by_name[n].unit if n in by_name else "1", "moved": False,
                   "bounds": [by_name[n].lower, by_name[n].upper] if n in by_name else [], "at_bound": None,
                   "held": w.as_dict()} for n, w in why.items()]


def refit_statement(summary: list[dict]) -> str:
    """One line: the parameters the refit moved and those that ended on a bound."""
    moved = ", ".join(f"{r['name']} {r['study']:.3g} -> {r['value']:.3g}" for r in summary if r["moved"]) or "none"
    edge = [r for r in summary if r["at_bound"]]
    text = f"the baseline refit moved {moved}"
    held = [(r["name"], r["held"]["kind"], r["held"]["detail"]) for r in summary if r.get("held")]
    for kind in dict.fromkeys(k for _, k, _ in held):
        mine = [(n, d) for n, k, d in held if k == kind]
        if len({d for _, d in mine}) == 1:
            text += f"; held at the study's ({kind}: {mine[0][1]}): {', '.join(n for n, _ in mine)}"
        else:
            text += f"; held at the study's ({kind}): " + ", ".join(f"{n} ({d})" for n, d in mine)
    if edge:
        text += ("; ended on a bound (no estimate: the log does not fix them, their values are not concluded): "
                 + ", ".join(f"{r['name']} on its {r['at_bound']} bound {r['bounds'][r['at_bound'] == 'upper']:.3g}"
                             for r in edge))
    return text


GEOMETRIES = ("auto", "w", "tan")
SHOWN = {"w": "delta", "tan": "tan(delta)"}
SETS = "--steering-geometry w|tan or the study's yaw plant steering_geometry sets it"


def fixed_geometry(option: str, baseline) -> tuple[str | None, str]:
    """(geometry or None, where from): the option's when not auto, else the study's when it declares
    one; None leaves it to identify (or the plant's default)."""
    if option not in GEOMETRIES:
        raise ValueError(f"--steering-geometry {option!r}: expected one of {', '.join(GEOMETRIES)}")
    if option != "auto":
        return option, f"--steering-geometry {option}"
    if baseline.geometry_declared:
        return baseline.steering_geometry, f"the study's yaw plant steering_geometry = {baseline.steering_geometry!r}"
    return None, ""


def identify_note(report: dict) -> str:
    """Why identify's report chose its geometry, from its ``steering_geometry_choice`` (not its notes'
    wording): the option, the wheel angle's reach below where tan w exceeds w by 1 %, both geometries'
    yaw RMS (the one passed over named), the kinematic regime's model; '' when it says none."""
    c = report.get("steering_geometry_choice") or {}
    how, shown = c.get("how"), {"w": "w", "tan": "tan w"}
    if how == "option":
        return f"the yaw plant is driven by {c['value']} (--steering-geometry {c['value']})"
    if how == "small_angles":
        return (f"the wheel angle reaches {c['reach']:.2g} rad (99th percentile), under {c['threshold']:.2g} rad "
                f"where tan w exceeds w by 1 %: the two alike, w kept")
    if how == "compared":
        value, other = c["value"], c["passed_over"]
        return (f"the wheel angle reaches {c['reach']:.2g} rad (99th percentile), where tan w exceeds w by "
                f"{100 * (math.tan(c['reach']) / c['reach'] - 1):.0f} %: the yaw plant is driven by {shown[value]} "
                f"(yaw RMS {c['rms'][value]:.3g} rad/s); passed over: {shown[other]} (RMS {c['rms'][other]:.3g} rad/s); "
                f"--steering-geometry w|tan sets it")
    if how == "kinematic" or report.get("final_model") == "kinematic":
        return "the kinematic regime, whose model is r = v tan(delta) / L"
    return ""


def geometry_choice(baseline, fixed: str | None, source: str, identified: str | None, why: str = "") -> dict:
    """{value, from, passed_over, says}: ``fixed`` (from ``source``) if given, else ``identified``
    (identify's, ``why`` its reason), else the baseline's."""
    default = baseline.steering_geometry
    if fixed is not None:
        value, origin = fixed, source
    elif identified in ("w", "tan"):
        value, origin = identified, "as identify chose on this log" + (f": {why}" if why else "")
    else:
        value, origin = default, "the study's default (identify did not choose one)"
    other = "w" if value == "tan" else "tan"
    if fixed is None and identified in ("w", "tan") and "passed over" in why:     # identify's line says both
        says = f"steering geometry: the diagnosis's yaw model {origin} (or the study's yaw plant steering_geometry)"
    else:
        says = (f"steering geometry: the yaw model is driven by {SHOWN[value]} ({origin}); passed over: "
                f"{SHOWN[other]}{' (the study default)' if other == default and fixed is None else ''}; {SETS}")
    return {"value": value, "from": origin, "passed_over": other, "says": says}


def with_geometry(baseline, geometry: str):
    """The baseline with its yaw model driven under ``geometry``."""
    return baseline if geometry == baseline.steering_geometry else replace(baseline, steering_geometry=geometry)
