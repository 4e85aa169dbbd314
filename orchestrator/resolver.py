"""From a study (a description) to a resolved model (orchestrator.model), after libcosim's
``model_uri_resolver``: a chain of sub-resolvers, each asked in turn for the class of a component
until one knows its kind of type. Each is defined by the module that knows that kind:

- ``SubsystemTypes`` (orchestrator.composite): an inline ``[subsystems.NAME]`` or a study file;
- ``FMUTypes`` (orchestrator.fmu): a path to an ``.fmu``;
- ``PythonTypes`` (orchestrator.python_types): a registered type name or ``module:Class``.

A sub-resolver is any object with ``component_class(study, name, resolver)`` returning a
Component class, or None when the type is not of its kind; ``Resolver([...])`` chains others.

Resolving also checks the study's tool tables against the installed tools (orchestrator.registry):
a table no installed tool reads is refused by name, and a table whose tool registered a schema (a
pydantic model) is validated with it. With no plugin installed at all (the orchestrator used alone)
every tool table is kept as written.

    model = resolve(study)                 # every type found once
    system = build_system(model)           # orchestrator.build
"""
from __future__ import annotations

from typing import Protocol, Sequence

from pydantic import ValidationError

from .component import Component
from .composite import SubsystemTypes
from .fmu import FMUTypes
from .model import Model, resolved_parameters
from .python_types import PythonTypes
from .registry import registry
from .study import SET_PARAMETER_CHECKS, Study, StudyError
from .study_schema import TABLES


class SubResolver(Protocol):
    def component_class(self, study: Study, name: str, resolver: "Resolver") -> type[Component] | None: ...


class Resolver:
    """A chain of sub-resolvers, asked in order."""

    def __init__(self, sub_resolvers: Sequence[SubResolver]) -> None:
        self.sub_resolvers = list(sub_resolvers)

    def resolve(self, study: Study) -> Model:
        """The model of ``study``: its tool tables checked, every component's class found once
        (kept with the study: resolving the same study again returns the same model)."""
        model = study._resolved.get(self)
        if model is None:
            check_tables(study)
            model = study._resolved[self] = Model(study, {name: self.component_class(study, name)
                                                          for name in [*study.components, *study.subsystems]})
        return model

    def component_class(self, study: Study, name: str) -> type[Component]:
        for sub in self.sub_resolvers:
            cls = sub.component_class(study, name, self)
            if cls is not None:
                return cls
        spec = study.components.get(name)
        raise StudyError(f"{study.where}: components.{name}.type: {spec.type if spec else name!r}: "
                         f"no resolver knows this kind of type")


_DEFAULT: Resolver | None = None


def default_resolver() -> Resolver:
    """Subsystems, FMUs, then Python types (the last takes every type that is not a file)."""
    global _DEFAULT
    if _DEFAULT is None:
        _DEFAULT = Resolver([SubsystemTypes(), FMUTypes(), PythonTypes()])
    return _DEFAULT


def resolve(study: Study, resolver: Resolver | None = None) -> Model:
    """``study``'s resolved model (by ``resolver``, default: ``default_resolver()``)."""
    return (resolver or default_resolver()).resolve(study)


def check_tables(study: Study) -> None:
    """Every tool table of ``study`` is one an installed tool registered, and valid by its schema
    when the tool gave one (nothing is checked when no plugin is installed)."""
    reg = registry()
    if not reg.loaded:
        return
    known = reg.sections
    for name, table in study.sections.items():
        if name not in known:
            raise StudyError(f"{study.where}: unknown table {name!r}; a study has {', '.join(TABLES)} or a tool's "
                             f"table ({', '.join(sorted(known)) or 'none installed'})")
        schema = reg.section_schemas.get(name)
        if schema is None:
            continue
        try:
            schema.model_validate(table)
        except ValidationError as err:
            problems = "; ".join(f"{'.'.join(map(str, (name, *e['loc'])))}: {e['msg'].removeprefix('Value error, ')}"
                                 for e in err.errors())
            raise StudyError(f"{study.where}: {problems}") from None


def check_set_parameters(study: Study) -> None:
    """Each ``components.C.parameters.P`` an override sets names a parameter C's class declares (a
    misspelt one is refused, with its nearest names, before the override is said applied); a
    component whose type cannot be found here is left to the resolve, which names it."""
    for field in study._set_by:
        parts = field.split(".")
        if len(parts) != 4 or parts[0] != "components" or parts[2] != "parameters" or parts[1] not in study.components:
            continue
        try:
            cls = default_resolver().component_class(study, parts[1])
        except Exception:  # noqa: BLE001 - an unknown type, a missing plugin: named by the resolve
            continue
        if parts[3] not in cls.declared("parameter"):
            value = study.components[parts[1]].parameters[parts[3]]
            resolved_parameters(cls, parts[1], {parts[3]: value}, study.origin)


SET_PARAMETER_CHECKS.append(check_set_parameters)
