"""The steering geometry the diagnosis's baseline drives its yaw model with: the wheel angle delta
("w") or tan(delta) ("tan": the turn without slip r = v tan(delta) / L at any lock; the yaw plant's
``steering_geometry``, components.tractor_yaw_plant.steer_input).

In this order: the ``--steering-geometry`` option (w or tan); the study's own (its yaw plant sets
``steering_geometry``); the one ``identify`` chose on the same log (identification.ordinary_driving:
tan in the kinematic regime, else the smaller residual where the wheel angle is large); the plant's
default, w. The choice is said with what it passed over and what sets it.
"""
from __future__ import annotations

from dataclasses import replace

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
    """Why identify's report chose its geometry: its own line on it (its yaw RMS under both, without
    the prefix), the kinematic regime's model, or ''."""
    for note in report.get("notes") or ():
        if note.startswith("steering geometry:"):
            return note.removeprefix("steering geometry:").strip()
    return "the kinematic regime, whose model is r = v tan(delta) / L" if report.get("final_model") == "kinematic" else ""


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
