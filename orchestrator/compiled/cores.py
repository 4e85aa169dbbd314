"""What the compiled engine asks of a component: its C model core (``CCore``), from the providers
a project registers (``register_core_provider``; a provider is called with the system and a
component's name and returns its core or raises ``NoCCore`` with the reason).

A core is one C translation unit's worth of text that defines ``ModelState``, ``model_start(st,
p)``, ``model_sample(st, p, in, out)`` (outputs y_k = g(x_k, u_k), then x_k+1 = f(x_k, u_k)) and,
for a continuous component, ``model_outputs(st, p, out)`` (y_k = g(x_k) alone) with
``MODEL_HAS_OUTPUTS`` defined. It reads its parameters as ``p[P_name]``, its inputs as
``in[IN_name]``, its outputs as ``out[OUT_name]`` and its period as ``MODEL_PERIOD``: the loop
generator (orchestrator.compiled.generate) defines those macros.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

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


Provider = Callable[[object, str], CCore]
_PROVIDERS: list[Provider] = []


def register_core_provider(provider: Provider) -> None:
    """A project's C cores: ``provider(system, name)`` returns the core of component ``name``."""
    if provider not in _PROVIDERS:
        _PROVIDERS.append(provider)


def c_core(system, name: str) -> CCore:
    """The C core of component ``name`` (NoCCore with the reason when it has none)."""
    from ..registry import registry

    registry()                        # the plugins register their providers when loaded
    reasons = []
    for provider in _PROVIDERS:
        try:
            return provider(system, name)
        except NoCCore as exc:
            reasons.append(str(exc))
    raise NoCCore("; ".join(reasons) or "no C core provider is registered")
