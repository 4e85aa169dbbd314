"""The resolved model: a study with the class of every component found once (by a resolver,
orchestrator.resolver), and what can be known from the classes without building anything:
components by role or type, parameters in SI, a group's boundary ports, and the studies derived
from a group (``extract``, ``collapse``).

The one place where a study's parameter values are converted with the declared units
(orchestrator.units) is ``resolved_parameters``; the build uses it too.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Iterable, Mapping, Sequence

from .component import Component
from .errors import did_you_mean
from .parameter_ranges import range_refusal
from .study import Study, StudyError
from .units import FILE_UNIT, UnitError, to_si


def _port_name(comp: str, port: str) -> str:
    return f"{comp}_{port}"


class Model:
    """``study`` with ``classes``: component (or subsystem) name -> its Component class, in the
    study's order (components, then subsystems)."""

    def __init__(self, study: Study, classes: Mapping[str, type[Component]]) -> None:
        self.study = study
        self.classes = dict(classes)

    @property
    def where(self) -> str:
        return self.study.where

    def component_class(self, name: str) -> type[Component]:
        """The class behind component ``name`` (Python, FMU or subsystem)."""
        if name not in self.classes:
            raise StudyError(f"{self.where}: no component {name!r}; known: {', '.join(sorted(self.study.components))}")
        return self.classes[name]

    def parameters(self, name: str) -> dict[str, Any]:
        """Every parameter of component ``name`` in SI: declared defaults, then the study's values
        converted with the declared units (files found as the build finds them)."""
        cls = self.component_class(name)
        spec = self.study.components.get(name)
        return {**{k: v.start for k, v in cls.declared("parameter").items()},
                **resolved_parameters(cls, name, spec.parameters if spec else {}, self.study.origin, self.study.folders)}

    def find(self, *, role: str | None = None, type: type | str | None = None) -> list[str]:
        """Names of the components that declare ``role`` (``Component.roles``, or the study's
        ``roles`` of the component) or are of ``type`` (a class, matched with issubclass, or a type
        name as written in the study)."""
        found = []
        components = self.study.components
        for name, cls in self.classes.items():
            spec = components.get(name)
            if isinstance(type, str):
                if spec is None or spec.type != type:
                    continue
            elif type is not None and not issubclass(cls, type):
                continue
            if role is not None and role not in getattr(cls, "roles", ()) and role not in (spec.roles if spec else ()):
                continue
            found.append(name)
        return found

    def one(self, *, role: str | None = None, type: type | str | None = None, purpose: str = "") -> str:
        """The single component with ``role`` / of ``type``; a StudyError names what was found."""
        found = self.find(role=role, type=type)
        if len(found) != 1:
            what = f"role {role!r}" if role else f"type {getattr(type, '__name__', type)!r}"
            raise StudyError(f"{self.where}: components: {purpose + ' needs' if purpose else 'expected'} exactly one "
                             f"component with {what}, found {len(found)}" + (f" ({', '.join(found)})" if found else ""))
        return found[0]

    # --- subsystems: cut a group out, or fold it into one component -------------------------
    def boundary(self, names: Iterable[str], port_name: Callable[[str, str], str] = _port_name):
        """The group's external wiring: (inputs, outputs, internal connections), where inputs maps an
        exported port to [(comp, input)] and the outside signal feeding it (or None), outputs maps an
        exported port to (comp, output) and the outside inputs it drives."""
        study = self.study
        group = set(names)
        missing = sorted(group - set(study.components))
        if missing:
            raise StudyError(f"{self.where}: components {missing} not in the study")
        inputs: dict[str, dict[str, Any]] = {}
        outputs: dict[str, dict[str, Any]] = {}
        internal = []
        fed = {(c.target, c.input): c for c in study.connections}
        for name in study.components:
            if name not in group:
                continue
            cls = self.classes[name]
            for port in cls.declared("input"):
                conn = fed.get((name, port))
                if conn is not None and conn.source in group:
                    continue
                inputs[port_name(name, port)] = {"targets": [(name, port)],
                                                 "source": (conn.source, conn.output) if conn else None}
            for port in cls.declared("output"):
                outputs[port_name(name, port)] = {"source": (name, port), "drives": []}
        for c in study.connections:
            if c.source in group and c.target in group:
                internal.append(c)
            elif c.source in group:
                outputs[port_name(c.source, c.output)]["drives"].append((c.target, c.input))
        return inputs, outputs, internal

    def extract(self, names: Iterable[str], name: str | None = None,
                port_name: Callable[[str, str], str] = _port_name) -> Study:
        """The group of components as a study of its own with ``exports``: every input not fed
        inside the group and every output of the group, named by ``port_name``."""
        study = self.study
        names = list(names)
        inputs, outputs, internal = self.boundary(names, port_name)
        data = study.to_data()
        base = min(study.components[n].step or study.study.base_step for n in names)
        settings = {**data["study"], "name": name or f"{study.study.name}_subsystem", "base_step": base}
        settings.pop("analysis", None)
        settings.pop("realtime", None)
        if settings.get("allow_unconnected"):        # the group's own held inputs only
            settings["allow_unconnected"] = [i for i in settings["allow_unconnected"] if i.split(".", 1)[0] in names]
        sub = {"study": settings,
               "components": {n: data["components"][n] for n in names},
               "connections": [str(c) for c in internal],
               "exports": {"inputs": {p: f"{c}.{i}" for p, v in inputs.items() for c, i in v["targets"]},
                           "outputs": {p: f"{c}.{o}" for p, v in outputs.items() for c, o in [v["source"]]}}}
        return study.derive(sub)

    def collapse(self, names: Iterable[str], into: str, type: str, step: float | None = None,
                 port_name: Callable[[str, str], str] = _port_name,
                 parameters: Mapping[str, Any] | None = None) -> Study:
        """The study with the group replaced by one component ``into`` of ``type`` whose ports are
        the group's boundary ports (``port_name``); the outside wiring is kept."""
        names = list(names)
        inputs, outputs, _ = self.boundary(names, port_name)
        add = [f"{v['source'][0]}.{v['source'][1]} -> {into}.{p}" for p, v in inputs.items() if v["source"]]
        add += [f"{into}.{p} -> {t}.{i}" for p, v in outputs.items() for t, i in v["drives"]]
        spec: dict[str, Any] = {"type": type}
        if step is not None:
            spec["step"] = step
        if parameters:
            spec["parameters"] = dict(parameters)
        # a boundary input nothing drives was accepted so inside: its constant, or left to its start
        constants = {p: self.study.components[v["targets"][0][0]].inputs[v["targets"][0][1]]
                     for p, v in inputs.items() if not v["source"]
                     and v["targets"][0][1] in self.study.components[v["targets"][0][0]].inputs}
        if constants:
            spec["inputs"] = constants
        held = [f"{into}.{p}" for p, v in inputs.items() if not v["source"] and p not in constants]
        study = self.study.without(*names).with_component(into, **spec).with_connections(add=add)
        if held:
            study = study.with_values({"study.allow_unconnected": [*study.study.allow_unconnected, *held]})
        return study


def resolved_parameters(cls: type[Component], name: str, values: dict[str, Any], origin: Callable[[str], str],
                        folders: Callable[[], Sequence[Path]] | None = None) -> dict[str, Any]:
    """The study's values of component ``name``'s parameters in SI (declared units); unknown
    names and unit mismatches are refused with the field named where its value was given
    (``origin(field)``: the study file's field, or the ``--set`` that set it). A relative path in a parameter
    declared with unit ``"file"`` is found in the first of ``folders()`` (the study file's, then
    those of the files it extends) or the working folder that holds it, and made absolute; one
    found nowhere is left as written for the component to name."""
    params = cls.declared("parameter")
    converted: dict[str, Any] = {}
    for key, value in values.items():
        where = origin(f"components.{name}.parameters.{key}")
        if key not in params:
            raise StudyError(f"{where}: unknown parameter of "
                             f"{getattr(cls, 'type_name', cls.__name__)!r}{did_you_mean(key, params, n=1)}"
                             + f" Known: {', '.join(sorted(params))}")
        try:
            converted[key] = to_si(value, params[key].unit)
        except UnitError as exc:
            raise StudyError(f"{where}: {exc}") from None
        if params[key].unit == FILE_UNIT and isinstance(converted[key], str) and converted[key]:
            converted[key] = _find_file(converted[key], folders() if folders else ())
        start = params[key].start
        numeric = isinstance(start, (int, float)) and not isinstance(start, bool)
        if numeric and isinstance(converted[key], str):
            raise StudyError(f"{where}: got {value!r}, expected a number"
                             + (f" in {params[key].unit} (or a string like '1.5 {params[key].unit}')"
                                if params[key].unit not in ("", "1") else ""))
        why = range_refusal(key, params[key].unit, start, converted[key])
        if why is not None:
            raise StudyError(f"{where}: {why}")
    return converted


def _find_file(text: str, folders: Sequence[Path]) -> str:
    path = Path(text).expanduser()
    if path.is_absolute():
        return str(path)
    for folder in (*folders, Path.cwd()):
        if (folder / path).exists():
            return str((folder / path).resolve())
    return text
