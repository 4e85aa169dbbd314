"""SSP 1.0 archives (``.ssp``) and System Structure Descriptions (``.ssd``) as studies.

Each ``ssd:Component`` of the top-level system becomes a component whose type is its FMU (from
the archive, extracted once per process), with the values of its inline ParameterBindings
(converted to the FMU variable's unit by BaseUnit when the binding states another); each
``ssd:Connection`` between two elements becomes a connection. Start and stop time come from
DefaultExperiment; base step, component steps and roles, seed and analysis from the orchestrator's
own annotation (STUDY_ANNOTATION) when present, otherwise the base step is the smallest FMU default
step size and each component steps at its FMU's default step size when that is a multiple of it.
Not read (refused with a message naming them): nested systems, connections to the system's own
connectors, parameter bindings in external files.
"""
from __future__ import annotations

import os
import posixpath
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path
from typing import Any

from .errors import InputError
from .fmu_description import base_units, inspect_fmu, variable_unit
from .fmu_unpack import unpack
from .units import base_unit

NS = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
      "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
      "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues"}
STUDY_ANNOTATION = "org.cosim-orchestrator.study"   # the study fields SSP 1.0 has no element for
_EXTRACTED: dict[Path, Path] = {}


class SSPError(InputError):
    """The SSP cannot be read as a study (the message names the file, the element and why)."""


ALLOW_OUTSIDE = "SSP_ALLOW_OUTSIDE_PATHS"      # =1: an archive's components may name FMUs outside it


def _extract(path: Path) -> Path:
    """The folder an .ssp archive is unpacked to (once per process, removed at exit): its
    SystemStructure.ssd and the FMUs its components name, nothing else (orchestrator.fmu_unpack)."""
    path = path.resolve()
    if path not in _EXTRACTED:
        if not zipfile.is_zipfile(path):
            raise SSPError(f"{path}: not an SSP archive (not a zip file)")
        with zipfile.ZipFile(path) as zf:
            if "SystemStructure.ssd" not in zf.namelist():
                raise SSPError(f"{path}: no SystemStructure.ssd in the archive")
            try:
                root = ET.fromstring(zf.read("SystemStructure.ssd"))
            except ET.ParseError as exc:
                raise SSPError(f"{path}: SystemStructure.ssd: not readable XML: {exc}") from None
        used = {posixpath.normpath(c.get("source") or "") for c in root.iter(f"{{{NS['ssd']}}}Component")}
        _EXTRACTED[path] = unpack(path, lambda name: name == "SystemStructure.ssd" or name in used, "SSP")
    return _EXTRACTED[path]


def _annotation(element, tag: str):
    for ann in element.findall("ssd:Annotations/ssc:Annotation", NS):
        if ann.get("type") == STUDY_ANNOTATION:
            return ann.find(tag)
    return None


def _fmu_facts(fmu: Path) -> tuple[float | None, dict[str, tuple[str, Any]]]:
    """(default step size, variable name -> (unit, BaseUnit or None)) of an FMU."""
    md = inspect_fmu(fmu)
    bases = base_units(md)
    units = {}
    for v in md.modelVariables:
        unit = variable_unit(v)
        units[v.name] = (unit, bases.get(unit))
    step = md.defaultExperiment.stepSize if md.defaultExperiment is not None else None
    return (float(step) if step else None), units


def _value(where: str, param, fmu_unit: tuple[str, Any] | None) -> Any:
    for kind in ("Real", "Integer", "Boolean", "String", "Enumeration"):
        el = param.find(f"ssv:{kind}", NS)
        if el is None:
            continue
        raw = el.get("value")
        if kind == "Real":
            value, unit = float(raw), el.get("unit")
            if unit and fmu_unit is not None and unit != fmu_unit[0]:
                a, b = base_unit(unit), fmu_unit[1] or base_unit(fmu_unit[0])
                if a is None or b is None or a.exponents != b.exponents:
                    raise SSPError(f"{where}: value in {unit!r} for a variable in {fmu_unit[0]!r}")
                value = ((a.factor * value + a.offset) - b.offset) / b.factor
            return value
        if kind in ("Integer", "Enumeration"):
            return int(raw) if kind == "Integer" else raw
        if kind == "Boolean":
            return raw.strip().lower() in ("true", "1")
        return raw
    raise SSPError(f"{where}: no value element")


def study_data(path: str | Path) -> dict[str, Any]:
    """The study (as a study file's dict) an .ssp or .ssd describes."""
    path = Path(path)
    if not path.exists():
        raise SSPError(f"{path}: no such file")
    root_dir = _extract(path) if path.suffix == ".ssp" else path.resolve().parent
    ssd_path = root_dir / "SystemStructure.ssd" if path.suffix == ".ssp" else path
    try:
        root = ET.parse(ssd_path).getroot()
    except ET.ParseError as exc:
        raise SSPError(f"{ssd_path}: not readable XML: {exc}") from None
    system = root.find("ssd:System", NS)
    if system is None:
        raise SSPError(f"{path}: SystemStructure.ssd has no ssd:System")
    if system.find("ssd:Elements/ssd:System", NS) is not None:
        raise SSPError(f"{path}: nested systems are not supported (flatten the system into components)")
    study_ann = _annotation(root, "study")
    components: dict[str, dict[str, Any]] = {}
    steps: dict[str, float | None] = {}
    for comp in system.findall("ssd:Elements/ssd:Component", NS):
        name, source = comp.get("name"), comp.get("source")
        where = f"{path}: ssd:Component {name!r}"
        if not source:
            raise SSPError(f"{where}: no source")
        fmu = (root_dir / source).resolve()
        if path.suffix == ".ssp" and root_dir.resolve() not in fmu.parents and os.environ.get(ALLOW_OUTSIDE) != "1":
            raise SSPError(f"{where}: source {source!r} lies outside the archive; an SSP's FMUs are read from inside "
                           f"it ({ALLOW_OUTSIDE}=1 lets an archive you trust name files elsewhere)")
        default_step, units = _fmu_facts(fmu)
        parameters = {}
        for binding in comp.findall("ssd:ParameterBindings/ssd:ParameterBinding", NS):
            if binding.get("source"):
                raise SSPError(f"{where}: parameter bindings in external files ({binding.get('source')}) "
                               f"are not supported; put the values inline")
            for param in binding.findall("ssd:ParameterValues/ssv:ParameterSet/ssv:Parameters/ssv:Parameter", NS):
                pname = param.get("name")
                parameters[pname] = _value(f"{where}: parameter {pname!r}", param, units.get(pname))
        spec: dict[str, Any] = {"type": str(fmu)}
        if parameters:
            spec["parameters"] = parameters
        ann = _annotation(comp, "component")
        steps[name] = float(ann.get("step")) if ann is not None and ann.get("step") else default_step
        if ann is not None and ann.get("roles"):
            spec["roles"] = ann.get("roles").split()
        components[name] = spec
    connections = []
    for conn in system.findall("ssd:Connections/ssd:Connection", NS):
        a, b = conn.get("startElement"), conn.get("endElement")
        if not a or not b:
            raise SSPError(f"{path}: ssd:Connection {conn.get('startConnector')} -> {conn.get('endConnector')}: "
                           f"connections to the system's own connectors are not supported")
        connections.append(f"{a}.{conn.get('startConnector')} -> {b}.{conn.get('endConnector')}")
    experiment = root.find("ssd:DefaultExperiment", NS)
    start = float(experiment.get("startTime", 0.0)) if experiment is not None else 0.0
    stop = float(experiment.get("stopTime")) if experiment is not None and experiment.get("stopTime") else None
    if stop is None:
        raise SSPError(f"{path}: no DefaultExperiment stopTime; give one with --set study.stop_time=...")
    known = [s for s in steps.values() if s]
    base = float(study_ann.get("base_step")) if study_ann is not None else (min(known) if known else 0.01)
    for name, step in steps.items():
        if step and abs(step / base - round(step / base)) < 1e-9:
            components[name]["step"] = step
    study = {"name": root.get("name", path.stem), "description": root.get("description", ""), "start_time": start,
             "stop_time": stop, "base_step": base,
             "seed": int(study_ann.get("seed")) if study_ann is not None and study_ann.get("seed") else 0}
    if study_ann is not None and study_ann.get("analysis"):
        study["analysis"] = study_ann.get("analysis")
    return {"study": study, "components": components, "connections": connections}
