"""Sub-resolver of Python component types (orchestrator.resolver): ``type = "name"`` is
``<package>.name.COMPONENT`` in the study's ``component_package``, then in every package a plugin
registered (orchestrator.registry), then the entry point ``name`` of the group ``<root>.components`` (<root>: the package holding this orchestrator)
(any installed package may provide one: ``xte_monitor = "my_pkg.xte_monitor:XTEMonitor"``);
``type = "package.module:Class"`` is that class. ``[study] components_path`` names a folder of the
user's own modules (relative to the study file) where ``module:Class`` is looked for too."""
from __future__ import annotations

import importlib
import pkgutil
import sys
from importlib.metadata import entry_points
from pathlib import Path

from .component import Component
from .errors import did_you_mean
from .registry import failed_plugins_note, import_study_module, registry
from .study import Study, StudyError


class PythonTypes:
    """Every component type that is not a file: a Python class (to be asked last)."""

    def component_class(self, study: Study, name: str, resolver) -> type[Component] | None:
        spec = study.components.get(name)
        if spec is None:
            return None
        if study.study.components_path:
            add_components_path(study)
        return resolve_type(spec.type, study.study.component_package, f"{study.where}: components.{name}")


ENTRY_POINTS = f"{__name__.split('.')[0]}.components"   # <root>.components of the installed package


def add_components_path(study: Study) -> Path:
    """Put ``[study] components_path`` on sys.path (relative to the study file, or to a file it
    extends that names it); refused by name when it is not a folder."""
    text = study.study.components_path
    candidates = [Path(text)] if Path(text).is_absolute() else [f / text for f in study.folders()] or [Path(text)]
    folder = next((c for c in candidates if c.is_dir()), None)
    if folder is None:
        raise StudyError(f"{study.origin('study.components_path')}: {text!r}: no such folder (looked in "
                         f"{', '.join(str(c) for c in candidates)})")
    folder = str(folder.resolve())
    if folder not in sys.path:
        sys.path.insert(0, folder)
        importlib.invalidate_caches()
    return Path(folder)


def entry_point_type(type_name: str):
    """The class an installed package provides as entry point ``type_name`` of ``<root>.components``,
    None when none does."""
    found = [ep for ep in entry_points(group=ENTRY_POINTS) if ep.name == type_name]
    if not found:
        return None
    try:
        return found[0].load()
    except Exception as exc:  # noqa: BLE001 - any fault of a third party's code
        dist = getattr(getattr(found[0], "dist", None), "name", None) or "an unknown distribution"
        raise StudyError(f"type {type_name!r}: the entry point of {dist} ({ENTRY_POINTS}: {found[0].value}) cannot "
                         f"be loaded: {type(exc).__name__}: {exc}") from None


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
                             f"project: pip install -e .) and study.component_package is not set"
                             + failed_plugins_note())
        candidates, attr = [f"{p}.{type_name}" for p in dict.fromkeys(packages)], "COMPONENT"
    module = None
    for module_name in candidates:
        try:
            module = import_study_module(module_name)
            break
        except ModuleNotFoundError as exc:
            if exc.name is None or not module_name.startswith(exc.name):
                raise StudyError(f"{where}: type {type_name!r}: importing {module_name!r} failed ({exc})") from None
    if module is None and ":" not in type_name:
        cls = entry_point_type(type_name)
        if cls is not None:
            return _checked(cls, type_name, where)
    if module is None:
        known = _known_types(packages) + [ep.name for ep in entry_points(group=ENTRY_POINTS)]
        raise StudyError(f"{where}: type {type_name!r}: no such component type: cannot import "
                         f"{' or '.join(repr(c) for c in candidates)}"
                         + did_you_mean(type_name, known)
                         + (" (a module of your own: put its folder in [study] components_path, relative to the "
                            "study file)" if ":" in type_name else "") + failed_plugins_note())
    cls = getattr(module, attr, None)
    if cls is None:
        raise StudyError(f"{where}: type {type_name!r}: module {module_name!r} has no {attr!r}")
    return _checked(cls, type_name, where)


def _checked(cls, type_name: str, where: str) -> type[Component]:
    if not (isinstance(cls, type) and issubclass(cls, Component)):
        raise StudyError(f"{where}: type {type_name!r}: {getattr(cls, '__name__', cls)!r} is not a Component class")
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
