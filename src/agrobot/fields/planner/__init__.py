"""The coverage planner, in stages (fields.planner.pipeline): headland, decomposition, swaths,
route order, turns, speed profile; typed intermediates in fields.planner.types.

The names below are loaded on first use (PEP 562), so that a module of the package (its settings,
read for the ``plan`` command's defaults on every command's ``--help``) loads without the whole
planner (0.2 s of start-up, measured with ``python3 -X importtime -m agrobot --help``).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from ..first_use import loader

if TYPE_CHECKING:              # what static tools read; at run time __getattr__ loads each name
    from .path import Path as Path
    from .pipeline import Plan as Plan, plan as plan
    from .settings import Settings as Settings
    from .types import (HEADLAND as HEADLAND, KINDS as KINDS, SWATH as SWATH, TRANSIT as TRANSIT, TURN as TURN,
                        Cell as Cell, HeadlandPass as HeadlandPass, Route as Route, Segment as Segment,
                        Swath as Swath)

_HOME = {"Path": "path", "Plan": "pipeline", "plan": "pipeline", "Settings": "settings",
         **{name: "types" for name in ("HEADLAND", "KINDS", "SWATH", "TRANSIT", "TURN", "Cell", "HeadlandPass",
                                       "Route", "Segment", "Swath")}}
__all__ = list(_HOME)

__getattr__ = loader(__name__, _HOME, globals())
