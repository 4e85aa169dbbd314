"""Composite subsystems: a study used as one component of another (a Diagram inside a Diagram).

A subsystem is a study with an ``[exports]`` table, named by path as a component's ``type``
(``type = "plant_side.toml"``, relative to the study file), or an inline ``[subsystems.NAME]``
block. Its ports are the exported ones, with the units and start values the inner components
declare; its parameters are the inner components' parameters, named ``component.parameter``.

Semantics (the component contract, orchestrator.component):
- if every inner component is sampled, the composite is *sampled*: ``step(t, dt)`` sets the inner
  inputs and takes the inner instants of [t, t + dt); its feedthrough is the inner path from each
  exported input to each exported output (connections plus inner feedthrough);
- otherwise it is *continuous*: ``step(t, dt)`` holds the inputs of t and runs the inner engine
  to t + dt; its outputs then describe t + dt.
The inner study's seed is drawn from the composite's own random stream, its start time is the
host's; ``dt`` must be a whole number of the inner base steps.
"""
from __future__ import annotations

import contextvars
import json
from pathlib import Path
from typing import Any, ClassVar

from .build import System, build_system
from .component import Component, ComponentError, Variable
from .engine import RunError, Simulation
from .study import Study, StudyError
from .study_schema import SUBSYSTEM_SUFFIXES, ExportedInput


def _inner_port(system: System, comp: str, name: str, causality: str, field: str) -> Variable:
    """The declaration of an inner component's port; a StudyError names what exists."""
    node = system.nodes.get(comp)
    declared = node.component.declared(causality) if node else {}
    if name not in declared:
        raise StudyError(f"{field}: {comp}.{name} is not an {causality} of the subsystem"
                         + (f"; {comp}'s {causality}s: {', '.join(sorted(declared))}" if node else
                            f"; components: {', '.join(sorted(system.nodes))}"))
    return declared[name]


def exported_ports(system: System, sub: Study, where: str) -> tuple[list[Variable], dict[str, tuple[str, ...]]]:
    """Port variables of the composite and, when it is sampled, its feedthrough."""
    exports = sub.exports
    variables: list[Variable] = []
    unconnected = set(system.unconnected_inputs)
    for port in exports.inputs:
        targets = exports.input_targets(port)
        units = set()
        for comp, name in targets:
            declared = _inner_port(system, comp, name, "input", f"{where}: exports.inputs.{port}")
            if f"{comp}.{name}" not in unconnected:
                raise StudyError(f"{where}: exports.inputs.{port}: {comp}.{name} is already driven inside the subsystem")
            units.add(declared.unit.replace(" ", ""))
        if len(units) > 1:
            raise StudyError(f"{where}: exports.inputs.{port}: its targets differ in unit ({sorted(units)})")
        table = exports.inputs[port]
        if isinstance(table, ExportedInput) and table.unit is not None:
            if units and table.unit.replace(" ", "") not in units:
                raise StudyError(f"{where}: exports.inputs.{port}.unit: {table.unit!r}, but its targets take {sorted(units)}")
            variables.append(Variable(port, "input", table.unit, table.start, table.description,
                                      optional=all(_inner_port(system, c, n, "input", where).optional
                                                   for c, n in targets)))
            continue
        first = system.nodes[targets[0][0]].component.declared("input")[targets[0][1]]
        optional = all(system.nodes[c].component.declared("input")[n].optional for c, n in targets)
        variables.append(Variable(port, "input", first.unit, first.start, first.description, optional))
    for port in exports.outputs:
        v = _inner_port(system, *exports.output_source(port), "output", f"{where}: exports.outputs.{port}")
        variables.append(Variable(port, "output", v.unit, v.start, v.description))
    for comp, node in system.nodes.items():
        for v in node.component.declared("parameter").values():
            variables.append(Variable(f"{comp}.{v.name}", "parameter", v.unit, None, f"{comp}: {v.description}"))
    feedthrough: dict[str, tuple[str, ...]] = {}
    if all(node.component.sampled for node in system.nodes.values()):
        feedthrough = inner_feedthrough(system, exports)
    return variables, feedthrough


def inner_feedthrough(system: System, exports) -> dict[str, tuple[str, ...]]:
    """Exported output -> exported inputs it reaches in the same instant: a path of connections
    and inner direct feedthrough (every inner component is sampled)."""
    edges: dict[tuple[str, str], set[tuple[str, str]]] = {}          # port -> ports it drives
    for conn in system.connections:
        edges.setdefault((conn.source, conn.output), set()).add((conn.target, conn.input))
    for name, node in system.nodes.items():
        for out_name, deps in node.component.feedthrough.items():
            for d in deps:
                edges.setdefault((name, d), set()).add((name, out_name))
    reach: dict[str, set[tuple[str, str]]] = {}
    for port in exports.inputs:
        seen, todo = set(), list(exports.input_targets(port))
        while todo:
            p = todo.pop()
            if p not in seen:
                seen.add(p)
                todo.extend(edges.get(p, ()))
        reach[port] = seen
    return {out: tuple(i for i in exports.inputs if exports.output_source(out) in reach[i]) for out in exports.outputs}


# the study files being resolved as subsystems, outermost first (any resolver); per thread and
# per task, so that studies resolved side by side (a sweep's threads) never see each other's
_OPEN: contextvars.ContextVar[tuple[Path, ...]] = contextvars.ContextVar("open_subsystem_files", default=())


class SubsystemTypes:
    """Sub-resolver (orchestrator.resolver): an inline ``[subsystems.NAME]`` block, or a component
    whose type is a study file (.toml/.yaml, relative to the study file). Each subsystem's class is
    made once per content (its inner system is built once to check its exports)."""

    def __init__(self) -> None:
        self._classes: dict[str, type[CompositeComponent]] = {}

    def component_class(self, study: Study, name: str, resolver) -> type["CompositeComponent"] | None:
        if name in study.subsystems:
            return self.composite_class(study.subsystem(name), f"{study.where}: subsystems.{name}", resolver)
        spec = study.components.get(name)
        if spec is None or not spec.type.lower().endswith(SUBSYSTEM_SUFFIXES):
            return None
        path = study.file_path(spec.type).resolve()
        chain = list(_OPEN.get()) or ([Path(study.path).resolve()] if study.path is not None else [])
        if path in chain:
            cycle = chain[chain.index(path):] + [path]
            raise StudyError(f"{study.where}: components.{name}.type = {spec.type!r}: a study that uses itself as a "
                             f"subsystem ({' -> '.join(p.name for p in cycle)})")
        try:
            sub = Study.load(path)
        except StudyError as exc:
            raise StudyError(f"{study.where}: components.{name}.type: subsystem {exc}") from None
        token = _OPEN.set(tuple(chain + [path]))
        try:
            return self.composite_class(sub, f"{study.where}: components.{name}.type", resolver)
        finally:
            _OPEN.reset(token)

    def composite_class(self, sub: Study, where: str, resolver) -> type["CompositeComponent"]:
        """A Component class whose ports are ``sub``'s exports."""
        key = json.dumps([str(sub.path), sub.to_data()], sort_keys=True, default=str)
        if key not in self._classes:
            self._classes[key] = _composite_class(sub, where, resolver)
        return self._classes[key]


def _composite_class(sub: Study, where: str, resolver) -> type["CompositeComponent"]:
    if sub.exports is None:
        raise StudyError(f"{where}: {sub.where} has no [exports] table; a study used as a subsystem declares "
                         f"the ports it offers: [exports] inputs = {{port = \"component.input\"}}, "
                         f"outputs = {{port = \"component.output\"}}")
    try:
        system = build_system(resolver.resolve(sub))
    except StudyError as exc:
        raise StudyError(f"{where}: in the subsystem: {exc}") from None
    variables, feedthrough = exported_ports(system, sub, sub.where)
    sampled = all(node.component.sampled for node in system.nodes.values())
    attrs = {"variables": tuple(variables), "feedthrough": feedthrough, "sampled": sampled,
             "subsystem": sub, "resolver": resolver, "type_name": sub.where, "roles": tuple(sub.exports.roles)}
    return type(f"Subsystem_{sub.study.name.replace('.', '_')}", (CompositeComponent,), attrs)


class CompositeComponent(Component):
    """One instance of a subsystem: its own engine, stepped inside this component's step."""

    subsystem: ClassVar[Study]
    resolver: ClassVar[Any]          # the resolver that made the class resolves its variants
    type_name: ClassVar[str]

    def initialize(self, t0: float, dt: float) -> None:
        seed = int(self.rng.integers(0, 2**31 - 1))
        values = {"study.seed": seed, "study.start_time": t0,
                  **{k: v for k, v in self.p.items() if v is not None}}
        try:
            sub = self.subsystem.with_values(values)
            system = build_system(self.resolver.resolve(sub))
        except StudyError as exc:
            raise ComponentError(f"{self.name}: subsystem: {exc}") from None
        h = sub.study.base_step
        self.substeps = int(round(dt / h))
        self.require(self.substeps >= 1 and abs(self.substeps * h - dt) < 1e-9,
                     f"step {dt} s must be a multiple of the subsystem's base step {h} s")
        ex = sub.exports
        self._inputs = [(port, [(system.nodes[c].component.u, n) for c, n in ex.input_targets(port)])
                        for port in ex.inputs]
        self._outputs = [(port, system.nodes[c].component, n) for port in ex.outputs
                         for c, n in [ex.output_source(port)]]
        self.system = system
        self.sim = Simulation(system, record=False)
        self.sim.start()
        self._publish()

    def _publish(self) -> None:
        y = self.y
        for port, comp, name in self._outputs:
            y[port] = comp.y[name]

    def step(self, t: float, dt: float) -> None:
        u = self.u
        for port, targets in self._inputs:
            for inner_u, name in targets:
                inner_u[name] = u[port]
        try:
            self.sim.advance(self.sim.k + self.substeps)
        except RunError as exc:
            if isinstance(exc.__cause__, KeyboardInterrupt):     # Ctrl-C or SIGTERM (errors.Terminated): the same kind
                raise type(exc.__cause__)() from None
            raise ComponentError(f"{self.name}: in the subsystem {exc}") from None
        self._publish()

    def terminate(self) -> None:
        if getattr(self, "sim", None) is not None:
            self.sim.terminate()
