"""The co-simulation unit contract (FMI-shaped).

A component declares its variables (name, causality, unit, start, description), which outputs
depend directly on which inputs in the same step (direct feedthrough), and whether it is
*sampled* or *continuous*:

- sampled: ``step(t, dt)`` reads the inputs at ``t`` and sets outputs that hold on ``[t, t+dt)``
  (a discrete controller, a sensor, a reference generator);
- continuous: ``step(t, dt)`` integrates from ``t`` to ``t+dt`` with the inputs of ``t`` held;
  afterwards the outputs describe ``t+dt`` (a plant, an actuator).

Inputs live in ``self.u``, outputs in ``self.y``, parameters in ``self.p`` (plain dicts, SI units).
A Python class, an FMU wrapper or a hardware adapter are interchangeable behind this interface.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Mapping

import numpy as np

CAUSALITIES = ("input", "output", "parameter")


@dataclass(frozen=True)
class Variable:
    """One declared variable of a component."""

    name: str
    causality: str
    unit: str
    start: Any
    description: str
    optional: bool = False     # an input that may stay unconnected: it then holds ``start``

    def __post_init__(self) -> None:
        if self.causality not in CAUSALITIES:
            raise ValueError(f"variable {self.name!r}: causality must be one of {CAUSALITIES}")
        if self.optional and self.causality != "input":
            raise ValueError(f"variable {self.name!r}: only an input can be optional")


def inp(name: str, unit: str, start: Any, description: str, optional: bool = False) -> Variable:
    """An input. A connection or a study constant must drive it, unless ``optional``: left
    unconnected it then holds ``start`` for the whole run (said once when the run starts)."""
    return Variable(name, "input", unit, start, description, optional)


def out(name: str, unit: str, start: Any, description: str) -> Variable:
    return Variable(name, "output", unit, start, description)


def par(name: str, unit: str, start: Any, description: str) -> Variable:
    return Variable(name, "parameter", unit, start, description)


class ComponentError(Exception):
    """A component refuses its parameters or fails while stepping."""


class EndRun(Exception):
    """A component asks to end the run where it stands (an FMU's terminate request): not a
    failure; the run stops cleanly at the last instant every component reached."""

    def __init__(self, component: str, reason: str) -> None:
        super().__init__(f"{component}: {reason}")
        self.component, self.reason = component, reason


class Component:
    """Base class of every Python co-simulation unit.

    Subclasses set ``variables`` and ``feedthrough`` (output name -> input names it depends on
    within the same step), ``sampled`` (see module docstring) and implement ``initialize`` and
    ``step``; ``roles`` names what the component is for the tools that look components up
    (``Model.find(role=...)``, orchestrator.model). ``rng`` is a numpy Generator seeded by the
    orchestrator from the study seed.
    """

    variables: ClassVar[tuple[Variable, ...]] = ()
    feedthrough: ClassVar[Mapping[str, tuple[str, ...]]] = {}
    sampled: ClassVar[bool] = True
    roles: ClassVar[tuple[str, ...]] = ()   # what the component is, for lookup by tools (Model.find)
    connected_inputs: frozenset[str] = frozenset()   # inputs a connection drives (set when built)

    def __init__(self, name: str, parameters: Mapping[str, Any] | None = None,
                 rng: np.random.Generator | None = None) -> None:
        self.name = name
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self.p: dict[str, Any] = {v.name: v.start for v in self.variables if v.causality == "parameter"}
        self.u: dict[str, Any] = {v.name: v.start for v in self.variables if v.causality == "input"}
        self.y: dict[str, Any] = {v.name: v.start for v in self.variables if v.causality == "output"}
        self.events: list[tuple[float, str]] = []
        for key, value in (parameters or {}).items():
            if key not in self.p:
                raise ComponentError(f"{name}: unknown parameter {key!r}; known: {sorted(self.p)}")
            self.p[key] = value

    # --- declarations -------------------------------------------------------------------------
    @classmethod
    def declared(cls, causality: str) -> dict[str, Variable]:
        return {v.name: v for v in cls.variables if v.causality == causality}

    # --- life cycle ---------------------------------------------------------------------------
    def initialize(self, t0: float, dt: float) -> None:
        """Prepare internal state for a run starting at ``t0`` with step ``dt``."""

    def step(self, t: float, dt: float) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    # A sampled hardware adapter may also define ``actuate(t)``: called at the end of each of its
    # instants, after every sampled component has stepped and with its inputs refreshed, so that
    # it reads its sensors in ``step`` (first) and writes the commands of the same instant here
    # (last): read - compute - write in one cycle, as a real-time target does.
    actuate = None

    # A sampled component may also define ``advance(t, dt)``: called after the instant's outputs are
    # recorded, with its inputs refreshed (every value of t, as a continuous component sees them),
    # to move its state over [t, t + dt) (an FMU: set the inputs of t, doStep). ``step`` then only
    # computes the outputs of t (get after set), which holds for any co-simulation FMU.
    advance = None

    def terminate(self) -> None:
        """Release what the component holds (ports, sockets, buses); called once after a run."""

    def reset(self) -> None:
        """Return inputs and outputs to their start values (parameters are kept)."""
        self.events = []
        for v in self.variables:
            if v.causality == "input":
                self.u[v.name] = v.start
            elif v.causality == "output":
                self.y[v.name] = v.start

    # --- helpers for subclasses ---------------------------------------------------------------
    def event(self, t: float, message: str) -> None:
        """Log why something happened (a watchdog tripping, a link lost); the runner writes
        every component's events to events.log."""
        self.events.append((float(t), message))

    def require(self, condition: bool, message: str) -> None:
        if not condition:
            raise ComponentError(f"{self.name}: {message}")
