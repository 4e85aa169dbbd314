"""A small fixed-step co-simulation orchestrator: components with declared ports, wired from a
study file. A library: it knows nothing of the system it simulates; a project registers its
components and tools (orchestrator.registry).

    study = load_study("my.toml")          # a description (orchestrator.study)
    model = resolve(study)                 # every component's class found once (orchestrator.resolver)
    system = build_system(model)           # instances, wired and ordered (orchestrator.build)
    recording = Simulation(system).run()   # the master algorithm (orchestrator.engine)

Importing the package loads the description only; ``resolve``, ``build_system``, ``Simulation``
and ``Model`` are loaded from their modules when first named.
"""
import importlib

from .component import Component, ComponentError, Variable, inp, out, par
from .study import Study, StudyError, load_study, parse_study

_LATER = {"Model": "model", "resolve": "resolver", "build_system": "build", "Simulation": "engine"}

__all__ = ["Component", "ComponentError", "Variable", "inp", "out", "par", "Study", "StudyError",
           "load_study", "parse_study", *_LATER]


def __getattr__(name: str):
    if name in _LATER:
        return getattr(importlib.import_module(f".{_LATER[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
