"""FMUs (FMI 2.0 and 3.0, co-simulation or model exchange, through fmpy) behind the component contract.

A study names an FMU by path (``type = "fmus/plant.fmu"``, relative to the study file). Everything
comes from ``modelDescription.xml``, read as the standard writes it (no vendor annotations):

- ports: every variable of causality input, output or parameter, of any type (FMI 2.0 Real,
  Integer, Boolean, String, Enumeration; FMI 3.0 Float32/64, (U)Int8..64, Boolean, String, Binary,
  Enumeration). An FMI 3.0 array is a whole port ``x`` (a numpy array) and element ports ``x[2]``
  or ``x[1,3]`` (1-based, as structured names write them); connect either. Clocks are refused by name;
- units: each port's unit with the BaseUnit of the FMU's UnitDefinitions; connections compare
  dimension and factor (orchestrator.units);
- timing, FMI's co-simulation semantics: at each instant t of its step the inputs of t are set and
  the outputs read (get after set), so outputs that ModelStructure declares dependent on inputs
  reflect the inputs of t; the orchestrator orders the FMU after their sources and refuses algebraic
  loops through them. After the instant is recorded, ``advance`` sets the inputs of t again (every
  value of t) and calls doStep(t, dt); a model-exchange FMU is integrated instead (scipy's RK45,
  state events located, time and step events handled). The first instant sets the inputs from
  their sources before anything is read, so inputs at the start time are the sources' values;
- a terminate request (fmi2Discard with fmi2Terminated, FMI 3.0 terminateSimulation, or an event
  update asking to terminate) ends the run cleanly (EndRun), reported in metrics.json as ``ended_by``.
One instance is kept per component and ``reset()`` between runs.

Imported where used: fmpy (start-up: 0.06 s on every command, which loads this module through the
component registry), scipy.integrate (start-up: 0.05 s; model-exchange FMUs only).
"""
from __future__ import annotations

import ctypes
import re
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .component import Component, ComponentError, EndRun, Variable
from .fmu_description import FMUError, base_units, inspect_fmu, variable_unit
from .fatal_calls import named, watch
from .fmu_process import RemoteSlave
from .fmu_unpack import fmu_entries, remove as remove_unpacked, unpack
from .study import Study, StudyError
from .units import BaseUnit


def _text(value="") -> str:       # (called without an argument: the empty string)
    """A String variable's value as text (fmpy returns bytes)."""
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)


# FMI type -> (fmpy accessor suffix, Python conversion)
_FMI2_TYPES = {"Real": ("Real", float), "Integer": ("Integer", int), "Enumeration": ("Integer", int),
               "Boolean": ("Boolean", bool), "String": ("String", _text)}
_FMI3_TYPES = {**{t: (t, float) for t in ("Float32", "Float64")},
               **{t: (t, int) for t in ("Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64")},
               "Enumeration": ("Int64", int), "Boolean": ("Boolean", bool), "String": ("String", _text),
               "Binary": ("Binary", bytes)}
CAUSALITIES = {"input": "input", "output": "output", "parameter": "parameter", "structuralParameter": "parameter"}


@dataclass(frozen=True)
class _FMIVar:
    """One FMI variable: its accessor type, value reference, shape (() for a scalar) and conversion."""

    name: str
    vr: int
    accessor: str
    convert: Any
    shape: tuple[int, ...]

    @property
    def size(self) -> int:
        return int(np.prod(self.shape)) if self.shape else 1

    def element_names(self) -> list[str]:
        return [f"{self.name}[{','.join(str(i + 1) for i in idx)}]" for idx in np.ndindex(*self.shape)] \
            if self.shape else []


def _shape(md, v, path: Path) -> tuple[int, ...]:
    dims = getattr(v, "dimensions", None) or []
    shape = []
    for d in dims:
        if d.start not in (None, ""):
            shape.append(int(d.start))
            continue
        ref = d.variable or next((w for w in md.modelVariables if w.valueReference == d.valueReference), None)
        if ref is None or ref.start in (None, ""):
            raise FMUError(f"{path}: array {v.name!r}: its dimension (value reference {d.valueReference}) has no size")
        shape.append(int(ref.start))
    return tuple(shape)


def _start(fv: _FMIVar, text) -> Any:
    if text is None:
        zero = fv.convert()          # 0.0, 0, False, "" or b''
        return np.full(fv.shape, zero, dtype=object if fv.convert in (_text, bytes) else None) if fv.shape else zero
    if fv.convert is _text:
        return _text(text)
    if fv.convert is bytes:
        try:
            return bytes.fromhex(str(text).removeprefix("0x")) if text else b""
        except ValueError:
            return str(text).encode()
    items = str(text).split() if fv.shape else [text]
    parse = (lambda s: str(s).lower() in ("true", "1")) if fv.convert is bool else \
        (lambda s: fv.convert(float(s)) if fv.convert is int else float(s))
    values = [parse(s) for s in items]
    if not fv.shape:
        return values[0]
    if len(values) == 1:
        values = values * fv.size
    return np.asarray(values).reshape(fv.shape)


def fmu_component_class(path: str | Path) -> type["FMUComponent"]:
    """A Component subclass whose declared variables are the FMU's ports (see module docstring)."""
    path = Path(path).resolve()
    md = inspect_fmu(path)
    fmi3 = not md.fmiVersion.startswith("2")
    types = _FMI3_TYPES if fmi3 else _FMI2_TYPES
    bases = base_units(md)
    variables, fmi_vars, port_units, ports_of = [], {}, {}, {}
    for v in md.modelVariables:
        causality = CAUSALITIES.get(v.causality)
        if causality is None:
            continue
        if v.type not in types:
            raise FMUError(f"{path}: variable {v.name!r} has type {v.type}, which this orchestrator cannot exchange")
        accessor, convert = types[v.type]
        fv = _FMIVar(v.name, v.valueReference, accessor, convert, _shape(md, v, path))
        fmi_vars[v.name] = (causality, fv)
        unit = variable_unit(v)
        start = _start(fv, v.start)
        names = [v.name] + fv.element_names()
        ports_of[v.name] = names
        # an FMU's input has the start value its modelDescription must give (FMI): left
        # unconnected it holds it, and the run says so (orchestrator.build)
        held = causality == "input"
        variables.append(Variable(v.name, causality, unit, start, v.description or "", held))
        for element, value in zip(fv.element_names(), np.asarray(start).ravel() if fv.shape else []):
            variables.append(Variable(element, causality, unit, value.item() if hasattr(value, "item") else value,
                                      f"element of {v.name}", held))
        if unit in bases:
            port_units.update({n: bases[unit] for n in names})
    inputs = [n for n, (c, _) in fmi_vars.items() if c == "input"]
    every_input = tuple(p for d in inputs for p in ports_of[d])
    # an output ModelStructure does not list (a malformed description) may depend on any input
    feedthrough: dict[str, tuple[str, ...]] = {p: every_input for n, (c, _) in fmi_vars.items() if c == "output"
                                                for p in ports_of[n]}
    for unknown in md.outputs:
        deps = unknown.dependencies
        dep_vars = [d.name for d in deps] if deps is not None else inputs     # no attribute: every input
        ports = tuple(p for d in dep_vars if d in inputs for p in ports_of[d])
        for name in ports_of.get(unknown.variable.name, []):
            feedthrough[name] = ports
    attrs = {"variables": tuple(variables), "feedthrough": feedthrough, "sampled": True,
             "fmu_path": path, "model_description": md, "fmi_vars": fmi_vars, "base_units": port_units,
             "model_exchange": md.coSimulation is None}
    return type(f"FMU_{re.sub(r'[^A-Za-z0-9_]', '_', md.modelName)}", (FMUComponent,), attrs)


class FMUComponent(Component):
    """One FMU instance (created on first initialise, reset on later runs)."""

    fmu_path: Path
    model_description: Any
    fmi_vars: dict[str, tuple[str, _FMIVar]]
    base_units: dict[str, BaseUnit]
    model_exchange: bool
    connected_inputs: frozenset[str] = frozenset()

    isolate: bool = False               # in a child process (orchestrator.fmu_process)
    call_timeout: float = 60.0          # s, for an isolated FMU's calls
    in_process_note: str = ""           # a foreign FMU the study keeps in this process: where it said so

    def __init__(self, name, parameters=None, rng=None) -> None:
        super().__init__(name, parameters, rng)
        self._slave = None
        self._unpacked = None
        self.instantiations = 0
        self._fmi3 = not self.model_description.fmiVersion.startswith("2")

    # --- instance --------------------------------------------------------------------------------
    def _create(self) -> None:
        import fmpy
        from fmpy.fmi2 import FMU2Model, FMU2Slave
        from fmpy.fmi3 import FMU3Model, FMU3Slave

        md = self.model_description
        kind = md.modelExchange if self.model_exchange else md.coSimulation
        classes = {(False, False): FMU2Slave, (False, True): FMU2Model, (True, False): FMU3Slave, (True, True): FMU3Model}
        cls = classes[(self._fmi3, self.model_exchange)]
        token = md.instantiationToken if self._fmi3 else md.guid
        self._unpacked = unpack(self.fmu_path, fmu_entries([fmpy.platform, fmpy.platform_tuple]), "FMU")
        kwargs = dict(guid=token, unzipDirectory=str(self._unpacked), modelIdentifier=kind.modelIdentifier,
                      instanceName=self.name)
        if self.isolate and not self.model_exchange:
            self._slave = RemoteSlave(cls.__name__, kwargs, f"{self.name}: FMU {self.fmu_path.name}", self.call_timeout)
        else:
            if self.isolate:
                print(f"note: {self.name}: a model-exchange FMU runs in this process (isolate_fmus isolates "
                      f"co-simulation FMUs)", file=sys.stderr)
            elif self.in_process_note:
                print(f"note: {self.name}: FMU {self.fmu_path.name} runs in this process, for speed "
                      f"({self.in_process_note}): a crash in it ends the run, named on stderr", file=sys.stderr)
            watch()
            self._slave = cls(**kwargs)
        self._slave.instantiate()
        self.instantiations += 1

    def _label(self, what: str) -> str:
        """The name a fatal signal's dump gives a call into this FMU (orchestrator.fatal_calls)."""
        return f"FMU component '{self.name}' ({self.fmu_path.name}): {what}"

    def _call(self, what: str, fn, *args):
        try:
            return fn(*args) if self.isolate else named(self._label(what), fn, *args)
        except EndRun:
            raise
        except Exception as exc:     # fmpy raises FMICallException on a non-OK status
            raise ComponentError(f"{self.name}: FMU {self.fmu_path.name}: {what} failed ({exc})") from None

    def _groups(self, causality: str) -> list[tuple[str, list[_FMIVar]]]:
        groups: dict[str, list[_FMIVar]] = {}
        for c, fv in self.fmi_vars.values():
            if c == causality:
                groups.setdefault(fv.accessor, []).append(fv)
        return list(groups.items())

    def _setters(self, what: str, groups):
        """Per accessor group: (setter, value references, variables, what the call does), built once."""
        s = self._slave
        return [(getattr(s, f"set{accessor}"), [f.vr for f in fvs], fvs, f"{what} ({', '.join(f.name for f in fvs)})")
                for accessor, fvs in groups if fvs]

    def _values(self, fvs, values_of) -> list:
        values = []
        for fv in fvs:
            value = values_of(fv)
            flat = np.asarray(value, dtype=object).ravel().tolist() if fv.shape else [value]
            if len(flat) != fv.size:
                raise ComponentError(f"{self.name}: {fv.name}: expected {fv.size} values, got {len(flat)}")
            values += [fv.convert(x) if fv.convert is not int else int(round(float(x))) for x in flat]
        return values

    def _write(self, setters, values_of, last: list | None = None) -> None:
        """Set every group's values; with ``last`` (one slot per group), a group whose values
        did not change since the last call is not set again."""
        for i, (setter, refs, fvs, what) in enumerate(setters):
            values = self._values(fvs, values_of)
            if last is not None:
                if last[i] == values:
                    continue
                last[i] = values
            self._call(what, setter, refs, values)

    def _input_value(self, fv: _FMIVar):
        u = self.u
        if not fv.shape or fv.name in self.connected_inputs:
            return u[fv.name]
        return np.asarray([u[e] for e in fv.element_names()], dtype=object).reshape(fv.shape)

    def _set_inputs(self) -> None:
        """The inputs of the instant: set once whether ``step`` or ``advance`` comes first."""
        self._write(self._in_setters, self._input_value, self._last_inputs)

    def _read_outputs(self) -> None:
        s, y = self._slave, self.y
        for accessor, fvs in self._out_groups:
            getter = getattr(s, f"get{accessor}")
            refs = [f.vr for f in fvs]
            total = sum(f.size for f in fvs)
            values = self._call("reading outputs", getter, refs, total) if self._fmi3 else \
                self._call("reading outputs", getter, refs)
            i = 0
            for fv in fvs:
                chunk = [fv.convert(x) if fv.convert is not bytes else x for x in values[i:i + fv.size]]
                i += fv.size
                if fv.shape:
                    y[fv.name] = np.asarray(chunk).reshape(fv.shape)
                    y.update(zip(fv.element_names(), chunk))
                else:
                    y[fv.name] = chunk[0]

    # --- life cycle ------------------------------------------------------------------------------
    def initialize(self, t0: float, dt: float) -> None:
        if self._slave is None:
            self._call("instantiate", self._create)
        else:
            self._call("reset", self._slave.reset)
        s = self._slave
        both = [n for n, (c, fv) in self.fmi_vars.items() if c == "input" and fv.shape
                and n in self.connected_inputs and any(e in self.connected_inputs for e in fv.element_names())]
        if both:
            raise ComponentError(f"input array {both[0]!r} is connected whole and by element; connect one or the other")
        starts = {v.name: v.start for v in self.variables}
        changed = [(acc, [fv for fv in fvs if not _equal(self.p[fv.name], starts[fv.name])])
                   for acc, fvs in self._groups("parameter")]
        self._write(self._setters("setting parameters", changed), lambda fv: self.p[fv.name])
        self._in_setters = self._setters("setting inputs", self._groups("input"))
        self._last_inputs = [None] * len(self._in_setters)
        self._out_groups = self._groups("output")
        if self._fmi3:
            self._call("enterInitializationMode", lambda: s.enterInitializationMode(startTime=t0))
        else:
            self._call("setupExperiment", s.setupExperiment, None, t0)
            self._call("enterInitializationMode", s.enterInitializationMode)
        self._set_inputs()
        self._call("exitInitializationMode", s.exitInitializationMode)
        if self.model_exchange:
            self._integrator = _ModelExchange(self, t0)
        self._read_outputs()

    def step(self, t: float, dt: float) -> None:
        """The outputs of t from the inputs of t (get after set)."""
        self._set_inputs()
        if self.model_exchange:
            self._integrator.inputs_changed(t)
        self._read_outputs()

    def advance(self, t: float, dt: float) -> None:
        """doStep(t, dt) with the inputs of t (or integrate, for model exchange)."""
        if self.isolate and not self.model_exchange:
            self._slave.at = f" at t = {t:.6g} s"
        self._set_inputs()
        if self.model_exchange:
            self._integrator.integrate(t, t + dt)
        elif self._fmi3:
            self._do_step3(t, dt)
        else:
            self._do_step2(t, dt)

    def _do_step2(self, t: float, dt: float) -> None:
        from fmpy.fmi1 import FMICallException
        from fmpy.fmi2 import fmi2Discard

        try:
            if self.isolate:
                self._slave.doStep(t, dt)
            else:
                named(self._label("doStep"), self._slave.doStep, t, dt)
        except FMICallException as exc:
            if exc.status == fmi2Discard and self._terminated2():
                raise EndRun(self.name, f"fmi2DoStep from t = {t:.6g} s returned fmi2Discard with fmi2Terminated") from None
            raise ComponentError(f"{self.name}: FMU {self.fmu_path.name}: doStep at t = {t:.6g} s failed ({exc})") from None

    def _terminated2(self) -> bool:
        from fmpy.fmi2 import fmi2Terminated

        try:
            return bool(self._slave.getBooleanStatus(fmi2Terminated))
        except Exception:        # noqa: BLE001 - an FMU that cannot tell has not asked to terminate
            return False

    def _do_step3(self, t: float, dt: float) -> None:
        from fmpy.fmi1 import FMICallException
        from fmpy.fmi3 import fmi3Boolean, fmi3Float64

        s = self._slave
        event, terminate, early, last = fmi3Boolean(), fmi3Boolean(), fmi3Boolean(), fmi3Float64()
        if self.isolate:
            failed, _, terminate.value, _, last.value = s.call("doStep3", t, dt)
            if failed is not None and not terminate.value:
                raise ComponentError(f"{self.name}: FMU {self.fmu_path.name}: doStep at t = {t:.6g} s failed "
                                     f"({FMICallException(*failed)})")
        else:
            try:
                named(self._label("doStep"), s.fmi3DoStep, s.component, t, dt, fmi3Boolean(True),
                      ctypes.byref(event), ctypes.byref(terminate), ctypes.byref(early), ctypes.byref(last))
            except FMICallException as exc:
                if not terminate.value:
                    raise ComponentError(f"{self.name}: FMU {self.fmu_path.name}: doStep at t = {t:.6g} s failed ({exc})") from None
        if terminate.value:
            raise EndRun(self.name, f"fmi3DoStep from t = {t:.6g} s set terminateSimulation "
                                    f"(last successful time {last.value:.6g} s)")

    def terminate(self) -> None:
        """Nothing to release between runs (the instance is reset and reused), unless the FMU's
        own process has ended (an isolated FMU that crashed, exited or hung): then its process
        and unpacked folder go now, not whenever the garbage collector reaches this object."""
        slave = getattr(self, "_slave", None)
        if slave is not None and hasattr(slave, "alive") and not slave.alive():
            self._release()

    def __del__(self) -> None:
        self._release()

    def _release(self) -> None:
        slave, self._slave = getattr(self, "_slave", None), None
        if slave is not None:
            try:
                slave.terminate()
            except Exception:
                pass
            try:
                slave.freeInstance()
            except Exception:
                pass
            if hasattr(slave, "close"):         # an isolated FMU: its process ends
                slave.close()
        remove_unpacked(getattr(self, "_unpacked", None))
        self._unpacked = None


def _equal(a, b) -> bool:
    try:
        return bool(np.all(np.asarray(a) == np.asarray(b)))
    except Exception:        # noqa: BLE001 - values that cannot be compared count as changed
        return False


class _ModelExchange:
    """Integrate a model-exchange FMU over communication intervals: scipy's RK45 with the event
    indicators as event functions (a sign change stops the integrator at the crossing), time events
    from the event update, step events from completedIntegratorStep; event iteration in event mode."""

    def __init__(self, comp: FMUComponent, t0: float) -> None:
        self.c, self.s, self.fmi3 = comp, comp._slave, comp._fmi3
        md = comp.model_description
        self.nx = len(md.derivatives)
        self.nz = int(getattr(md, "numberOfEventIndicators", None) or len(getattr(md, "eventIndicators", None) or []))
        self._x = (ctypes.c_double * max(self.nx, 1))()
        self._dx = (ctypes.c_double * max(self.nx, 1))()
        self._z = (ctypes.c_double * max(self.nz, 1))()
        self.next_time = np.inf
        self._event_iteration(t0)
        self.c._call("enterContinuousTimeMode", self.s.enterContinuousTimeMode)

    def _event_iteration(self, t: float) -> None:
        while True:
            info = self.c._call("event update", self.s.updateDiscreteStates if self.fmi3 else self.s.newDiscreteStates)
            needed, terminate, _, _, time_defined, next_time = info
            if terminate:
                raise EndRun(self.c.name, f"the model asked to terminate at its event update at t = {t:.6g} s")
            if not needed:
                break
        self.next_time = float(next_time) if time_defined else np.inf

    def _states(self) -> np.ndarray:
        if self.nx:
            self.s.getContinuousStates(self._x, self.nx)
        return np.frombuffer(self._x, dtype=float, count=self.nx).copy()

    def _put(self, t: float, x: np.ndarray) -> None:
        self.s.setTime(t)
        if self.nx:
            self._x[:self.nx] = x
            self.s.setContinuousStates(self._x, self.nx)

    def _derivatives(self, t: float, x: np.ndarray) -> np.ndarray:
        self._put(t, x)
        (self.s.getContinuousStateDerivatives if self.fmi3 else self.s.getDerivatives)(self._dx, self.nx)
        return np.frombuffer(self._dx, dtype=float, count=self.nx).copy()

    def _indicators(self, t: float, x: np.ndarray) -> np.ndarray:
        self._put(t, x)
        self.s.getEventIndicators(self._z, self.nz)
        return np.frombuffer(self._z, dtype=float, count=self.nz).copy()

    def inputs_changed(self, t: float) -> None:
        self.s.setTime(t)

    def _event(self, t: float) -> None:
        self.c._call("enterEventMode", self.s.enterEventMode)
        self._event_iteration(t)
        self.c._call("enterContinuousTimeMode", self.s.enterContinuousTimeMode)

    def integrate(self, t: float, t_end: float) -> None:
        from scipy.integrate import solve_ivp

        x = self._states()
        stalled = 0
        while t < t_end - 1e-12 * max(1.0, abs(t_end)):
            stop = min(t_end, self.next_time)
            state_event = False
            if self.nx:
                z0 = self._indicators(t, x) if self.nz else np.zeros(0)
                events = []
                for i in range(self.nz):
                    def crossing(tt, xx, i=i):
                        return self._indicators(tt, xx)[i]
                    crossing.terminal = True
                    # leave the side the indicator is on now (an indicator at zero after an event
                    # is not a new crossing)
                    crossing.direction = -1.0 if z0[i] >= 0 else 1.0
                    events.append(crossing)
                sol = solve_ivp(self._derivatives, (t, stop), x, method="RK45", rtol=1e-8, atol=1e-10,
                                events=events or None)
                if sol.status == -1:
                    raise ComponentError(f"{self.c.name}: integration failed at t = {t:.6g} s: {sol.message}")
                stalled = stalled + 1 if float(sol.t[-1]) <= t else 0
                if stalled > 100:
                    raise ComponentError(f"{self.c.name}: events without progress at t = {t:.6g} s (chattering)")
                t, x = float(sol.t[-1]), sol.y[:, -1]
                state_event = sol.status == 1
            else:
                t = stop
            self._put(t, x)
            step_event, terminate = self.s.completedIntegratorStep()[:2]
            if terminate:
                raise EndRun(self.c.name, f"the model asked to terminate after an integrator step at t = {t:.6g} s")
            if state_event or step_event or t >= self.next_time - 1e-12:
                self._event(t)
                x = self._states()


class FMUTypes:
    """Sub-resolver (orchestrator.resolver): a component whose type is a path ending in ``.fmu``,
    relative to the study file."""

    def component_class(self, study: Study, name: str, resolver) -> type[FMUComponent] | None:
        spec = study.components.get(name)
        if spec is None or not spec.type.lower().endswith(".fmu"):
            return None
        try:
            cls = fmu_component_class(study.file_path(spec.type))
        except FMUError as exc:
            raise StudyError(f"{study.where}: components.{name}.type: {exc}") from None
        isolate = study.study.isolate_fmus
        foreign = not ours(cls.model_description)
        if isolate is None:          # the default: a co-simulation FMU from outside the project in its own process
            isolate = foreign and not cls.model_exchange
        if isolate:
            cls = type(cls.__name__, (cls,), {"isolate": True, "call_timeout": study.study.fmu_timeout})
        elif foreign:
            cls = type(cls.__name__, (cls,), {"in_process_note": f"{study.origin('study.isolate_fmus')} = false"})
        return cls


PROJECT_TOOL = __name__.split(".")[0]   # how the generationTool of the FMUs the project's exporters write begins


def ours(model_description) -> bool:
    """An FMU the project's own exporters generated (its C is the project's, compiled here)."""
    return str(getattr(model_description, "generationTool", "") or "").startswith(PROJECT_TOOL)
