"""A small fixed-step co-simulation orchestrator: components with declared ports, wired from a
study file. A library: it knows nothing of the system it simulates; a project registers its
components and tools (orchestrator.registry).

    study = load_study("my.toml")          # a description (orchestrator.study)
    model = resolve(study)                 # every component's class found once (orchestrator.resolver)
    system = build_system(model)           # instances, wired and ordered (orchestrator.build)
    recording = Simulation(system).run()   # the master algorithm (orchestrator.engine)
"""
from .build import build_system
from .component import Component, ComponentError, Variable, inp, out, par
from .engine import Simulation
from .model import Model
from .resolver import resolve
from .study import Study, StudyError, load_study, parse_study

__all__ = ["Component", "ComponentError", "Variable", "inp", "out", "par", "Study", "StudyError",
           "load_study", "parse_study", "Model", "resolve", "build_system", "Simulation"]
