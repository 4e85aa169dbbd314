"""Study files and the Study API: the one description of a co-simulation, and the one way to
derive a variant of it.

Layout of a study file (TOML or YAML, validated with pydantic)::

    extends = "other.toml"  (optional: start from that study, merge this file's tables over it)
    connections_remove = [...], connections_add = [...]   (with extends: edit the parent's
                            connections instead of repeating them)
    [study]                 name, stop_time, base_step, seed, start_time, signals_format, analysis
    [components.NAME]       type, step, parameters = {...}, inputs = {...} (constants for inputs
                            left unconnected). ``type`` is a registered component type
                            ("first_order_lag"), "package.module:Class", a path to an FMU
                            (.fmu) or to another study used as a subsystem (.toml/.yaml)
    [subsystems.NAME]       an inline subsystem, one component of this study: step, base_step,
                            components, connections, exports
    [exports]               the ports this study offers when another study uses it as a
                            subsystem: inputs = {port = "comp.input" or [...]}, outputs = {port = "comp.output"}
    connections = ["src.output -> dst.input", ...]
    [sweep]                 parameters to sweep (see orchestrator.sweep)
    [TOOL]                  a table read by a tool that registered it (see orchestrator.registry)

A ``Study`` is immutable in use: ``with_values``, ``with_component``, ``replace_component``,
``without``, ``with_connections``, ``extract`` and ``collapse`` return new studies; ``to_toml``
writes one back. Parameters keep the values as written ("8000 N/rad", "30 deg") until
``parameters(name)`` resolves them to SI with the component's declared units, the one place
where a unit string is parsed (``orchestrator.units``).
"""
from __future__ import annotations

import copy
import math
import re
import tomllib
from pathlib import Path
from typing import Any, Iterable, Literal, Mapping

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from .errors import InputError


class StudyError(InputError):
    """A study cannot be loaded or built; the message names the file and the field."""


_NAME = r"[A-Za-z_]\w*"
# a port: an identifier or an FMI structured name (``body.speed``, ``x[2]``, ``a.b[1,3].c``)
_INDEX = r"(?:\[\d+(?:,\d+)*\])?"
_PORT_NAME = rf"{_NAME}{_INDEX}(?:\.{_NAME}{_INDEX})*"
_CONNECTION = re.compile(rf"^\s*({_NAME})\.({_PORT_NAME})\s*->\s*({_NAME})\.({_PORT_NAME})\s*$")
_PORT = re.compile(rf"^\s*({_NAME})\.({_PORT_NAME})\s*$")
SUBSYSTEM_SUFFIXES = (".toml", ".yaml", ".yml")


class StudySettings(BaseModel):
    model_config = ConfigDict(extra="forbid")
    name: str
    description: str = ""
    start_time: float = Field(default=0.0, allow_inf_nan=False)
    stop_time: float = Field(gt=0, allow_inf_nan=False)
    base_step: float = Field(gt=0, allow_inf_nan=False)
    seed: int = Field(ge=0)
    signals_format: Literal["parquet", "csv"] = "parquet"
    component_package: str | None = None   # look types up here first (default: registered packages)
    analysis: str | None = None
    realtime: bool = False           # pace the base step against the wall clock
    realtime_tolerance: float = Field(default=0.002, ge=0)   # s: lateness that counts as a deadline miss

    @model_validator(mode="after")
    def _times(self) -> "StudySettings":
        if self.stop_time <= self.start_time:
            raise ValueError(f"stop_time ({self.stop_time}) must be after start_time ({self.start_time})")
        if self.base_step > self.stop_time - self.start_time:
            raise ValueError("base_step is longer than the run")
        return self


class ComponentSpec(BaseModel):
    model_config = ConfigDict(extra="forbid")
    type: str
    step: float | None = Field(default=None, gt=0)
    parameters: dict[str, Any] = {}
    inputs: dict[str, Any] = {}
    roles: list[str] = []          # roles besides the class's own (an FMU that plays a role a tool looks up)


class Connection(BaseModel):
    source: str
    output: str
    target: str
    input: str

    def __str__(self) -> str:
        return f"{self.source}.{self.output} -> {self.target}.{self.input}"


def _parse_connections(value: Any) -> Any:
    if not isinstance(value, list):
        raise ValueError("expected a list of strings 'component.output -> component.input'")
    parsed = []
    for i, item in enumerate(value):
        if isinstance(item, str):
            match = _CONNECTION.match(item)
            if not match:
                raise ValueError(f"item {i} {item!r}: expected 'component.output -> component.input'")
            parsed.append(dict(zip(("source", "output", "target", "input"), match.groups())))
        else:
            parsed.append(item)
    return parsed


def _check_component_names(value: dict[str, Any]) -> dict[str, Any]:
    for name in value:
        if not re.fullmatch(_NAME, name):
            raise ValueError(f"component name {name!r} must be an identifier")
    return value


class ExportedInput(BaseModel):
    """An exported input written as a table: its inner targets (possibly none: a port the
    subsystem accepts and ignores, to match another implementation's ports) and, for none, its
    declaration."""

    model_config = ConfigDict(extra="forbid")
    targets: list[str] = []
    unit: str | None = None
    start: float = 0.0
    description: str = ""

    @model_validator(mode="after")
    def _declared(self) -> "ExportedInput":
        if not self.targets and self.unit is None:
            raise ValueError("an exported input with no targets needs a 'unit'")
        return self


class Exports(BaseModel):
    """Ports a study offers as a subsystem: exported name -> inner 'component.port'. An exported
    input may drive several inner inputs (a list) or none (a table with ``unit``)."""

    model_config = ConfigDict(extra="forbid")
    inputs: dict[str, str | list[str] | ExportedInput] = {}
    outputs: dict[str, str] = {}
    roles: list[str] = []          # what the subsystem is, for Study.find (Component.roles)

    @model_validator(mode="after")
    def _ports(self) -> "Exports":
        for kind, table in (("inputs", self.inputs), ("outputs", self.outputs)):
            for name, target in table.items():
                if not re.fullmatch(_NAME, name):
                    raise ValueError(f"{kind}.{name}: an exported port name must be an identifier")
                items = target.targets if isinstance(target, ExportedInput) else \
                    [target] if isinstance(target, str) else target
                for item in items:
                    if not _PORT.match(item):
                        raise ValueError(f"{kind}.{name} = {item!r}: expected 'component.port'")
        return self

    def input_targets(self, name: str) -> list[tuple[str, str]]:
        value = self.inputs[name]
        items = value.targets if isinstance(value, ExportedInput) else [value] if isinstance(value, str) else value
        return [_PORT.match(v).groups() for v in items]

    def output_source(self, name: str) -> tuple[str, str]:
        return _PORT.match(self.outputs[name]).groups()


class SubsystemSpec(BaseModel):
    """An inline subsystem: a component of the study that is itself a small study."""

    model_config = ConfigDict(extra="forbid")
    step: float | None = Field(default=None, gt=0)
    base_step: float | None = Field(default=None, gt=0)   # default: the subsystem's step
    description: str = ""
    components: dict[str, ComponentSpec]
    connections: list[Connection] = []
    exports: Exports

    _connections = field_validator("connections", mode="before")(classmethod(lambda cls, v: _parse_connections(v)))
    _names = field_validator("components")(classmethod(lambda cls, v: _check_component_names(v)))


class SweepRange(BaseModel):
    """Inclusive range: ``{start, stop, step}`` or ``{start, stop, num}``."""

    model_config = ConfigDict(extra="forbid")
    start: float
    stop: float
    step: float | None = None
    num: int | None = None

    @model_validator(mode="after")
    def _one_of(self) -> "SweepRange":
        if (self.step is None) == (self.num is None):
            raise ValueError("give exactly one of 'step' or 'num'")
        if self.num is not None and self.num < 1:
            raise ValueError("'num' must be >= 1")
        if self.step is not None and (self.step == 0 or (self.stop - self.start) * self.step < 0):
            raise ValueError(f"empty range: from {self.start} to {self.stop} by {self.step}")
        return self

    def values(self) -> list[float]:
        if self.num is not None:
            return [float(v) for v in np.linspace(self.start, self.stop, self.num)]
        n = int(math.floor((self.stop - self.start) / self.step + 1e-9)) + 1
        return [self.start + k * self.step for k in range(n)]


class Uniform(BaseModel):
    """Monte Carlo: a value drawn uniformly from [low, high]."""

    model_config = ConfigDict(extra="forbid")
    uniform: tuple[float, float]

    @model_validator(mode="after")
    def _order(self) -> "Uniform":
        if not self.uniform[0] <= self.uniform[1]:
            raise ValueError(f"uniform = {list(self.uniform)}: expected [low, high] with low <= high")
        return self


class Sweep(BaseModel):
    """Points to run: ``grid`` (every combination), ``zip`` (element by element) or
    ``monte_carlo`` (``samples`` draws: a list is a uniform choice, ``{uniform = [a, b]}`` a
    uniform value, each sample with its own seed; all drawn from the study's seed)."""

    model_config = ConfigDict(extra="forbid")
    mode: Literal["grid", "zip", "monte_carlo"] = "grid"
    parameters: dict[str, list[Any] | SweepRange | Uniform]
    seeds: list[int] | None = None
    samples: int | None = Field(default=None, ge=1)
    analysis: str | None = None

    @model_validator(mode="after")
    def _monte_carlo(self) -> "Sweep":
        draws = [k for k, v in self.parameters.items() if isinstance(v, Uniform)]
        if self.mode == "monte_carlo":
            if self.samples is None:
                raise ValueError("mode = 'monte_carlo' needs 'samples' (how many draws)")
        elif draws or self.samples is not None:
            raise ValueError(f"'samples' and {{uniform = [a, b]}} ({', '.join(draws) or 'none here'}) need "
                             f"mode = 'monte_carlo'")
        return self

    @field_validator("parameters")
    @classmethod
    def _names(cls, value: dict[str, Any]) -> dict[str, Any]:
        if not value:
            raise ValueError("a sweep needs at least one parameter")
        for name, values in value.items():
            if not re.fullmatch(rf"{_NAME}(\.{_NAME})+", name):
                raise ValueError(f"{name!r}: expected 'component.parameter' or 'study.field'")
            if isinstance(values, list) and not values:
                raise ValueError(f"{name!r}: empty list of values")
        return value

    def expanded(self) -> dict[str, list[Any]]:
        return {k: (v.values() if isinstance(v, SweepRange) else list(v)) for k, v in self.parameters.items()}

    def draws(self, seed: int) -> list[tuple[dict[str, Any], int]]:
        """Monte Carlo: ``samples`` (values, seed) pairs from one generator seeded by ``seed``."""
        rng = np.random.default_rng(seed)
        out = []
        for _ in range(self.samples or 0):
            values = {}
            for name, spec in self.parameters.items():
                if isinstance(spec, Uniform):
                    values[name] = float(rng.uniform(*spec.uniform))
                else:
                    options = spec.values() if isinstance(spec, SweepRange) else list(spec)
                    values[name] = options[int(rng.integers(len(options)))]
            out.append((values, int(rng.integers(2**31 - 1))))
        return out


_TABLES = ("study", "components", "connections", "sweep", "exports", "subsystems")


class Study(BaseModel):
    model_config = ConfigDict(extra="forbid")
    study: StudySettings
    components: dict[str, ComponentSpec] = {}
    connections: list[Connection] = []
    sweep: Sweep | None = None
    exports: Exports | None = None
    subsystems: dict[str, SubsystemSpec] = {}
    sections: dict[str, dict[str, Any]] = {}    # tables of registered tools ([my_tool])
    path: Path | None = None

    @model_validator(mode="before")
    @classmethod
    def _tool_tables(cls, data: Any) -> Any:
        """Top-level tables other than the orchestrator's go to ``sections`` when a tool
        registered them; anything else is refused by name."""
        if not isinstance(data, dict):
            return data
        from .registry import registry

        data = dict(data)
        sections = dict(data.pop("sections", {}) or {})
        known = registry().sections
        for key in [k for k in data if k not in _TABLES and k != "path"]:
            if key not in known:
                raise ValueError(f"unknown table {key!r}; a study has {', '.join(_TABLES)}"
                                 + (f" or a tool's table ({', '.join(sorted(known))})" if known else ""))
            value = data.pop(key)
            if not isinstance(value, dict):
                raise ValueError(f"{key}: expected a table")
            sections[key] = value
        data["sections"] = sections
        return data

    _connections = field_validator("connections", mode="before")(classmethod(lambda cls, v: _parse_connections(v)))

    @field_validator("components")
    @classmethod
    def _names(cls, value: dict[str, ComponentSpec]) -> dict[str, ComponentSpec]:
        return _check_component_names(value)

    @model_validator(mode="after")
    def _some_component(self) -> "Study":
        if not self.components and not self.subsystems:
            raise ValueError("a study needs at least one component")
        both = sorted(set(self.components) & set(self.subsystems))
        if both:
            raise ValueError(f"{both}: a name is either a component or a subsystem, not both")
        return self

    # --- loading and writing ------------------------------------------------------------------
    @classmethod
    def load(cls, path: str | Path, overrides: Iterable[str] = ()) -> "Study":
        """A study file (``extends`` resolved) with ``key=value`` overrides (``--set``; the value
        is read as TOML, else as a string), validated once."""
        data = read_study_file(path)
        for item in overrides:
            key, value = parse_override(item, path)
            _set_value(data, key, value, f"{path}: override {item!r}")
        return parse_study(data, path)

    @property
    def where(self) -> str:
        return str(self.path) if self.path else "<study>"

    def to_data(self) -> dict[str, Any]:
        """The study as a study file holds it (values as written; tool tables at the top level)."""
        data = self.model_dump(mode="python", exclude={"path", "sections"}, exclude_unset=True)
        data.update(copy.deepcopy(self.sections))
        if "connections" in data:
            data["connections"] = [str(c) for c in self.connections]
        for name, sub in self.subsystems.items():
            if "connections" in data["subsystems"][name]:
                data["subsystems"][name]["connections"] = [str(c) for c in sub.connections]
        return data

    def to_toml(self) -> str:
        import tomli_w

        data = self.to_data()
        order = ["connections", "study"] + [k for k in data if k not in ("connections", "study")]
        return tomli_w.dumps({k: data[k] for k in order if k in data}, multiline_strings=False)

    def extension_toml(self, values: Mapping[str, Any], comment: str = "") -> str:
        """A study file that is this study with ``values`` set (keys as in ``with_values``): a
        small file that ``extends`` the study file when this study is what its file says, else the
        whole study written out."""
        header = "".join(f"# {line}\n" for line in comment.splitlines())
        extended = self.with_values(values)
        try:
            pristine = self.path is not None and \
                parse_study(read_study_file(self.path), self.path).to_data() == self.to_data()
        except StudyError:
            pristine = False
        if not pristine:
            return header + extended.to_toml()
        import tomli_w

        overlay: dict[str, Any] = {"extends": Path(self.path).resolve().as_posix()}
        skeleton = {"components": {n: {} for n in self.components}, "subsystems": {n: {"components": {
            c: {} for c in s.components}} for n, s in self.subsystems.items()}, "study": {},
            **{k: {} for k in self.sections}}
        for key, value in values.items():
            _set_value(skeleton, key, value, f"{self.where}: {key!r}")
        overlay.update(_pruned(skeleton))
        return header + tomli_w.dumps(overlay)

    def _derive(self, data: dict[str, Any]) -> "Study":
        return parse_study(data, self.path if self.path is not None else "<study>")

    # --- variants -----------------------------------------------------------------------------
    def with_values(self, values: Mapping[str, Any]) -> "Study":
        """Set values by dotted key: ``study.FIELD``, ``COMP.PARAM``, ``COMP.inputs.PORT``,
        ``SUBSYSTEM.COMP.PARAM`` (an inline subsystem's component), ``TABLE.FIELD`` (a tool's table)."""
        data = self.to_data()
        for key, value in values.items():
            _set_value(data, key, value, f"{self.where}: {key!r}")
        return self._derive(data)

    def with_component(self, name: str, **fields: Any) -> "Study":
        """Add component ``name`` or update fields of it (``type``, ``step``; ``parameters`` and
        ``inputs`` are merged into what it has)."""
        data = self.to_data()
        spec = data.setdefault("components", {}).setdefault(name, {})
        for key, value in fields.items():
            if key in ("parameters", "inputs") and isinstance(spec.get(key), dict):
                spec[key] = {**spec[key], **value}
            else:
                spec[key] = value
        return self._derive(data)

    def replace_component(self, name: str, type: str, *, step: float | None = None,
                          parameters: Mapping[str, Any] | None = None, keep_parameters: bool = False) -> "Study":
        """Component ``name`` becomes a ``type`` (same name, so every connection stays)."""
        if name not in self.components:
            raise StudyError(f"{self.where}: components.{name}: no such component; known: {', '.join(sorted(self.components))}")
        data = self.to_data()
        old = data["components"][name]
        new = {"type": type, "step": step if step is not None else old.get("step")}
        new["parameters"] = {**(old.get("parameters", {}) if keep_parameters else {}), **(parameters or {})}
        if old.get("inputs"):
            new["inputs"] = old["inputs"]
        data["components"][name] = {k: v for k, v in new.items() if v is not None}
        return self._derive(data)

    def without(self, *names: str) -> "Study":
        """Drop components or subsystems (with every connection touching them) or whole tables
        (``sweep``, ``exports``, a tool's table)."""
        data = self.to_data()
        gone = set()
        for name in names:
            if name in self.components or name in self.subsystems:
                data.get("components", {}).pop(name, None)
                data.get("subsystems", {}).pop(name, None)
                gone.add(name)
            elif name in data and name not in ("study", "components", "connections"):
                data.pop(name)
            else:
                raise StudyError(f"{self.where}: without({name!r}): no such component or table")
        data["connections"] = [str(c) for c in self.connections if c.source not in gone and c.target not in gone]
        return self._derive(data)

    def with_connections(self, add: Iterable[str] = (), remove: Iterable[str] = ()) -> "Study":
        """Add connection strings, remove connections (given as strings, compared parsed)."""
        drop = {str(Connection(**dict(zip(("source", "output", "target", "input"), _CONNECTION.match(r).groups()))))
                for r in remove}
        data = self.to_data()
        data["connections"] = [str(c) for c in self.connections if str(c) not in drop] + list(add)
        return self._derive(data)

    # --- tool tables --------------------------------------------------------------------------
    def section(self, name: str) -> dict[str, Any] | None:
        """A registered tool's table, or None when the study has none."""
        return self.sections.get(name)

    # --- components: types, resolved parameters, lookup -------------------------------------
    def component_class(self, name: str):
        """The class behind component ``name`` (Python, FMU or subsystem)."""
        from .build import component_class

        if name in self.subsystems:
            return component_class(self, name, None)
        if name not in self.components:
            raise StudyError(f"{self.where}: no component {name!r}; known: {', '.join(sorted(self.components))}")
        return component_class(self, name, self.components[name].type)

    def parameters(self, name: str) -> dict[str, Any]:
        """Every parameter of component ``name`` in SI: declared defaults, then the study's values
        converted with the declared units (files found as the build finds them)."""
        from .build import resolved_parameters

        cls = self.component_class(name)
        spec = self.components.get(name)
        return {**{k: v.start for k, v in cls.declared("parameter").items()},
                **resolved_parameters(cls, name, spec.parameters if spec else {}, self.where, self.folders)}

    def folders(self) -> tuple[Path, ...]:
        """Where a relative file named in the study is looked for: the study file's folder, then
        the folders of the files it extends, nearest first."""
        out: list[Path] = []
        seen: set[Path] = set()
        path = Path(self.path) if self.path is not None else None
        while path is not None and path.is_file() and path.resolve() not in seen:
            seen.add(path.resolve())
            if path.resolve().parent not in out:
                out.append(path.resolve().parent)
            if path.suffix not in (".toml", ".yaml", ".yml"):
                break
            parent = _read_one(path).get("extends")
            path = path.parent / parent if isinstance(parent, str) else None
        return tuple(out)

    def find(self, *, role: str | None = None, type: type | str | None = None) -> list[str]:
        """Names of the components that declare ``role`` (``Component.roles``) or are of ``type``
        (a class, matched with isinstance semantics, or a type name as written in the study)."""
        found = []
        for name in list(self.components) + list(self.subsystems):
            if isinstance(type, str):
                if self.components.get(name) is None or self.components[name].type != type:
                    continue
                if role is None:
                    found.append(name)
                    continue
            cls = self.component_class(name)
            if type is not None and not isinstance(type, str) and not issubclass(cls, type):
                continue
            extra = self.components[name].roles if name in self.components else []
            if role is not None and role not in getattr(cls, "roles", ()) and role not in extra:
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
    def boundary(self, names: Iterable[str], port_name=lambda comp, port: f"{comp}_{port}"):
        """The group's external wiring: (inputs, outputs, internal connections), where inputs maps an
        exported port to [(comp, input)] and the outside signal feeding it (or None), outputs maps an
        exported port to (comp, output) and the outside inputs it drives."""
        group = set(names)
        missing = sorted(group - set(self.components))
        if missing:
            raise StudyError(f"{self.where}: components {missing} not in the study")
        inputs: dict[str, dict[str, Any]] = {}
        outputs: dict[str, dict[str, Any]] = {}
        internal = []
        fed = {(c.target, c.input): c for c in self.connections}
        for name in self.components:
            if name not in group:
                continue
            cls = self.component_class(name)
            for port in cls.declared("input"):
                conn = fed.get((name, port))
                if conn is not None and conn.source in group:
                    continue
                inputs[port_name(name, port)] = {"targets": [(name, port)],
                                                 "source": (conn.source, conn.output) if conn else None}
            for port in cls.declared("output"):
                outputs[port_name(name, port)] = {"source": (name, port), "drives": []}
        for c in self.connections:
            if c.source in group and c.target in group:
                internal.append(c)
            elif c.source in group:
                outputs[port_name(c.source, c.output)]["drives"].append((c.target, c.input))
        return inputs, outputs, internal

    def extract(self, names: Iterable[str], name: str | None = None,
                port_name=lambda comp, port: f"{comp}_{port}") -> "Study":
        """The group of components as a study of its own with ``exports``: every input not fed
        inside the group and every output of the group, named by ``port_name``."""
        names = list(names)
        inputs, outputs, internal = self.boundary(names, port_name)
        data = self.to_data()
        steps = {self.components[n].step or self.study.base_step for n in names}
        base = min(steps)
        settings = {**data["study"], "name": name or f"{self.study.name}_subsystem", "base_step": base}
        settings.pop("analysis", None)
        settings.pop("realtime", None)
        sub = {"study": settings,
               "components": {n: data["components"][n] for n in names},
               "connections": [str(c) for c in internal],
               "exports": {"inputs": {p: f"{c}.{i}" for p, v in inputs.items() for c, i in v["targets"]},
                           "outputs": {p: f"{c}.{o}" for p, v in outputs.items() for c, o in [v["source"]]}}}
        return self._derive(sub)

    def collapse(self, names: Iterable[str], into: str, type: str, step: float | None = None,
                 port_name=lambda comp, port: f"{comp}_{port}", parameters: Mapping[str, Any] | None = None) -> "Study":
        """This study with the group replaced by one component ``into`` of ``type`` whose ports are
        the group's boundary ports (``port_name``); the outside wiring is kept."""
        names = list(names)
        inputs, outputs, _ = self.boundary(names, port_name)
        add = [f"{v['source'][0]}.{v['source'][1]} -> {into}.{p}" for p, v in inputs.items() if v["source"]]
        add += [f"{into}.{p} -> {t}.{i}" for p, v in outputs.items() for t, i in v["drives"]]
        reduced = self.without(*names)
        spec: dict[str, Any] = {"type": type}
        if step is not None:
            spec["step"] = step
        if parameters:
            spec["parameters"] = dict(parameters)
        return reduced.with_component(into, **spec).with_connections(add=add)


def _pruned(table: dict[str, Any]) -> dict[str, Any]:
    """The table without empty sub-tables (recursively)."""
    out = {}
    for key, value in table.items():
        if isinstance(value, dict):
            value = _pruned(value)
            if not value:
                continue
        out[key] = value
    return out


def _format_validation(path: Path, err: ValidationError) -> str:
    lines = [f"{path}: invalid study file"]
    for e in err.errors():
        loc = ".".join(str(p) for p in e["loc"]) or "(top level)"
        lines.append(f"  field {loc}: {e['msg'].removeprefix('Value error, ')}")
    return "\n".join(lines)


def merge(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    """Deep merge: tables merge key by key, anything else in ``over`` replaces."""
    out = copy.deepcopy(base)
    for key, value in over.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merge(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def read_study_file(path: str | Path, _seen: tuple[Path, ...] = ()) -> dict[str, Any]:
    """Parse a study file; a top-level ``extends = "other.toml"`` (relative to this file) starts
    from that study and merges this file's tables over it (a component given another ``type``
    starts afresh: the parent's parameters of the old type do not carry over)."""
    path = Path(path)
    if path.suffix in (".ssp", ".ssd"):          # an SSP archive or its System Structure Description
        from .ssp import study_data

        return study_data(path)
    data = _read_one(path)
    parent = data.pop("extends", None)
    edits = {k: data.pop(k) for k in ("connections_remove", "connections_add") if k in data}
    if parent is None:
        if edits:
            raise StudyError(f"{path}: field {next(iter(edits))}: only with extends (it edits the parent's connections)")
        return data
    if not isinstance(parent, str):
        raise StudyError(f"{path}: field extends: expected a file name")
    parent_path = (path.parent / parent).resolve()
    if parent_path in _seen:
        raise StudyError(f"{path}: field extends: circular ({' -> '.join(map(str, _seen + (parent_path,)))})")
    base = read_study_file(parent_path, _seen + (path.resolve(),))
    for name, spec in (data.get("components") or {}).items():
        old = (base.get("components") or {}).get(name)
        if isinstance(spec, dict) and isinstance(old, dict) and "type" in spec and spec["type"] != old.get("type"):
            base["components"][name] = {}       # another type: its parameters and inputs start afresh
    merged = merge(base, data)
    if edits:
        merged["connections"] = _edited_connections(merged.get("connections") or [], edits, path)
    return merged


def _edited_connections(connections: list, edits: dict[str, Any], path: Path) -> list:
    """The parent's connections without ``connections_remove`` and with ``connections_add``
    (compared parsed, so spacing does not matter); removing one that is not there is an error."""
    def key(item):
        return tuple(_parse_connections([item])[0].values())

    for field in edits:
        if not isinstance(edits[field], list) or not all(isinstance(x, str) for x in edits[field]):
            raise StudyError(f"{path}: field {field}: expected a list of strings 'component.output -> component.input'")
        try:
            [key(x) for x in edits[field]]
        except ValueError as exc:
            raise StudyError(f"{path}: field {field}: {exc}") from None
    present = {key(c): c for c in connections}
    drop = {key(x) for x in edits.get("connections_remove", [])}
    missing = [x for x in edits.get("connections_remove", []) if key(x) not in present]
    if missing:
        raise StudyError(f"{path}: field connections_remove: {missing[0]!r} is not a connection of the study it extends")
    return [c for c in connections if key(c) not in drop] + list(edits.get("connections_add", []))


def _read_one(path: Path) -> dict[str, Any]:
    """Parse TOML (``.toml``) or YAML (``.yaml``/``.yml``) into a plain dict."""
    if not path.is_file():
        raise StudyError(f"{path}: study file not found")
    text = path.read_text(encoding="utf-8")
    try:
        if path.suffix == ".toml":
            return tomllib.loads(text)
        if path.suffix in (".yaml", ".yml"):
            import yaml

            data = yaml.safe_load(text)
            if not isinstance(data, dict):
                raise StudyError(f"{path}: expected a mapping at the top level")
            return data
    except tomllib.TOMLDecodeError as exc:
        raise StudyError(f"{path}: not valid TOML: {exc}") from None
    except Exception as exc:  # yaml errors
        if isinstance(exc, StudyError):
            raise
        raise StudyError(f"{path}: not valid YAML: {exc}") from None
    raise StudyError(f"{path}: unknown study file type {path.suffix!r}; expected .toml, .yaml or .yml")


def parse_study(data: dict[str, Any], path: str | Path = "<study>") -> Study:
    path = Path(path)
    try:
        study = Study.model_validate(data)
    except ValidationError as err:
        raise StudyError(_format_validation(path, err)) from None
    study.path = path
    return study


def load_study(path: str | Path, overrides: Iterable[str] | None = None) -> Study:
    """Load and validate a study file; ``overrides`` are ``key=value`` strings (``--set``)."""
    return Study.load(path, overrides or ())


def parse_override(item: str, path: str | Path) -> tuple[str, Any]:
    """``comp.param=value`` -> (key, value); the value is read as TOML, else kept as a string."""
    if "=" not in item or "." not in item.split("=", 1)[0]:
        raise StudyError(f"{path}: override {item!r}: expected 'component.parameter=value' or 'study.field=value'")
    key, raw = item.split("=", 1)
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()
    return key.strip(), value


def _set_value(data: dict[str, Any], key: str, value: Any, where: str) -> None:
    """Set one dotted key in study data (see ``Study.with_values``)."""
    parts = key.split(".")
    if len(parts) < 2 or not all(re.fullmatch(_NAME, p) for p in parts):
        raise StudyError(f"{where}: expected 'component.parameter', 'component.inputs.port' or 'study.field'")
    head, rest = parts[0], parts[1:]
    if head == "study":
        if len(rest) != 1:
            raise StudyError(f"{where}: expected 'study.field'")
        data.setdefault("study", {})[rest[0]] = value
        return
    comps = data.get("components", {})
    subs = data.get("subsystems", {})
    if head in comps:
        spec = comps[head]
        if len(rest) == 2 and rest[0] == "inputs":
            spec.setdefault("inputs", {})[rest[1]] = value
        else:
            spec.setdefault("parameters", {})[".".join(rest)] = value
        return
    if head in subs and len(rest) >= 2:
        _set_value(subs[head], ".".join(rest), value, where)
        return
    if head not in ("components", "subsystems") and isinstance(data.get(head), dict) and len(rest) == 1:
        data[head][rest[0]] = value            # a table's field: sweep.mode, my_tool.period
        return
    known = sorted(comps) + sorted(subs)
    raise StudyError(f"{where}: no component {head!r}; known: {', '.join(known)}")
