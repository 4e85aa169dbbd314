"""The coverage planner, in stages (fields.planner.pipeline): headland, decomposition, swaths,
route order, turns, speed profile; typed intermediates in fields.planner.types."""
from .path import Path
from .pipeline import Plan, plan
from .settings import Settings
from .types import HEADLAND, KINDS, SWATH, TRANSIT, TURN, Cell, HeadlandPass, Route, Segment, Swath

__all__ = ["Path", "Plan", "plan", "Settings", "HEADLAND", "KINDS", "SWATH", "TRANSIT", "TURN", "Cell", "HeadlandPass",
           "Route", "Segment", "Swath"]
