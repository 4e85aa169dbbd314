"""What the orchestrator learns from the project it serves, through entry points.

A project declares plugins in its ``pyproject.toml``::

    [project.entry-points."<root>.plugins"]        # <root>: the package holding this orchestrator
    components = "<root>.components:register"        # a callable taking the Registry

Each plugin's ``register(registry)`` adds what it brings: component packages (a study's
``type = "name"`` is looked up as ``<package>.name.COMPONENT``), command-line sub-commands, the
top-level study tables it reads (``[my_tool]``, with a pydantic model that validates it if the
tool gives one: orchestrator.resolver checks every table when a study is resolved).
The orchestrator itself names no package, table or tool of any project.
"""
from __future__ import annotations

import argparse
import copy
import importlib
import sys
import warnings
from dataclasses import dataclass, field
from importlib.metadata import entry_points
from typing import Callable

ROOT = __name__.split(".")[0]          # the installed package this orchestrator lives in
GROUP = f"{ROOT}.plugins"


@dataclass
class Command:
    name: str
    help: str
    add_arguments: Callable[[argparse.ArgumentParser], None]
    run: Callable[[argparse.Namespace], int]


@dataclass
class RunOption:
    """An option a plugin adds to ``run``: ``apply(study, value)`` returns the study to run."""

    flag: str
    help: str
    metavar: str
    apply: Callable


@dataclass
class Registry:
    component_packages: list[str] = field(default_factory=list)
    commands: dict[str, Command] = field(default_factory=dict)
    sections: dict[str, str] = field(default_factory=dict)        # study table -> what reads it
    section_schemas: dict[str, type] = field(default_factory=dict)  # study table -> its pydantic model
    run_options: list[RunOption] = field(default_factory=list)
    module_aliases: dict[str, str] = field(default_factory=dict)  # former top-level name -> its current one
    loaded: list[str] = field(default_factory=list)
    failed: dict[str, str] = field(default_factory=dict)   # entry point -> why it was left out

    def add_component_package(self, package: str) -> None:
        if package not in self.component_packages:
            self.component_packages.append(package)

    def add_command(self, name: str, help: str, add_arguments, run) -> None:
        self.commands[name] = Command(name, help, add_arguments, run)

    def add_run_option(self, flag: str, help: str, metavar: str, apply) -> None:
        """``run FLAG VALUE``: the study is replaced by ``apply(study, value)`` before it runs."""
        self.run_options.append(RunOption(flag, help, metavar, apply))

    def add_module_alias(self, former: str, current: str) -> None:
        """A study naming module ``former.x`` (a module path from an earlier release) gets ``current.x``,
        with a deprecation note (import_study_module)."""
        self.module_aliases[former] = current

    def add_section(self, name: str, reader: str, schema: type | None = None) -> None:
        """A top-level study table ``[name]`` that ``reader`` reads; ``schema``, a pydantic model,
        validates it when a study is resolved."""
        self.sections[name] = reader
        if schema is not None:
            self.section_schemas[name] = schema


_REGISTRY: Registry | None = None


def registry() -> Registry:
    """The registry, filled once from the installed plugins. A plugin that cannot be imported or
    whose ``register`` raises is named in one warning line (its distribution, entry point and
    error), left out whole (what it registered before failing is dropped) and remembered in
    ``failed``: every command that does not need it works."""
    global _REGISTRY
    if _REGISTRY is None:
        reg = Registry()
        for ep in sorted(entry_points(group=GROUP), key=lambda e: e.name):
            before = copy.deepcopy(reg)
            try:
                ep.load()(reg)
            except Exception as exc:  # noqa: BLE001 - any fault of a third party's code
                reg = before
                reg.failed[ep.name] = _failure(ep, exc)
                print(f"warning: {reg.failed[ep.name]}; its components and commands are unavailable", file=sys.stderr)
                continue
            reg.loaded.append(ep.name)
        _REGISTRY = reg
    return _REGISTRY


def _failure(ep, exc: Exception) -> str:
    """One line naming a plugin that failed: distribution, entry point, the error."""
    dist = getattr(getattr(ep, "dist", None), "name", None) or "an unknown distribution"
    what = "cannot be imported" if isinstance(exc, ImportError) else "failed to register"
    hint = " (is a script's folder shadowing a package of that name on sys.path?)" if isinstance(exc, ImportError) else ""
    return (f"plugin {ep.name!r} of {dist} ({GROUP}: {ep.value}) {what}: {type(exc).__name__}: "
            f"{str(exc).splitlines()[0] if str(exc) else ''}{hint}")


def failed_plugins_note() -> str:
    """'' or a sentence naming the plugins that failed (for a message about something not found)."""
    failed = registry().failed
    return "" if not failed else " Plugins that failed to load: " + "; ".join(failed.values()) + "."


_NOTED: set[str] = set()


def import_study_module(name: str):
    """Import a module a study names (an analysis, a component's ``pkg.mod:Class``). A name under a
    former top-level package (registry().module_aliases) is imported under its current name, with a
    FutureWarning once per name: such study files keep working for one release."""
    head, _, rest = name.partition(".")
    current = registry().module_aliases.get(head)
    if current is not None and not name.startswith(current + "."):
        new = f"{current}.{rest}" if rest else current
        if name not in _NOTED:
            _NOTED.add(name)
            warnings.warn(f"module path {name!r} is deprecated: write {new!r} (the project's modules moved "
                          f"under one package; the former path is accepted until the next release)",
                          FutureWarning, stacklevel=2)
        name = new
    return importlib.import_module(name)
