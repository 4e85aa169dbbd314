"""The schema of a study file: each table's fields, validated with pydantic (names, steps,
connections ``"src.output -> dst.input"``, exported ports, sweep ranges). Only data: nothing here
knows what a component type is."""
from __future__ import annotations

import math
import re
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

NAME = r"[A-Za-z_]\w*"
# a port: an identifier or an FMI structured name (``body.speed``, ``x[2]``, ``a.b[1,3].c``)
INDEX = r"(?:\[\d+(?:,\d+)*\])?"
PORT_NAME = rf"{NAME}{INDEX}(?:\.{NAME}{INDEX})*"
CONNECTION = re.compile(rf"^\s*({NAME})\.({PORT_NAME})\s*->\s*({NAME})\.({PORT_NAME})\s*$")
PORT = re.compile(rf"^\s*({NAME})\.({PORT_NAME})\s*$")
SUBSYSTEM_SUFFIXES = (".toml", ".yaml", ".yml")
# a bound on a key figure: a comparison and a number, then any words ("< 0.40", ">= 0.99 (target)");
# a bare number means "==" (orchestrator.key_figures)
BOUND = re.compile(r"^\s*(<=|>=|==|<|>|=)?\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)(?![\w.])")


class StudySettings(BaseModel):
    model_config = ConfigDict(extra="forbid")
    name: str                        # names the run in its results
    description: str = ""
    start_time: float = Field(default=0.0, allow_inf_nan=False)   # s
    stop_time: float = Field(gt=0, allow_inf_nan=False)           # s
    base_step: float = Field(gt=0, allow_inf_nan=False)           # s: every component step is a multiple
    seed: int = Field(ge=0)          # every random stream is seeded from it and the component's name
    signals_format: Literal["parquet", "csv"] = "parquet"        # the signal table's file format
    component_package: str | None = None   # look types up here first (default: registered packages)
    components_path: str | None = None     # a folder of the user's own component modules, relative to the study file
    analysis: str | None = None      # module with the study's metrics and figures (analysis.figure8)
    realtime: bool = False           # pace the base step against the wall clock
    realtime_tolerance: float = Field(default=0.002, ge=0)   # s: lateness that counts as a deadline miss
    bounds: dict[str, str] = {}      # key figure -> "< 0.30": judged after the run (orchestrator.key_figures)
    isolate_fmus: bool | None = None   # each co-simulation FMU in a child process (a crash or a hang a named error);
    #                                    default: those from outside the project; false: none (faster, said when run)
    fmu_timeout: float = Field(default=60.0, gt=0, allow_inf_nan=False)   # s an isolated FMU's call may take
    allow_unconnected: list[str] = []   # "component.input"s that may stay unconnected: they hold their start value

    @field_validator("bounds")
    @classmethod
    def _bounds(cls, value: dict[str, str]) -> dict[str, str]:
        for key, text in value.items():
            if not BOUND.match(text):
                raise ValueError(f"bound {key} = {text!r}: expected a comparison and a number, e.g. '< 0.40' or '>= 0.99'")
        return value

    @field_validator("allow_unconnected")
    @classmethod
    def _ports(cls, value: list[str]) -> list[str]:
        for item in value:
            if not PORT.match(item):
                raise ValueError(f"allow_unconnected: {item!r}: expected 'component.input'")
        return [item.strip() for item in value]

    @model_validator(mode="after")
    def _times(self) -> "StudySettings":
        if self.stop_time <= self.start_time:
            raise ValueError(f"stop_time ({self.stop_time}) must be after start_time ({self.start_time})")
        if self.base_step > self.stop_time - self.start_time:
            raise ValueError("base_step is longer than the run")
        return self


class ComponentSpec(BaseModel):
    model_config = ConfigDict(extra="forbid")
    type: str                      # a component type, "package.module:Class", an .fmu or a study file
    step: float | None = Field(default=None, gt=0)   # s (default: the base step)
    parameters: dict[str, Any] = {}   # declared parameter -> value (a number in SI or "30 deg")
    inputs: dict[str, Any] = {}    # unconnected input -> constant value
    roles: list[str] = []          # roles besides the class's own (an FMU that plays a role a tool looks up)


class Connection(BaseModel):
    source: str
    output: str
    target: str
    input: str

    def __str__(self) -> str:
        return f"{self.source}.{self.output} -> {self.target}.{self.input}"


def parse_connections(value: Any) -> Any:
    if not isinstance(value, list):
        raise ValueError("expected a list of strings 'component.output -> component.input'")
    parsed = []
    for i, item in enumerate(value):
        if isinstance(item, str):
            match = CONNECTION.match(item)
            if not match:
                raise ValueError(f"item {i} {item!r}: expected 'component.output -> component.input'")
            parsed.append(dict(zip(("source", "output", "target", "input"), match.groups())))
        else:
            parsed.append(item)
    return parsed


def check_component_names(value: dict[str, Any]) -> dict[str, Any]:
    for name in value:
        if not re.fullmatch(NAME, name):
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
    roles: list[str] = []          # what the subsystem is, for Model.find (Component.roles)

    @model_validator(mode="after")
    def _ports(self) -> "Exports":
        for kind, table in (("inputs", self.inputs), ("outputs", self.outputs)):
            for name, target in table.items():
                if not re.fullmatch(NAME, name):
                    raise ValueError(f"{kind}.{name}: an exported port name must be an identifier")
                items = target.targets if isinstance(target, ExportedInput) else \
                    [target] if isinstance(target, str) else target
                for item in items:
                    if not PORT.match(item):
                        raise ValueError(f"{kind}.{name} = {item!r}: expected 'component.port'")
        return self

    def input_targets(self, name: str) -> list[tuple[str, str]]:
        value = self.inputs[name]
        items = value.targets if isinstance(value, ExportedInput) else [value] if isinstance(value, str) else value
        return [PORT.match(v).groups() for v in items]

    def output_source(self, name: str) -> tuple[str, str]:
        return PORT.match(self.outputs[name]).groups()


class SubsystemSpec(BaseModel):
    """An inline subsystem: a component of the study that is itself a small study."""

    model_config = ConfigDict(extra="forbid")
    step: float | None = Field(default=None, gt=0)
    base_step: float | None = Field(default=None, gt=0)   # default: the subsystem's step
    description: str = ""
    components: dict[str, ComponentSpec]
    connections: list[Connection] = []
    exports: Exports

    _connections = field_validator("connections", mode="before")(classmethod(lambda cls, v: parse_connections(v)))
    _names = field_validator("components")(classmethod(lambda cls, v: check_component_names(v)))


MAX_SWEEP_POINTS = 1_000_000     # a sweep's points at most: its table and folders are held and listed


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

    def count(self) -> float:
        """How many values (computed, not listed: a range of 10^12 values is refused by its count)."""
        if self.num is not None:
            return float(self.num)
        return math.floor((self.stop - self.start) / self.step + 1e-9) + 1.0

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
        points = self.points()
        if points > MAX_SWEEP_POINTS:
            raise ValueError(f"{points:.3g} points ({self._how()}), more than the {MAX_SWEEP_POINTS:,} a sweep may hold "
                             f"(each point is a row of the sweep's table and a folder); split the sweep")
        return self

    def _counts(self) -> list[float]:
        return [v.count() if isinstance(v, SweepRange) else 1.0 if isinstance(v, Uniform) else float(len(v))
                for v in self.parameters.values()]

    def points(self) -> float:
        """How many points the sweep has (before any is made): samples x seeds, the grid's product or
        the zip's length."""
        seeds = float(len(self.seeds)) if self.seeds else 1.0
        if self.mode == "monte_carlo":
            return float(self.samples or 0)            # each draw has its own seed
        counts = self._counts()
        return (math.prod(counts) if self.mode == "grid" else min(counts, default=0.0)) * seeds

    def _how(self) -> str:
        if self.mode == "monte_carlo":
            return f"samples = {self.samples}"
        return " x ".join(f"{k}: {c:.3g}" for k, c in zip(self.parameters, self._counts()))

    @field_validator("parameters")
    @classmethod
    def _names(cls, value: dict[str, Any]) -> dict[str, Any]:
        if not value:
            raise ValueError("a sweep needs at least one parameter")
        for name, values in value.items():
            if not re.fullmatch(rf"{NAME}(\.{NAME})+", name):
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


# the orchestrator's own top-level tables; any other table of a study file belongs to a tool
TABLES = ("study", "components", "connections", "sweep", "exports", "subsystems")
