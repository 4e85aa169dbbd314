"""What the compiled engine asks of a component: its C model core. A component class that has one
says so itself, ``c_core = CoreDescription(Path(__file__).with_suffix(".c"), ...)``: the C file beside
its module, what is fixed when the code is generated, and which parameters the core does not model.
The same description serves the compiled engine (``c_core``) and the FMU exporter.

A core is one C translation unit's worth of text that defines ``ModelState``, ``model_start(st,
p)``, ``model_sample(st, p, in, out)`` (outputs y_k = g(x_k, u_k), then x_k+1 = f(x_k, u_k)) and,
for a continuous component, ``model_outputs(st, p, out)`` (y_k = g(x_k) alone) with
``MODEL_HAS_OUTPUTS`` defined. It reads its parameters as ``p[P_name]``, its inputs as
``in[IN_name]``, its outputs as ``out[OUT_name]`` and its period as ``MODEL_PERIOD``: the loop
generator (orchestrator.compiled.generate) defines those macros.

Every numeric parameter of a component with a core is one of: read by the core (``P_name`` in its C
files), fixed at generation (``compiled_parameters``: read by ``compiled`` or ``runtime``), or not
modelled (``not_compiled``): a study that sets one of those away from its default has no C form, and
the engine and the exporter refuse it, naming the parameter, instead of silently running without it.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from ..errors import InputError


class NoCCore(InputError):
    """A component that has no C core as configured (the message says why)."""


@dataclass
class CCore:
    source: str                                   # C text: shape-fixing #defines and the core's #include
    parameters: list[tuple[str, float]]           # (name, value) in P_ order: run-time values
    inputs: list[str]                             # input names in IN_ order
    outputs: list[str]                            # output names in OUT_ order
    include_dirs: list[Path] = field(default_factory=list)
    files: list[Path] = field(default_factory=list)   # every file the source includes (the cache key reads them)


def _no_defines(comp, period: float) -> str:
    return ""


@dataclass(frozen=True)
class CoreDescription:
    """How a component class becomes a C model core (declared on the class as ``c_core``)."""

    source: Path                                                  # the core's C file
    compiled: Callable[[object, float], str] = _no_defines        # C #defines of values fixed at generation
    compiled_parameters: tuple[str, ...] = ()                     # parameters read by ``compiled`` / ``runtime``
    not_compiled: tuple[str, ...] = ()                            # parameters the core does not model
    values: Callable[[object], dict[str, float]] | None = None    # parameter values overriding comp.p
    extra_parameters: tuple[tuple[str, float, str, str], ...] = ()   # core-only parameters (a seed)
    extra_values: Callable[[object, str], dict[str, float]] | None = None
    dependencies: Callable[[object], dict[str, list[str]]] | None = None   # default: the declared feedthrough
    extra_sources: tuple[Path, ...] = ()                          # C files the core includes
    # the compiled loop: #defines that replace ``compiled``'s, reading the values that vary from run to
    # run (a delay length) as run-time parameters, and those values
    runtime: Callable[[object, float], tuple[str, dict[str, float]]] | None = None

    @property
    def files(self) -> tuple[Path, ...]:
        return (self.source, *self.extra_sources)

    @property
    def include_dirs(self) -> list[Path]:
        return sorted({f.parent for f in self.files})


def description_of(comp) -> CoreDescription | None:
    """The ``c_core`` the component's own class declares (a subclass with other equations declares
    its own; one that declares none has no C form)."""
    found = vars(type(comp)).get("c_core")
    return found if isinstance(found, CoreDescription) else None


def check_compiled(comp, description: CoreDescription) -> None:
    """NoCCore naming the first parameter the core does not model that the study sets away from its
    default."""
    for name in description.not_compiled:
        default = comp.declared("parameter")[name].start
        if comp.p[name] != default:
            raise NoCCore(f"{name} = {comp.p[name]!r} has no C form: its core {description.source.name} does not "
                          f"model it (only the Python form does; the core runs the default, {default!r})")


def _numeric(value) -> bool:
    return isinstance(value, (bool, int, float, np.number))


def core_parameters(comp, description: CoreDescription, where: str) -> list[tuple[str, float, str, str]]:
    """(name, value, unit, description) of the core's run-time parameters: the component's numeric
    parameters neither fixed at generation nor unmodelled, then the core's own (a seed). ``where``
    prefixes the message of a parameter that is not a number."""
    values = {**comp.p, **(description.values(comp) if description.values else {})}
    skipped = set(description.compiled_parameters) | set(description.not_compiled)
    parameters = []
    for v in comp.variables:
        if v.causality != "parameter" or v.name in skipped:
            continue
        value = values[v.name]
        if not _numeric(value):
            raise NoCCore(f"{where}parameters.{v.name} = {value!r}: not a number; the C form takes numeric "
                          f"parameters only")
        parameters.append((v.name, float(value), v.unit or "1", v.description))
    extra = dict(description.extra_values(comp, comp.name)) if description.extra_values else {}
    return parameters + [(n, extra.get(n, start), unit, text) for n, start, unit, text in description.extra_parameters]


def c_core(system, name: str) -> CCore:
    """The C core of study component ``name`` for the compiled loop (NoCCore with the reason when it
    has none)."""
    node = system.nodes[name]
    comp, period = node.component, float(node.step)
    description = description_of(comp)
    if description is None:
        raise NoCCore(f"type {type(comp).__name__} has no C core")
    check_compiled(comp, description)
    parameters = [(n, v) for n, v, _, _ in core_parameters(comp, description, "")]
    if description.runtime is not None:
        defines, runtime = description.runtime(comp, period)
    else:
        defines, runtime = description.compiled(comp, period), {}
    inputs = [v.name for v in comp.variables if v.causality == "input"]
    outputs = [v.name for v in comp.variables if v.causality == "output"]
    return CCore(f'{defines}#include "{description.source.name}"\n', parameters + list(runtime.items()), inputs,
                 outputs, description.include_dirs, list(description.files))


def capacity(n: int) -> int:
    """Room of a buffer whose length is a run-time value: 32, or the next power of two (a few
    shapes cover every length a sweep draws)."""
    return 32 if n <= 32 else 1 << (n - 1).bit_length()


def c_array(values) -> str:
    """Numbers as the body of a C double array initialiser (repr: every digit kept)."""
    return ", ".join(repr(float(v)) for v in np.asarray(values, dtype=float).ravel())
