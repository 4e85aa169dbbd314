"""Units at the edges: study files may write ``"45 deg"``; inside everything is SI and radians."""
from __future__ import annotations

import math
import re
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

_QUANTITY = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(\S+)\s*$")


class UnitError(ValueError):
    pass


def same_unit(a: str, b: str) -> bool:
    """Units are compared as written, ignoring spaces ("rad/s" == "rad / s")."""
    return a.replace(" ", "") == b.replace(" ", "")


def to_si(value: Any, unit: str) -> Any:
    """Convert a study value to the SI unit ``unit``.

    Numbers, booleans, lists and plain strings pass through; a string ``"<number> <unit>"`` is
    converted when its unit is ``unit`` itself or an edge unit that maps onto it. Parameters with
    no unit (``""``: names, addresses, paths) take strings as they are.
    """
    if isinstance(value, str) and unit == "":
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
