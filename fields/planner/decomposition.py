"""Decomposition: which part of the inner field is worked, and how its swaths split into
boustrophedon cells (runs of consecutive lines whose swaths continue one another). A convex field
is one cell; a hole or a bay splits the lines that cross it into several."""
from __future__ import annotations

import math

import numpy as np
from shapely.geometry import Polygon

from ..field import FieldError
from .types import Cell, Swath


def min_width(poly: Polygon) -> float:
    """The shorter side of the smallest rotated rectangle round ``poly`` (at least its width)."""
    rect = poly.minimum_rotated_rectangle
    xy = np.asarray(rect.exterior.coords)
    sides = np.hypot(*np.diff(xy, axis=0).T)
    return float(min(sides[:2])) if len(sides) >= 2 else 0.0


def worked_region(parts: list[Polygon], width: float, passes: int, where: str, notes: list[str]) -> Polygon:
    """The largest piece of the inner field (noted when there are several); refused when it is
    narrower than two working widths."""
    largest = max(parts, key=lambda p: p.area) if parts else None
    if largest is None or min_width(largest) < 2 * width:
        raise FieldError(f"{where}: the field is narrower than two working widths ({2 * width:g} m) inside its "
                         f"{passes} headland pass(es) of {width:g} m (its narrowest width there: "
                         f"{min_width(largest) if largest is not None else 0.0:.1f} m)")
    if len(parts) > 1:
        notes.append(f"the inner field falls apart into {len(parts)} pieces; the largest ({largest.area / 1e4:.2f} ha) "
                     f"is worked")
    return largest


def cells(lines: list[list[Swath]], angle: float) -> list[Cell]:
    """Boustrophedon cells: a swath continues the one before on the previous line if each overlaps
    only the other along the driving direction."""
    d = np.array([math.cos(angle), math.sin(angle)])
    members: list[list[Swath]] = []
    previous: list[tuple[float, float, int]] = []
    for swaths in lines:
        spans = [tuple(sorted((float(sw.start @ d), float(sw.end @ d)))) for sw in swaths]
        current = []
        for sw, (x0, x1) in zip(swaths, spans):
            touching = [p for p in previous if p[0] < x1 and x0 < p[1]]
            cell = None
            if len(touching) == 1:
                p = touching[0]
                if sum(1 for y0, y1 in spans if y0 < p[1] and p[0] < y1) == 1:
                    cell = p[2]
            if cell is None:
                members.append([])
                cell = len(members) - 1
            members[cell].append(sw)
            current.append((x0, x1, cell))
        previous = current
    return [Cell(k, tuple(m)) for k, m in enumerate(members)]
