"""Co-simulation FMUs (FMI 2.0 and 3.0, through fmpy) behind the component contract.

A study names an FMU by path (``type = "fmus/plant.fmu"``, relative to the study file). Ports,
units and start values come from ``modelDescription.xml``; parameters are set after instantiation,
before initialisation; outputs are read after initialisation (propagated at t0). One instance is
kept per component and ``reset()`` between runs.

Stepping semantics:
- by default an FMU is *continuous*: ``doStep(t, dt)`` integrates with the inputs of t and its
  outputs describe t + dt (no direct feedthrough);
- an FMU whose modelDescription carries a vendor annotation ``<Tool name="T"><Sampled/></Tool>``,
  T a tool name a plugin registered (orchestrator.registry), is *sampled*: doStep computes its outputs from the
  inputs at t and they hold on [t, t + dt); feedthrough comes from ModelStructure's output
  dependencies (an exported controller is such an FMU).
Only Real/Float64 variables become ports (others are ignored).
"""
from __future__ import annotations

import zipfile
from pathlib import Path
from typing import Any

from .component import Component, ComponentError, Variable
from .errors import InputError

class FMUError(InputError):
    """The file cannot be used as a co-simulation component (message names file and reason)."""


def _binary_dir(fmi_version: str) -> str:
    import fmpy

    return fmpy.platform if fmi_version.startswith("2") else fmpy.platform_tuple


def inspect_fmu(path: Path):
    """Read and check an FMU: (model description, unzip-free checks done). Raises FMUError."""
    from fmpy import read_model_description, sharedLibraryExtension

    if not path.exists():
        raise FMUError(f"{path}: no such file")
    if not zipfile.is_zipfile(path):
        raise FMUError(f"{path}: not an FMU (not a zip archive)")
    with zipfile.ZipFile(path) as zf:
        names = set(zf.namelist())
    if "modelDescription.xml" not in names:
        raise FMUError(f"{path}: not an FMU (no modelDescription.xml in the archive)")
    try:
        md = read_model_description(str(path), validate=False)
    except Exception as exc:  # fmpy raises several kinds for a malformed description
        raise FMUError(f"{path}: modelDescription.xml cannot be read: {exc}") from None
    if md.fmiVersion not in ("2.0",) and not md.fmiVersion.startswith("3."):
        raise FMUError(f"{path}: FMI version {md.fmiVersion} is not supported (2.0 and 3.0 are)")
    if md.coSimulation is None:
        raise FMUError(f"{path}: a model-exchange-only FMU; co-simulation (FMI 2.0/3.0 CoSimulation) is required")
    ident = md.coSimulation.modelIdentifier
    binary = f"binaries/{_binary_dir(md.fmiVersion)}/{ident}{sharedLibraryExtension}"
    if binary not in names:
        have = sorted({n.split("/")[1] for n in names if n.startswith("binaries/") and n.count("/") >= 2})
        raise FMUError(f"{path}: no binary for this platform ({binary} missing; the FMU has "
                       f"{', '.join(have) or 'no binaries'})")
    return md


def _unit(variable) -> str:
    unit = getattr(variable, "unit", None)
    if not unit and getattr(variable, "declaredType", None) is not None:
        unit = getattr(variable.declaredType, "unit", None)
    return unit or "1"


def _is_real(variable) -> bool:
    return variable.type in ("Real", "Float64")


def _is_sampled(path: Path) -> bool:
    with zipfile.ZipFile(path) as zf:
        xml = zf.read("modelDescription.xml").decode("utf-8", "replace")
    from .registry import registry

    return "<Sampled" in xml and any(f'<Tool name="{tool}">' in xml for tool in registry().fmu_annotation_tools)


def fmu_component_class(path: str | Path) -> type["FMUComponent"]:
    """A Component subclass whose declared variables are the FMU's Real ports."""
    path = Path(path).resolve()
    md = inspect_fmu(path)
    variables, refs = [], {}
    for v in md.modelVariables:
        if not _is_real(v) or v.causality not in ("input", "output", "parameter"):
            continue
        start = float(v.start) if v.start is not None else 0.0
        variables.append(Variable(v.name, v.causality, _unit(v), start, v.description or ""))
        refs[v.name] = v.valueReference
    sampled = _is_sampled(path)
    feedthrough: dict[str, tuple[str, ...]] = {}
    if sampled:
        inputs = {v.name for v in md.modelVariables if v.causality == "input"}
        for unknown in md.outputs:
            deps = unknown.dependencies
            names = [d.name for d in deps] if deps is not None else sorted(inputs)
            feedthrough[unknown.variable.name] = tuple(n for n in names if n in inputs)
    attrs = {"variables": tuple(variables), "feedthrough": feedthrough, "sampled": sampled,
             "fmu_path": path, "model_description": md, "value_references": refs}
    return type(f"FMU_{md.modelName}", (FMUComponent,), attrs)


class FMUComponent(Component):
    """One FMU instance (created on first initialise, reset on later runs)."""

    fmu_path: Path
    model_description: Any
    value_references: dict[str, int]

    def __init__(self, name, parameters=None, rng=None) -> None:
        super().__init__(name, parameters, rng)
        self._slave = None
        self._unzipdir: str | None = None
        self.instantiations = 0

    def _create(self) -> None:
        from fmpy import extract
        from fmpy.fmi2 import FMU2Slave
        from fmpy.fmi3 import FMU3Slave

        md = self.model_description
        self._unzipdir = extract(str(self.fmu_path))
        cls = FMU2Slave if md.fmiVersion == "2.0" else FMU3Slave
        token = md.guid if md.fmiVersion == "2.0" else md.instantiationToken
        self._slave = cls(guid=token, unzipDirectory=self._unzipdir,
                          modelIdentifier=md.coSimulation.modelIdentifier, instanceName=self.name)
        self._slave.instantiate()
        self.instantiations += 1

    def _call(self, what: str, fn, *args):
        try:
            return fn(*args)
        except Exception as exc:     # fmpy raises FMICallException on a non-OK status
            raise ComponentError(f"{self.name}: FMU {self.fmu_path.name}: {what} failed ({exc})") from None

    def initialize(self, t0: float, dt: float) -> None:
        fmi2 = self.model_description.fmiVersion == "2.0"
        if self._slave is None:
            self._call("instantiate", self._create)
        else:
            self._call("reset", self._slave.reset)
        s, refs = self._slave, self.value_references
        set_real = s.setReal if fmi2 else s.setFloat64
        self._get = s.getReal if fmi2 else s.getFloat64
        self._set = set_real
        names = list(self.p)
        if names:
            self._call("setting parameters", set_real, [refs[n] for n in names], [float(self.p[n]) for n in names])
        if fmi2:
            self._call("setupExperiment", s.setupExperiment, None, t0)
            self._call("enterInitializationMode", s.enterInitializationMode)
        else:
            self._call("enterInitializationMode", lambda: s.enterInitializationMode(startTime=t0))
        self._in_names = list(self.u)
        self._in_refs = [refs[n] for n in self._in_names]
        if self._in_refs:
            self._call("setting inputs", set_real, self._in_refs, [float(self.u[n]) for n in self._in_names])
        self._call("exitInitializationMode", s.exitInitializationMode)
        self._out_names = list(self.y)
        self._out_refs = [refs[n] for n in self._out_names]
        self._read_outputs()

    def _read_outputs(self) -> None:
        if self._out_refs:
            values = self._call("reading outputs", self._get, self._out_refs)
            self.y.update(zip(self._out_names, values))

    def step(self, t: float, dt: float) -> None:
        u = self.u
        if self._in_refs:
            self._call("setting inputs", self._set, self._in_refs, [float(u[n]) for n in self._in_names])
        self._call(f"doStep at t = {t:.6g} s", self._slave.doStep, t, dt)
        self._read_outputs()

    def __del__(self) -> None:
        slave = getattr(self, "_slave", None)
        if slave is not None:
            try:
                slave.terminate()
                slave.freeInstance()
            except Exception:
                pass
