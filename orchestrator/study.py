"""Study files: declarative description of a co-simulation (TOML or YAML), validated with pydantic.

Layout::

    [study]            name, stop_time, base_step, seed, start_time, signals_format, analysis
    [components.NAME]  type = "module" or "package.module:Class", step, parameters = {...},
                       inputs = {...}   (constant values for inputs left unconnected)
    connections = ["src.output -> dst.input", ...]
"""
from __future__ import annotations

import copy
import math
import re
import tomllib
from pathlib import Path
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator


class StudyError(Exception):
    """A study cannot be loaded or built; the message names the file and the field."""


_CONNECTION = re.compile(r"^\s*([A-Za-z_][\w]*)\.([A-Za-z_][\w]*)\s*->\s*([A-Za-z_][\w]*)\.([A-Za-z_][\w]*)\s*$")


class StudySettings(BaseModel):
    model_config = ConfigDict(extra="forbid")
    name: str
    description: str = ""
    start_time: float = 0.0
    stop_time: float = Field(gt=0)
    base_step: float = Field(gt=0)
    seed: int = Field(ge=0)
    signals_format: Literal["parquet", "csv"] = "parquet"
    component_package: str = "components"
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


class Connection(BaseModel):
    source: str
    output: str
    target: str
    input: str

    def __str__(self) -> str:
        return f"{self.source}.{self.output} -> {self.target}.{self.input}"


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


class Sweep(BaseModel):
    model_config = ConfigDict(extra="forbid")
    mode: Literal["grid", "zip"] = "grid"
    parameters: dict[str, list[Any] | SweepRange]
    seeds: list[int] | None = None
    analysis: str | None = None

    @field_validator("parameters")
    @classmethod
    def _names(cls, value: dict[str, Any]) -> dict[str, Any]:
        if not value:
            raise ValueError("a sweep needs at least one parameter")
        for name, values in value.items():
            if not re.fullmatch(r"[A-Za-z_]\w*\.[A-Za-z_]\w*", name):
                raise ValueError(f"{name!r}: expected 'component.parameter' or 'study.field'")
            if isinstance(values, list) and not values:
                raise ValueError(f"{name!r}: empty list of values")
        return value

    def expanded(self) -> dict[str, list[Any]]:
        return {k: (v.values() if isinstance(v, SweepRange) else list(v)) for k, v in self.parameters.items()}


class Study(BaseModel):
    model_config = ConfigDict(extra="forbid")
    study: StudySettings
    components: dict[str, ComponentSpec]
    connections: list[Connection] = []
    sweep: Sweep | None = None
    identification: dict[str, Any] | None = None   # validated by the identification tool
    path: Path | None = None

    @field_validator("connections", mode="before")
    @classmethod
    def _parse_connections(cls, value: Any) -> Any:
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

    @field_validator("components")
    @classmethod
    def _names(cls, value: dict[str, ComponentSpec]) -> dict[str, ComponentSpec]:
        if not value:
            raise ValueError("a study needs at least one component")
        for name in value:
            if not re.fullmatch(r"[A-Za-z_]\w*", name):
                raise ValueError(f"component name {name!r} must be an identifier")
        return value


def _format_validation(path: Path, err: ValidationError) -> str:
    lines = [f"{path}: invalid study file"]
    for e in err.errors():
        loc = ".".join(str(p) for p in e["loc"]) or "(top level)"
        lines.append(f"  field {loc}: {e['msg']}")
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
    from that study and merges this file's tables over it."""
    path = Path(path)
    data = _read_one(path)
    parent = data.pop("extends", None)
    if parent is None:
        return data
    if not isinstance(parent, str):
        raise StudyError(f"{path}: field extends: expected a file name")
    parent_path = (path.parent / parent).resolve()
    if parent_path in _seen:
        raise StudyError(f"{path}: field extends: circular ({' -> '.join(map(str, _seen + (parent_path,)))})")
    return merge(read_study_file(parent_path, _seen + (path.resolve(),)), data)


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


def load_raw(path: str | Path, overrides: list[str] | None = None) -> dict[str, Any]:
    """The study file as data (``extends`` resolved), with ``component.parameter=value`` overrides."""
    data = read_study_file(path)
    for item in overrides or []:
        apply_override(data, item, path)
    return data


def load_study(path: str | Path, overrides: list[str] | None = None) -> Study:
    """Load and validate a study file; ``overrides`` are ``component.parameter=value`` strings."""
    return parse_study(load_raw(path, overrides), path)


def apply_override(data: dict[str, Any], item: str, path: str | Path) -> None:
    """Set ``comp.param=value`` or ``study.field=value`` in raw study data (value parsed as TOML)."""
    if "=" not in item or "." not in item.split("=", 1)[0]:
        raise StudyError(f"{path}: override {item!r}: expected 'component.parameter=value'")
    key, raw = item.split("=", 1)
    section, field = key.strip().split(".", 1)
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()
    if section in ("study", "identification"):
        data.setdefault(section, {})[field] = value
        return
    comps = data.get("components", {})
    if section not in comps:
        raise StudyError(f"{path}: override {item!r}: no component {section!r}; known: {sorted(comps)}")
    comps[section].setdefault("parameters", {})[field] = value
