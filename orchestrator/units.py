"""Units at the edges: study files may write ``"45 deg"``; inside everything is SI and radians.

Imported where used: pint (start-up: 0.3 s on every command, which loads this module; read when
two units are compared).
"""
from __future__ import annotations

import functools
import math
import re
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

# unit written in a study file -> (SI unit, factor to SI)
EDGE_UNITS: dict[str, tuple[str, float]] = {
    "deg": ("rad", math.pi / 180.0),
    "deg/s": ("rad/s", math.pi / 180.0),
    "deg/s2": ("rad/s2", math.pi / 180.0),
    "km/h": ("m/s", 1.0 / 3.6),
    "L/min": ("m3/s", 1.0 / 60000.0),
    "cm": ("m", 0.01),
    "mm": ("m", 0.001),
    "ms": ("s", 0.001),
    "Hz": ("1/s", 1.0),
}

FILE_UNIT = "file"        # a parameter naming a file: found relative to the study (orchestrator.build)

_QUANTITY = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(\S+)\s*$")


class UnitError(ValueError):
    pass


def same_unit(a: str, b: str) -> bool:
    """Units are compared as written, ignoring spaces ("rad/s" == "rad / s")."""
    return a.replace(" ", "") == b.replace(" ", "")


# FMI's BaseUnit exponents, in the order of the standard's attributes
FMI_BASE = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")
_PINT_DIMENSION = {"[mass]": "kg", "[length]": "m", "[time]": "s", "[current]": "A", "[temperature]": "K",
                   "[substance]": "mol", "[luminosity]": "cd", "[angle]": "rad"}


@dataclass(frozen=True)
class BaseUnit:
    """A unit as FMI's BaseUnit states it: value_in_SI = factor * value + offset, SI being
    kg^e0 m^e1 s^e2 A^e3 K^e4 mol^e5 cd^e6 rad^e7 (the radian is a base unit, as in FMI)."""

    exponents: tuple[int, ...]
    factor: float = 1.0
    offset: float = 0.0

    def matches(self, other: "BaseUnit") -> bool:
        """Same dimension and the same scale (a value passes unchanged)."""
        return (self.exponents == other.exponents and math.isclose(self.factor, other.factor, rel_tol=1e-9)
                and math.isclose(self.offset, other.offset, rel_tol=1e-9, abs_tol=1e-12))

    def fmi_attributes(self) -> dict[str, str]:
        attrs = {k: str(e) for k, e in zip(FMI_BASE, self.exponents) if e}
        if self.factor != 1.0:
            attrs["factor"] = repr(float(self.factor))
        if self.offset != 0.0:
            attrs["offset"] = repr(float(self.offset))
        return attrs


@functools.lru_cache(maxsize=1)
def _registry():
    """pint's default units with the radian as its own dimension (FMI counts rad as a base unit,
    so rad/s and 1/s differ, while deg/s and rad/s compare by factor)."""
    import pint

    here = Path(pint.__file__).parent
    with tempfile.TemporaryDirectory() as tmp:
        text = (here / "default_en.txt").read_text().replace("radian = [] = rad", "radian = [angle] = rad")
        (Path(tmp) / "default_en.txt").write_text(text)
        shutil.copy(here / "constants_en.txt", tmp)
        return pint.UnitRegistry(str(Path(tmp) / "default_en.txt"), cache_folder=None)


_MODELICA_FACTOR = re.compile(r"^([A-Za-z_%]\w*?)(-?\d+)$")


def _pint_expression(unit: str) -> str:
    """Modelica/FMI unit syntax ('rad.s-1', 'm/s2', 'kg.m2') to pint syntax ('rad*s**-1' ...)."""
    out = []
    for token in re.split(r"([./*()])", unit.replace(" ", "")):
        m = _MODELICA_FACTOR.match(token)
        out.append("*" if token == "." else f"{m.group(1)}**{m.group(2)}" if m else token)
    return "".join(out)


@functools.lru_cache(maxsize=512)
def base_unit(unit: str) -> BaseUnit | None:
    """The BaseUnit of a unit string (study, component or FMU syntax); None when no units
    library name matches. ``""`` and ``"1"`` are dimensionless."""
    if unit.strip() in ("", "1", "-"):
        return BaseUnit((0,) * len(FMI_BASE))
    ureg = _registry()
    try:
        q = ureg.Quantity(_pint_expression(unit))
        if q.dimensionality and ureg.Quantity(0.0, q.units).to_base_units().magnitude != 0.0:
            offset = ureg.Quantity(0.0, q.units).to_base_units().magnitude
            factor = ureg.Quantity(1.0, q.units).to_base_units().magnitude - offset
        else:
            factor, offset = float(q.to_base_units().magnitude), 0.0
        dims = dict(q.dimensionality)
    except Exception:       # noqa: BLE001 - pint raises many kinds for a name it does not know
        return None
    if any(d not in _PINT_DIMENSION for d in dims) or any(float(e) != int(e) for e in dims.values()):
        return None
    exponents = tuple(int(dims.get(dim, 0)) for dim in _PINT_DIMENSION)
    return BaseUnit(exponents, float(factor), float(offset))


def units_match(a: str, b: str, a_base: BaseUnit | None = None, b_base: BaseUnit | None = None) -> bool:
    """Can a value in unit ``a`` feed a port in unit ``b`` unchanged? Same dimension and factor,
    from the BaseUnits where given (an FMU's unit definitions) and otherwise from the units
    library; strings no library knows must be written the same."""
    if same_unit(a, b):
        return True
    a_base = a_base or base_unit(a)
    b_base = b_base or base_unit(b)
    return a_base is not None and b_base is not None and a_base.matches(b_base)


def to_si(value: Any, unit: str) -> Any:
    """Convert a study value to the SI unit ``unit``.

    Numbers, booleans, lists and plain strings pass through; a string ``"<number> <unit>"`` is
    converted when its unit is ``unit`` itself or an edge unit that maps onto it. Parameters with
    no unit (``""``: names, addresses) or naming a file (``"file"``) take strings as they are.
    """
    if isinstance(value, str) and unit in ("", FILE_UNIT):
        return value
    if isinstance(value, str):
        match = _QUANTITY.match(value)
        if not match:
            return value
        number, written = float(match.group(1)), match.group(2)
        if same_unit(written, unit):
            return number
        if written in EDGE_UNITS and same_unit(EDGE_UNITS[written][0], unit):
            return number * EDGE_UNITS[written][1]
        raise UnitError(f"value {value!r} is in {written!r}, expected {unit!r}"
                        + (f" (or {', '.join(k for k, v in EDGE_UNITS.items() if v[0] == unit)})"
                           if any(v[0] == unit for v in EDGE_UNITS.values()) else ""))
    if isinstance(value, list):
        return [to_si(v, unit) for v in value]
    return value
