"""The package's modules as an import sees them: every .py file under src/agrobot (the linked design
folders followed) and its dotted name."""
from __future__ import annotations

import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "agrobot"


def package_files() -> list[Path]:
    """Every .py file of the package, sorted."""
    found = []
    for folder, _, files in os.walk(PACKAGE, followlinks=True):
        found += [Path(folder) / f for f in files if f.endswith(".py")]
    return sorted(found)


def module_name(path: Path) -> str:
    """``agrobot.x.y`` of a file of the package (a package's ``__init__`` is the package)."""
    parts = ["agrobot", *path.relative_to(PACKAGE).with_suffix("").parts]
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
