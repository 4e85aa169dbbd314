"""Which optional extra of the project provides a module that is missing, read from the installed
project's own metadata (its ``Requires-Dist: NAME; extra == "EXTRA"`` lines), so that a command
that needs one says what to install."""
from __future__ import annotations

import re
from importlib.metadata import PackageNotFoundError, requires

DISTRIBUTION = "agrobot-guidance"
MODULE_DISTRIBUTIONS = {"serial": "pyserial", "can": "python-can"}      # import name -> distribution name


def _canonical(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def extra_of(module: str) -> str | None:
    """The extra whose requirements install top-level ``module`` (None: not an extra's, or the
    project's metadata is not installed)."""
    try:
        lines = requires(DISTRIBUTION) or []
    except PackageNotFoundError:
        return None
    top = module.split(".")[0]
    wanted = _canonical(MODULE_DISTRIBUTIONS.get(top, top))
    for line in lines:
        m = re.match(r"\s*([A-Za-z0-9_.\-]+).*;\s*extra\s*==\s*['\"]([^'\"]+)['\"]", line)
        if m and _canonical(m.group(1)) == wanted and m.group(2) != "test":
            return m.group(2)
    return None


def missing_extra_message(exc: ModuleNotFoundError) -> str | None:
    """One line naming the extra to install for ``exc``, None when the module is no extra's."""
    extra = exc.name and extra_of(exc.name)
    if not extra:
        return None
    return (f"error: this needs the optional module {exc.name.split('.')[0]!r}, which is not installed: "
            f"pip install '{DISTRIBUTION}[{extra}]'")
