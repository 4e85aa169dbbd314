"""The Study: the one description of a co-simulation, and the one way to derive a variant of it.

Layout of a study file (TOML or YAML, or an SSP; read by orchestrator.study_files, validated
with the schema of orchestrator.study_schema)::

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
    [TOOL]                  any other table: a tool's, kept as written (``section(name)``)

A Study is a description only: parsing it resolves no type and needs no plugin (a tool's table
is checked against the installed tools when the study is resolved, orchestrator.resolver). A
``Study`` is immutable in use: ``with_values``, ``with_component``, ``replace_component``,
``without``, ``with_connections`` and ``subsystem`` return new studies; ``to_toml`` writes one
back. Parameters keep the values as written ("8000 N/rad", "30 deg"); the resolved model
(orchestrator.model) converts them to SI with the component's declared units.

A ``--set`` of a component parameter is checked against the component's class before the item is
said applied: the check is registered in ``SET_PARAMETER_CHECKS`` by orchestrator.resolver, which
knows the classes (a study itself resolves none).
"""
from __future__ import annotations

import copy
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping

import tomli_w
from pydantic import BaseModel, ConfigDict, PrivateAttr, ValidationError, field_validator, model_validator

from .errors import did_you_mean
from .study_files import (StudyError, lookup, parse_override, pruned, read_study_file, set_value,
                          study_folders)
from .study_schema import (CONNECTION, TABLES, ComponentSpec, Connection, Exports, StudySettings,
                           SubsystemSpec, Sweep, check_component_names, parse_connections)

__all__ = ["Study", "StudyError", "load_study", "parse_study"]


class _Memo(dict):
    """What was derived from a study and can be derived again: no part of its value (equal to any
    other memo, copied and pickled empty)."""

    __hash__ = None

    def __eq__(self, other: object) -> bool:
        return isinstance(other, _Memo)

    def __deepcopy__(self, memo: dict) -> "_Memo":
        return _Memo()

    def __reduce__(self):
        return _Memo, ()


class Study(BaseModel):
    model_config = ConfigDict(extra="forbid")
    study: StudySettings
    components: dict[str, ComponentSpec] = {}
    connections: list[Connection] = []
    sweep: Sweep | None = None
    exports: Exports | None = None
    subsystems: dict[str, SubsystemSpec] = {}
    sections: dict[str, dict[str, Any]] = {}    # the tools' tables ([my_tool]), as written
    path: Path | None = None
    # what resolvers made of this study (orchestrator.resolver keeps its model here: a study is
    # immutable in use, so its types are resolved once)
    _resolved: _Memo = PrivateAttr(default_factory=_Memo)
    # field (as the schema names it) -> the --set item that gave its value, for the messages
    _set_by: _Memo = PrivateAttr(default_factory=_Memo)

    def __copy__(self) -> "Study":
        copied = super().__copy__()
        copied._resolved = _Memo()          # a copy may be changed (model_copy(update=...))
        return copied

    @model_validator(mode="before")
    @classmethod
    def _tool_tables(cls, data: Any) -> Any:
        """Top-level tables other than the orchestrator's go to ``sections``, kept as written
        (whose they are is checked when the study is resolved); a top-level value that is not a
        table is refused by name."""
        if not isinstance(data, dict):
            return data
        data = dict(data)
        sections = dict(data.pop("sections", {}) or {})
        for key in [k for k in data if k not in TABLES and k != "path"]:
            value = data.pop(key)
            if not isinstance(value, dict):
                raise ValueError(f"unknown field {key!r}; a study has the tables {', '.join(TABLES)} "
                                 f"and the tables of its tools")
            sections[key] = value
        data["sections"] = sections
        return data

    _connections = field_validator("connections", mode="before")(classmethod(lambda cls, v: parse_connections(v)))

    @field_validator("components")
    @classmethod
    def _names(cls, value: dict[str, ComponentSpec]) -> dict[str, ComponentSpec]:
        return check_component_names(value)

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
        is read as TOML, else as a string), validated once. A field an override set is blamed on
        the override in every message about it (``origin``), here and when the study is resolved."""
        data = read_study_file(path)
        set_by, applied = _overridden(data, overrides, path)
        return _announced(parse_study(data, path, set_by), applied)

    def with_overrides(self, overrides: Iterable[str]) -> "Study":
        """This study with ``--set`` items applied (blamed on the items in messages, as by ``load``)."""
        data = self.to_data()
        set_by, applied = _overridden(data, overrides, self.where)
        study = parse_study(data, self.path if self.path is not None else "<study>", {**self._set_by, **set_by})
        return _announced(study, applied)

    def origin(self, field: str) -> str:
        """Where the value of ``field`` (``components.tracker.parameters.lookahead``) was given,
        for a message: ``--set ITEM`` or ``FILE: FIELD``."""
        item = self._set_by.get(field)
        return f"--set {item} ({field})" if item is not None else f"{self.where}: {field}"

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
        overlay: dict[str, Any] = {"extends": Path(self.path).resolve().as_posix()}
        skeleton = {"components": {n: {} for n in self.components}, "subsystems": {n: {"components": {
            c: {} for c in s.components}} for n, s in self.subsystems.items()}, "study": {},
            **{k: {} for k in self.sections}}
        for key, value in values.items():
            set_value(skeleton, key, value, f"{self.where}: {key!r}")
        overlay.update(pruned(skeleton))
        return header + tomli_w.dumps(overlay)

    def derive(self, data: dict[str, Any]) -> "Study":
        """A study from a study file's data (``to_data``), read as if it stood beside this one."""
        return parse_study(data, self.path if self.path is not None else "<study>")

    # --- variants -----------------------------------------------------------------------------
    def with_values(self, values: Mapping[str, Any]) -> "Study":
        """Set values by dotted key: ``study.FIELD``, ``COMP.PARAM``, ``COMP.inputs.PORT``,
        ``SUBSYSTEM.COMP.PARAM`` (an inline subsystem's component), ``TABLE.FIELD`` (a tool's table)."""
        data = self.to_data()
        for key, value in values.items():
            set_value(data, key, value, f"{self.where}: {key!r}")
        return self.derive(data)

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
        return self.derive(data)

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
        return self.derive(data)

    def without(self, *names: str) -> "Study":
        """Drop components or subsystems (with every connection touching them and the inputs of
        theirs the study lets hold) or whole tables (``sweep``, ``exports``, a tool's table)."""
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
        held = data.get("study", {}).get("allow_unconnected")
        if held:
            data["study"]["allow_unconnected"] = [item for item in held if item.split(".", 1)[0] not in gone]
        return self.derive(data)

    def with_connections(self, add: Iterable[str] = (), remove: Iterable[str] = ()) -> "Study":
        """Add connection strings, remove connections (given as strings, compared parsed)."""
        drop = {str(Connection(**dict(zip(("source", "output", "target", "input"), CONNECTION.match(r).groups()))))
                for r in remove}
        data = self.to_data()
        data["connections"] = [str(c) for c in self.connections if str(c) not in drop] + list(add)
        return self.derive(data)

    # --- tool tables --------------------------------------------------------------------------
    def section(self, name: str) -> dict[str, Any] | None:
        """A registered tool's table, or None when the study has none."""
        return self.sections.get(name)


    def folders(self) -> tuple[Path, ...]:
        """Where a relative file named in the study is looked for: the study file's folder, then
        the folders of the files it extends, nearest first."""
        return study_folders(self.path)

    def file_path(self, text: str) -> Path:
        """A file named in the study (an FMU or a subsystem as a component's type): relative to
        the study file."""
        path = Path(text)
        return path if path.is_absolute() or self.path is None else Path(self.path).parent / path

    def subsystem(self, name: str) -> "Study":
        """The inline ``[subsystems.NAME]`` block as a study of its own (times, seed and component
        package from this study)."""
        spec = self.subsystems[name]
        s = self.study
        data: dict[str, Any] = {
            "study": {"name": f"{s.name}.{name}", "description": spec.description, "start_time": s.start_time,
                      "stop_time": s.stop_time, "base_step": spec.base_step or spec.step or s.base_step,
                      "seed": s.seed,
                      "allow_unconnected": [a.split(".", 1)[1] for a in s.allow_unconnected
                                            if a.startswith(f"{name}.") and a.count(".") >= 2]},
            "components": {k: v.model_dump(exclude_unset=True) for k, v in spec.components.items()},
            "connections": [str(c) for c in spec.connections],
            "exports": spec.exports.model_dump(),
        }
        if s.component_package:
            data["study"]["component_package"] = s.component_package
        return self.derive(data)


_UNSET = object()


def _overridden(data: dict[str, Any], overrides: Iterable[str], path) -> tuple[dict[str, str], list[str]]:
    """Apply ``--set`` items to study data: (field -> item, one line per item saying what it changed,
    printed by ``_announced`` once the study is known valid)."""
    set_by, applied = {}, []
    for item in overrides:
        key, value = parse_override(item, path)
        before = copy.deepcopy(data)
        field = set_value(data, key, value, f"--set {item}")
        set_by[field] = item
        old = lookup(before, field, _UNSET)
        was = "not set in the file (the default)" if old is _UNSET else repr(old)
        kind = " (read as a string)" \
            if isinstance(value, str) and not item.split("=", 1)[1].strip().startswith(('"', "'")) else ""
        applied.append(f"--set {item}: {field} = {value!r}{kind}, was {was}")
    return set_by, applied


SET_PARAMETER_CHECKS: list[Callable[["Study"], None]] = []
"""Checks of what the ``--set`` items name, run before they are said applied (registered by the
modules that know the component classes: orchestrator.resolver)."""


def _announced(study: "Study", applied: list[str]) -> "Study":
    """Print what the ``--set`` items changed, after the study is parsed and each parameter an item
    sets is one its component declares (a misspelt name is refused with nothing said applied)."""
    if applied:
        for check in SET_PARAMETER_CHECKS:
            check(study)
        print("\n".join(applied))
    return study


def _format_validation(path: Path, err: ValidationError, set_by: Mapping[str, str]) -> str:
    """One line per error; an error in a field an override set names the override (and, for a
    field the table does not have, the nearest ones it has)."""
    file_lines, set_lines = [], []
    for e in err.errors():
        loc = ".".join(str(p) for p in e["loc"]) or "(top level)"
        message = e["msg"].removeprefix("Value error, ")
        item = next((i for f, i in set_by.items() if loc == f or loc.startswith(f + ".") or f.startswith(loc + ".")),
                    None)
        if item is None:
            file_lines.append(f"  field {loc}: {message}")
            continue
        if e["type"] == "extra_forbidden" and len(e["loc"]) >= 2:
            table = Study
            for part in e["loc"][:-1]:
                annotation = table.model_fields.get(str(part)) if isinstance(table, type) else None
                table = annotation.annotation if annotation is not None else None
            fields = sorted(table.model_fields) if isinstance(table, type) and issubclass(table, BaseModel) else []
            message = f"{'.'.join(map(str, e['loc'][:-1]))} has no field {str(e['loc'][-1])!r}" \
                + did_you_mean(e["loc"][-1], fields, form=" (did you mean {}?)") \
                + (f"; its fields: {', '.join(fields)}" if fields else "")
        set_lines.append(f"--set {item}: {message}" if e["type"] == "extra_forbidden" else
                         f"--set {item} ({loc}): {message}")
    if not file_lines:
        return "\n".join(set_lines)
    return "\n".join(set_lines + [f"{path}: invalid study file"] + file_lines)


def parse_study(data: dict[str, Any], path: str | Path = "<study>", set_by: Mapping[str, str] | None = None) -> Study:
    path = Path(path)
    try:
        study = Study.model_validate(data)
    except ValidationError as err:
        raise StudyError(_format_validation(path, err, set_by or {})) from None
    study.path = path
    study._set_by = _Memo(set_by or {})
    return study


def load_study(path: str | Path, overrides: Iterable[str] | None = None) -> Study:
    """Load and validate a study file; ``overrides`` are ``key=value`` strings (``--set``)."""
    return Study.load(path, overrides or ())
