"""One finding of the import audit, in the shape every consumer reads (measurements.audit's
docstring lists the kinds): {kind, channels, value, interval ([lo, hi] or None), unit, meaning,
resolved}."""
from __future__ import annotations


def finding(kind: str, channels, value: float, interval, unit: str, meaning: str, resolved: bool = False) -> dict:
    """One finding (the module docstring's shape), numbers as Python floats."""
    return {"kind": kind, "channels": [str(c) for c in channels], "value": float(value),
            "interval": None if interval is None else [float(interval[0]), float(interval[1])],
            "unit": unit, "meaning": meaning, "resolved": bool(resolved)}
