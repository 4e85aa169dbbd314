"""From a resolved model to the System the engine runs (after Drake's DiagramBuilder): component
instances with their parameters in SI and their constant inputs, port and unit checks of every
connection, the evaluation order of sampled components, and algebraic loops refused.

Every input is driven: by a connection, a study constant (``[components.X.inputs]``) or, in a
subsystem, an exported port. Any other input is refused unless its component declares it optional
or the study lists it in ``[study] allow_unconnected``; those hold their start value
(``System.held_inputs``, said when a run starts).

A built System can be run again and again: ``System.restart`` (called by the engine when a run
starts) returns every component's parameters, inputs, outputs and random stream to what they were
when built, so a run is a function of the study and its seed alone."""
from __future__ import annotations

import copy
import graphlib
import math
import zlib
from dataclasses import dataclass, field

import numpy as np

from .component import Component, ComponentError
from .errors import did_you_mean
from .model import Model, resolved_parameters
from .study import ComponentSpec, Connection, Study, StudyError
from .units import UnitError, to_si, units_match


@dataclass
class Node:
    """One component instance with its place in the schedule."""

    name: str
    component: Component
    step: float
    ratio: int                      # step / base_step
    sources: list[tuple[str, "Node", str]] = field(default_factory=list)  # (input, src node, output)
    seed: int = 0                   # the study seed the component's random stream is drawn from
    initial: tuple[dict, dict, dict] = field(default_factory=lambda: ({}, {}, {}))   # (p, u, y) as built

    def restart(self) -> None:
        """The component as built: parameters, inputs and outputs (in place: callers may hold
        the dicts), a fresh random stream, no events."""
        comp = self.component
        p, u, y = self.initial
        for mine, built in ((comp.p, p), (comp.u, u), (comp.y, y)):
            mine.clear()
            mine.update(copy.deepcopy(built))
        comp.rng = component_seed(self.seed, self.name)
        comp.events = []


ACKNOWLEDGED = "study.allow_unconnected"      # a held input the study names: recorded, not said


@dataclass
class System:
    study: Study
    nodes: dict[str, Node]
    sampled_order: list[Node]        # evaluated in this order at each sample instant
    continuous: list[Node]
    connections: list[Connection]
    unconnected_inputs: list[str]    # inputs no connection drives (constants and held ones included)
    # inputs left to their start value: ("component.input", value, unit, why)
    held_inputs: list[tuple[str, object, str, str]] = field(default_factory=list)

    def restart(self) -> None:
        """Every component as built (the engine calls it when a run starts)."""
        for node in self.nodes.values():
            node.restart()

    def held_lines(self) -> list[str]:
        """One line per input left unconnected that holds its start value, but those the study
        lists in ``study.allow_unconnected`` (its author's choice, recorded in run.json)."""
        return [f"{port} is unconnected: it holds {value:g}{'' if unit in ('', '1') else ' ' + unit} for the whole "
                f"run ({why})" if isinstance(value, (int, float)) else f"{port} is unconnected: it holds {value!r} ({why})"
                for port, value, unit, why in self.held_inputs if why != ACKNOWLEDGED]


def component_seed(study_seed: int, name: str) -> np.random.Generator:
    """Independent, reproducible stream per component: seeded by (study seed, crc32(name))."""
    return np.random.default_rng([study_seed, zlib.crc32(name.encode())])


def build_system(model: Model) -> System:
    """Instances of the model's components, wired and ordered (a StudyError names the field)."""
    if not isinstance(model, Model):
        raise TypeError(f"build_system takes a resolved Model (build_system(resolve(study))), not {type(model).__name__}")
    study = model.study
    where = study.where
    base = study.study.base_step
    nodes: dict[str, Node] = {}
    specs = {**study.components, **{n: ComponentSpec(type="", step=s.step) for n, s in study.subsystems.items()}}
    for name, spec in specs.items():
        cls = model.classes[name]
        converted = resolved_parameters(cls, name, spec.parameters, study.origin, study.folders)
        try:
            comp = cls(name, converted, rng=component_seed(study.study.seed, name))
        except ComponentError as exc:
            raise StudyError(f"{where}: components.{name}: {exc}") from None
        except (ValueError, TypeError, ArithmeticError, KeyError, IndexError) as exc:
            # a parameter value the component's equations cannot take (checked nowhere else)
            raise StudyError(f"{where}: components.{name}: cannot be built with parameters "
                             f"{dict(spec.parameters)}: {type(exc).__name__}: {exc}") from None
        inputs = cls.declared("input")
        for key, value in spec.inputs.items():
            at = study.origin(f"components.{name}.inputs.{key}")
            if key not in inputs:
                raise StudyError(f"{at}: unknown input{did_you_mean(key, inputs, n=1)}"
                                 + f" Known: {', '.join(sorted(inputs))}")
            try:
                comp.u[key] = to_si(value, inputs[key].unit)
            except UnitError as exc:
                raise StudyError(f"{at}: {exc}") from None
        step = spec.step if spec.step is not None else base
        ratio = round(step / base)
        if ratio < 1 or not math.isclose(ratio * base, step, rel_tol=1e-9, abs_tol=1e-12):
            raise StudyError(f"{where}: components.{name}.step: {step} s is not an integer multiple "
                             f"of study.base_step {base} s")
        nodes[name] = Node(name, comp, step, ratio, seed=study.study.seed,
                           initial=copy.deepcopy((comp.p, comp.u, comp.y)))

    connected: dict[tuple[str, str], Connection] = {}
    for i, conn in enumerate(study.connections):
        field_name = f"connections[{i}] '{conn}'"
        for comp_name in (conn.source, conn.target):
            if comp_name not in nodes:
                raise StudyError(f"{where}: {field_name}: unknown component {comp_name!r}; "
                                 f"known: {', '.join(sorted(nodes))}")
        src, dst = nodes[conn.source].component, nodes[conn.target].component
        outs, ins = src.declared("output"), dst.declared("input")
        if conn.output not in outs:
            hint = " (it is an input)" if conn.output in src.declared("input") else ""
            raise StudyError(f"{where}: {field_name}: {conn.source!r} has no output {conn.output!r}{hint}; "
                             f"outputs: {', '.join(sorted(outs))}")
        if conn.input not in ins:
            hint = " (it is an output)" if conn.input in dst.declared("output") else ""
            raise StudyError(f"{where}: {field_name}: {conn.target!r} has no input {conn.input!r}{hint}; "
                             f"inputs: {', '.join(sorted(ins))}")
        a, b = outs[conn.output].unit, ins[conn.input].unit
        # compared by dimension and factor (an FMU's BaseUnits where it states them)
        if not units_match(a, b, getattr(src, "base_units", {}).get(conn.output),
                           getattr(dst, "base_units", {}).get(conn.input)):
            raise StudyError(f"{where}: {field_name}: unit mismatch: output is in {a!r}, input expects "
                             f"{b!r} (not the same dimension and scale)")
        key = (conn.target, conn.input)
        if key in connected:
            raise StudyError(f"{where}: {field_name}: input {conn.target}.{conn.input} is already "
                             f"driven by '{connected[key]}'")
        connected[key] = conn
        nodes[conn.target].sources.append((conn.input, nodes[conn.source], conn.output))

    for name, node in nodes.items():
        node.component.connected_inputs = frozenset(i for t, i in connected if t == name)
    unconnected = [f"{n}.{i}" for n, node in nodes.items() for i in node.component.declared("input")
                   if (n, i) not in connected]
    held = _held_inputs(study, specs, nodes, unconnected)
    _refuse_algebraic_loops(nodes, study.connections, where)
    sampled = [n for n in nodes.values() if n.component.sampled]
    order = _sampled_order(sampled, where)
    continuous = [n for n in nodes.values() if not n.component.sampled]
    return System(study, nodes, order, continuous, list(study.connections), unconnected, held)


def _held_inputs(study: Study, specs, nodes: dict[str, Node], unconnected: list[str]) -> list[tuple]:
    """The inputs nothing drives that may hold their start value (declared optional, or listed in
    ``study.allow_unconnected``); a StudyError names every other one and the three ways to drive it."""
    where = study.where
    allowed = {}
    for i, item in enumerate(study.study.allow_unconnected):
        comp_name, port = item.split(".", 1)
        at = study.origin(f"study.allow_unconnected[{i}]")
        if comp_name not in nodes:
            raise StudyError(f"{at}: {item!r}: no component {comp_name!r}{did_you_mean(comp_name, nodes, n=1)}"
                             + f" Components: {', '.join(sorted(nodes))}")
        inputs = nodes[comp_name].component.declared("input")
        if port not in inputs:
            raise StudyError(f"{at}: {item!r}: {comp_name!r} has no input {port!r}{did_you_mean(port, inputs, n=1)}"
                             + f" Inputs: {', '.join(sorted(inputs))}")
        allowed[item] = i
    exported = set()
    if study.exports is not None:
        for port in study.exports.inputs:
            exported.update(f"{c}.{n}" for c, n in study.exports.input_targets(port))
    held, missing = [], []
    for item in unconnected:
        comp_name, port = item.split(".", 1)
        if port in specs[comp_name].inputs or item in exported:
            continue
        v = nodes[comp_name].component.declared("input")[port]
        if item in allowed:
            held.append((item, v.start, v.unit, ACKNOWLEDGED))
        elif v.optional:
            held.append((item, v.start, v.unit, f"declared optional: {v.description}"))
        else:
            missing.append(f"{item} ({v.description}; {v.unit})")
    declared = {f"{n}.{i}" for n, node in nodes.items() for i in node.component.declared("input")}
    if missing and exported <= declared:      # a wrong export is named by the subsystem's exports
        first = missing[0].split(" ", 1)[0]
        raise StudyError(
            f"{where}: connections: {len(missing)} input{'s' if len(missing) > 1 else ''} connected to nothing: "
            f"{', '.join(missing)}. Connect each (connections = [\"source.output -> {first}\"]), give it a "
            f"value ([components.{first.split('.')[0]}.inputs]) or let it hold its start value "
            f"([study] allow_unconnected = [\"{first}\"])")
    return held


def _direct(node: Node, input_name: str) -> bool:
    comp = node.component
    return comp.sampled and any(input_name in deps for deps in comp.feedthrough.values())


def _refuse_algebraic_loops(nodes: dict[str, Node], connections: list[Connection], where: str) -> None:
    """Port graph: connection edges output->input, feedthrough edges input->output of sampled
    components. A cycle is an algebraic loop (continuous components break loops: their outputs
    at t come from their state)."""
    graph: dict[tuple[str, str, str], set[tuple[str, str, str]]] = {}
    for conn in connections:
        graph.setdefault((conn.target, conn.input, "input"), set()).add((conn.source, conn.output, "output"))
    for name, node in nodes.items():
        comp = node.component
        if not comp.sampled:
            continue
        for out_name, deps in comp.feedthrough.items():
            graph.setdefault((name, out_name, "output"), set()).update((name, d, "input") for d in deps)
    try:
        list(graphlib.TopologicalSorter(graph).static_order())
    except graphlib.CycleError as exc:
        cycle = [f"{c}.{p} ({kind})" for c, p, kind in exc.args[1]]
        raise StudyError(f"{where}: algebraic loop through direct feedthrough: "
                         f"{' -> '.join(cycle)}; break it with a delay or a continuous "
                         f"component") from None


def _sampled_order(sampled: list[Node], where: str) -> list[Node]:
    """Order sampled components so each reads inputs its sources produced at the same instant.
    Edges into inputs without feedthrough are preferences: dropped if they alone close a cycle."""
    names = {n.name for n in sampled}
    by_name = {n.name: n for n in sampled}

    def graph(all_edges: bool) -> dict[str, set[str]]:
        g: dict[str, set[str]] = {n.name: set() for n in sampled}
        for node in sampled:
            for inp, src, _ in node.sources:
                if src.name in names and src.name != node.name and (all_edges or _direct(node, inp)):
                    g[node.name].add(src.name)
        return g

    for all_edges in (True, False):
        try:
            return [by_name[n] for n in graphlib.TopologicalSorter(graph(all_edges)).static_order()]
        except graphlib.CycleError:
            continue
    raise StudyError(f"{where}: cannot order sampled components")  # unreachable after loop check
