"""An FMU's model description, read and checked (fmpy): what a study file reader and the FMU
component both need to know of an FMU without loading its binary.

Imported where used: fmpy (start-up: 0.06 s on every command, which loads this module).
"""
from __future__ import annotations

import zipfile
from pathlib import Path

from .errors import InputError
from .units import FMI_BASE, BaseUnit


class FMUError(InputError):
    """The file cannot be used as a component (message names file and reason)."""


def _binary_dir(fmi_version: str) -> str:
    import fmpy

    return fmpy.platform if fmi_version.startswith("2") else fmpy.platform_tuple


def inspect_fmu(path: Path):
    """Read and check an FMU: its model description. Raises FMUError naming the file and reason."""
    from fmpy import read_model_description, sharedLibraryExtension

    if not path.exists():
        raise FMUError(f"{path}: no such file")
    if not zipfile.is_zipfile(path):
        raise FMUError(f"{path}: not an FMU (not a zip archive)")
    with zipfile.ZipFile(path) as zf:
        names = set(zf.namelist())
    if "modelDescription.xml" not in names:
        raise FMUError(f"{path}: not an FMU (no modelDescription.xml in the archive)")
    try:
        md = read_model_description(str(path), validate=False)
    except Exception as exc:  # fmpy raises several kinds for a malformed description
        raise FMUError(f"{path}: modelDescription.xml cannot be read: {exc}") from None
    if md.fmiVersion not in ("2.0",) and not md.fmiVersion.startswith("3."):
        raise FMUError(f"{path}: FMI version {md.fmiVersion} is not supported (2.0 and 3.0 are)")
    kind = md.coSimulation or md.modelExchange
    if kind is None:
        raise FMUError(f"{path}: neither co-simulation nor model exchange is provided "
                       f"(a scheduled-execution FMU cannot be stepped by this orchestrator)")
    binary = f"binaries/{_binary_dir(md.fmiVersion)}/{kind.modelIdentifier}{sharedLibraryExtension}"
    if binary not in names:
        have = sorted({n.split("/")[1] for n in names if n.startswith("binaries/") and n.count("/") >= 2})
        raise FMUError(f"{path}: no binary for this platform ({binary} missing; the FMU has "
                       f"{', '.join(have) or 'no binaries'})")
    clocked = [v.name for v in md.modelVariables if v.type == "Clock" or getattr(v, "clocks", None)]
    if clocked:
        raise FMUError(f"{path}: clocks are not supported; clocked variables: {', '.join(clocked[:8])}"
                       + (" ..." if len(clocked) > 8 else ""))
    return md


def base_units(md) -> dict[str, BaseUnit]:
    """Unit name -> BaseUnit, from an FMU's UnitDefinitions (units without a BaseUnit left out)."""
    return {u.name: BaseUnit(tuple(int(getattr(u.baseUnit, k)) for k in FMI_BASE), float(u.baseUnit.factor),
                             float(u.baseUnit.offset))
            for u in (md.unitDefinitions or []) if u.baseUnit is not None}


def variable_unit(variable) -> str:
    """A variable's unit: its own, else its declared type's, else "1"."""
    unit = getattr(variable, "unit", None)
    if not unit and getattr(variable, "declaredType", None) is not None:
        unit = getattr(variable.declaredType, "unit", None)
    return unit or "1"
