"""A package's names loaded on first use (PEP 562): the package lists where each name lives, and
its module ``__getattr__`` imports that module when the name is first read, so that importing one
module of the package (the fields plugin's commands on every start-up) loads none of the others."""
from __future__ import annotations

from importlib import import_module
from typing import Any, Callable


def loader(package: str, homes: dict[str, str], namespace: dict[str, Any]) -> Callable[[str], Any]:
    """The ``__getattr__`` of ``package``: ``homes`` maps each name to its module (relative to
    the package); a name read once is kept in ``namespace`` (the package's globals)."""
    def __getattr__(name: str) -> Any:
        if name not in homes:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(import_module(f".{homes[name]}", package), name)
        namespace[name] = value
        return value
    return __getattr__
