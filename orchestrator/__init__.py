"""A small fixed-step co-simulation orchestrator: components with declared ports, wired from a
study file. It knows nothing about tractors."""
from .component import Component, ComponentError, Variable, inp, out, par
from .study import Study, StudyError, load_study, parse_study

__all__ = ["Component", "ComponentError", "Variable", "inp", "out", "par", "Study", "StudyError",
           "load_study", "parse_study"]
