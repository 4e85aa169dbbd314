"""Sub-resolver of Python component types (orchestrator.resolver): ``type = "name"`` is
``<package>.name.COMPONENT`` in the study's ``component_package``, then in every package a plugin
registered (orchestrator.registry); ``type = "package.module:Class"`` is that class."""
from __future__ import annotations

import importlib
import pkgutil

from .component import Component
from .errors import did_you_mean
from .registry import import_study_module, registry
from .study import Study, StudyError


class PythonTypes:
    """Every component type that is not a file: a Python class (to be asked last)."""

    def component_class(self, study: Study, name: str, resolver) -> type[Component] | None:
        spec = study.components.get(name)
        if spec is None:
            return None
        return resolve_type(spec.type, study.study.component_package, f"{study.where}: components.{name}")


def resolve_type(type_name: str, package: str | None, where: str) -> type[Component]:
    """``"name"`` -> ``<package>.name.COMPONENT`` (the study's package, then every registered
    one); ``"pkg.mod:Class"`` -> that class."""
    packages: list[str] = []
    if ":" in type_name:
        module_name, attr = type_name.split(":", 1)
        candidates = [module_name]
    else:
        packages = ([package] if package else []) + registry().component_packages
        if not packages:
            raise StudyError(f"{where}: type {type_name!r}: no component package is registered (install the "
                             f"project: pip install -e .) and study.component_package is not set")
        candidates, attr = [f"{p}.{type_name}" for p in dict.fromkeys(packages)], "COMPONENT"
    module = None
    for module_name in candidates:
        try:
            module = import_study_module(module_name)
            break
        except ModuleNotFoundError as exc:
            if exc.name is None or not module_name.startswith(exc.name):
                raise StudyError(f"{where}: type {type_name!r}: importing {module_name!r} failed ({exc})") from None
    if module is None:
        known = _known_types(packages)
        raise StudyError(f"{where}: type {type_name!r}: no such component type: cannot import "
                         f"{' or '.join(repr(c) for c in candidates)}"
                         + did_you_mean(type_name, known))
    cls = getattr(module, attr, None)
    if cls is None:
        raise StudyError(f"{where}: type {type_name!r}: module {module_name!r} has no {attr!r}")
    if not (isinstance(cls, type) and issubclass(cls, Component)):
        raise StudyError(f"{where}: type {type_name!r}: {attr!r} is not a Component class")
    return cls


def _known_types(packages: list[str]) -> list[str]:
    """Module names of the component packages (the type names a study may use)."""
    names = []
    for package in packages:
        try:
            names += [m.name for m in pkgutil.iter_modules(importlib.import_module(package).__path__)]
        except (ImportError, AttributeError):
            continue
    return names
