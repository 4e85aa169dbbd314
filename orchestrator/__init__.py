"""A small fixed-step co-simulation orchestrator: components with declared ports, wired from a
study file. A library: it knows nothing of the system it
simulates; a project registers its components and tools (orchestrator.registry)."""
from .component import Component, ComponentError, Variable, inp, out, par
from .study import Study, StudyError, load_study, parse_study

__all__ = ["Component", "ComponentError", "Variable", "inp", "out", "par", "Study", "StudyError",
           "load_study", "parse_study"]
