"""Decomposition: the pieces of the inner field (a narrow waist or a hole near the boundary splits
it; every piece is worked, each with its own swaths), and how a piece's swaths split into
boustrophedon cells (runs of consecutive lines whose swaths continue one another). A convex field
is one cell; a hole or a bay splits the lines that cross it into several."""
from __future__ import annotations

import math
from typing import Callable

import numpy as np
from shapely.geometry import Polygon

from ..field import FieldError
from .types import Cell, Swath

Along = Callable[[np.ndarray], float]      # a point's coordinate along the swaths' direction


def min_width(poly: Polygon) -> float:
    """The shorter side of the smallest rotated rectangle round ``poly`` (at least its width)."""
    rect = poly.minimum_rotated_rectangle
    xy = np.asarray(rect.exterior.coords)
    sides = np.hypot(*np.diff(xy, axis=0).T)
    return float(min(sides[:2])) if len(sides) >= 2 else 0.0


def worked_regions(parts: list[Polygon], width: float, passes: int, where: str, notes: list[str]) -> list[Polygon]:
    """Every piece of the inner field, the largest first (the pieces noted when there are several);
    refused when even the largest is narrower than two working widths."""
    parts = sorted(parts, key=lambda p: -p.area)
    if not parts or min_width(parts[0]) < 2 * width:
        raise FieldError(f"{where}: the field is narrower than two working widths ({2 * width:g} m) inside its "
                         f"{passes} headland pass(es) of {width:g} m (its narrowest width there: "
                         f"{min_width(parts[0]) if parts else 0.0:.1f} m)")
    if len(parts) > 1:
        notes.append(f"the inner field falls apart into {len(parts)} pieces ("
                     + ", ".join(f"{p.area / 1e4:.2f}" for p in parts) + " ha); every piece is worked, joined along "
                     "the headland")
    return parts


def straight_along(angle: float) -> Along:
    """The coordinate along straight swaths at ``angle``."""
    d = np.array([math.cos(angle), math.sin(angle)])
    return lambda p: float(np.asarray(p) @ d)


def cells(lines: list[list[Swath]], angle: float | Along, first: int = 0, piece: int = 0) -> list[Cell]:
    """Boustrophedon cells: a swath continues the one before on the previous line if each overlaps
    only the other along the driving direction (``angle``, or a function giving a point's
    coordinate along curved swaths). Cells are numbered from ``first``, in ``piece``."""
    along = straight_along(angle) if isinstance(angle, (int, float)) else angle
    members: list[list[Swath]] = []
    previous: list[tuple[float, float, int]] = []
    for swaths in lines:
        spans = [tuple(sorted((along(sw.start), along(sw.end)))) for sw in swaths]
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
    return [Cell(first + k, tuple(m), piece) for k, m in enumerate(members)]
