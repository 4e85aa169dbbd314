"""The physical range of a component parameter, by the class of quantity its declared unit and name
say, checked when the study is resolved (before anything is built or run):

| class | which parameters | range |
| --- | --- | --- |
| every number | a declared default that is a number | not NaN (an infinite limit, ``max_fix_age = inf``, is one) |
| mass | unit ``kg`` | (0, 1e6] kg |
| inertia | unit ``kg m^2`` | (0, 1e8] kg m^2 |
| delay | unit ``s``, name ending in ``delay``, ``latency`` or ``latency_jitter`` | [0, 3600] s |
| wait | unit ``s``, name ending in ``timeout`` or ``wait`` | (0, inf] s (inf: never) |
| port | name ``port`` or ending in ``_port``, a number | an integer 0 to 65535 |
| count | name beginning ``n_`` or ending in ``_count``, unit ``1`` | an integer 0 to 1e7 |

A value outside its class's range is refused naming the parameter, where it was given, the value
and the range.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any, Callable


@dataclass(frozen=True)
class PhysicalRange:
    what: str
    applies: Callable[[str, str], bool]
    low: float
    high: float
    low_open: bool = False
    integer: bool = False

    def refusal(self, value: float) -> str | None:
        below = value <= self.low if self.low_open else value < self.low
        if below or value > self.high or (self.integer and not (math.isfinite(value) and value == int(value))):
            low = "(" if self.low_open else "["
            kind = "an integer in " if self.integer else ""
            return f"expected {kind}{low}{self.low:g}, {self.high:g}] (a {self.what})"
        return None


RANGES = (
    PhysicalRange("mass in kg", lambda name, unit: unit == "kg", 0.0, 1e6, low_open=True),
    PhysicalRange("moment of inertia in kg m^2", lambda name, unit: unit in ("kg m^2", "kg*m^2", "kg m2"), 0.0, 1e8,
          low_open=True),
    PhysicalRange("delay in s", lambda name, unit: unit == "s" and re.search(r"(delay|latency|latency_jitter)$", name) is not None,
          0.0, 3600.0),
    PhysicalRange("wait in s", lambda name, unit: unit == "s" and re.search(r"(timeout|wait)$", name) is not None, 0.0,
          math.inf, low_open=True),
    PhysicalRange("TCP/UDP port", lambda name, unit: name == "port" or name.endswith("_port"), 0, 65535, integer=True),
    PhysicalRange("count", lambda name, unit: unit in ("1", "") and (name.startswith("n_") or name.endswith("_count")),
          0, 1e7, integer=True),
)


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def range_refusal(name: str, unit: str, start: Any, value: Any) -> str | None:
    """Why ``value`` (SI) of parameter ``name`` (declared ``unit`` and default ``start``) is not
    physical, or None."""
    if not _number(value) or not _number(start):
        return None
    if math.isnan(value):
        return None if math.isnan(start) else f"got {value!r}, expected a number"
    for rule in RANGES:
        if rule.applies(name, unit):
            why = rule.refusal(float(value))
            if why is not None:
                return f"got {value:g}, {why}"
    return None
