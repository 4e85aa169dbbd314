"""The headland: how many passes of the working width w the turns need, the inner field the swaths
fill (the boundary buffered in by n w), what the implement can reach, and the headland passes.

- **Width**: auto, as many passes as the turns need to stay inside the field: their reach beyond
  the swath ends, the straight run-in of the implement's length and ``settle``, the tractor's half
  width, w/2 (a swath's end may lie w/2 beyond the inner field: fields.planner.swaths).
- **Passes**: rings at (k + 1/2) w inside the boundary (and round each hole). Corners are rounded
  (a tractor cannot follow a polygon's corner). ``tight`` corners: every pass at R, the tightest a
  forward pass can take; the field's corner beyond the outer pass is (R + w/2)^2 (1 - pi/4) at a
  right angle, and passes k and k + 1 are (sqrt 2 - 1) w further apart on the corner's bisector
  than on the sides (a small gap between them there). ``parallel`` corners: the innermost at R,
  each further out at w more: no gap between passes, but the outer pass rounds at R + (n - 1) w
  and leaves (R + (n - 1/2) w)^2 (1 - pi/4) of each right-angled corner. Tight leaves less of the
  whole field (about half, on the real fields).
- **Workable**: the field opened by a disk of radius R_o + w/2 + (R - R_i), R_o the outer pass's
  corner radius, R_i the trailed implement's steady radius when the tractor turns at R (it cuts
  each corner by R - R_i).
"""
from __future__ import annotations

import math

import numpy as np
from shapely.geometry import LineString, Polygon

from ..field import Field, FieldError, polygons
from .sampling import POLYLINE_STEP
from .settings import Settings
from .types import HeadlandPass

MARGIN = 0.2        # m kept between the tractor and the boundary beyond its half width


def width_needed(reach: float, settings: Settings) -> float:
    """Headland width [m] the turns need: their reach beyond the swath ends, the straight run-in,
    the tractor's half width from the boundary, w/2 (the swath ends' slack), a margin."""
    return reach + settings.lead + settings.half_width + 0.5 * settings.working_width + MARGIN


def passes(needed: float, settings: Settings, reach: float, where: str) -> int:
    """The number of headland passes: given, or as many as ``needed`` takes."""
    w = settings.working_width
    n = settings.headland_passes or max(1, math.ceil(needed / w))
    if settings.headland_passes and n * w < needed:
        raise FieldError(f"{where}: the turns do not fit the headland: a turn reaches {reach:.1f} m beyond the swath "
                         f"ends after a straight run of {settings.lead:.1f} m (the implement's length and settling), "
                         f"{needed:.1f} m in all, but {n} headland pass(es) of {w:g} m give {n * w:.1f} m (turn "
                         f"radius {settings.turn_radius:g} m); use {math.ceil(needed / w)} passes or a smaller turn radius")
    return n


def inner_parts(field: Field, n: int, width: float) -> list[Polygon]:
    """What the swaths may fill inside n passes: the pieces (larger than w^2) of the boundary buffered in by n w."""
    inner = field.boundary.buffer(-n * width, join_style="mitre", mitre_limit=3.0)
    return [p for p in polygons(inner) if p.area > width * width]


def corner_radius(settings: Settings, n: int, k: int) -> float:
    """The corner radius of headland pass k of n (0 the outermost)."""
    if settings.headland_corners == "tight":
        return settings.turn_radius
    return settings.turn_radius + (n - 1 - k) * settings.working_width


def workable(field: Field, settings: Settings, n: int) -> Polygon:
    outer = corner_radius(settings, n, 0)
    rho = outer + 0.5 * settings.working_width + (settings.turn_radius - settings.implement_radius)
    opened = field.boundary.buffer(-rho).buffer(rho)
    return max(polygons(opened), key=lambda p: p.area) if polygons(opened) else field.boundary


def ring_path(field: Field, offset: float, radius: float) -> list[np.ndarray]:
    """The closed paths at ``offset`` inside the boundary (and around each hole), corners rounded
    to ``radius``: (N, 4) x, y, heading, curvature, counter-clockwise around the field, a vertex
    every POLYLINE_STEP. Passes whose offset + radius is the same are parallel."""
    shape = field.boundary.buffer(-(offset + radius)).buffer(radius, quad_segs=16)
    out = []
    for poly in polygons(shape):
        for ring, ccw in [(poly.exterior, True)] + [(r, False) for r in poly.interiors]:
            xy = np.asarray(LineString(ring.coords).segmentize(POLYLINE_STEP).coords)[:-1]
            out.append(closed_path(xy[::-1] if ring.is_ccw != ccw else xy))
    return out


def closed_path(xy: np.ndarray) -> np.ndarray:
    """(N, 4) x, y, heading (towards the next point, unwrapped), curvature of a closed polyline."""
    d = np.diff(np.vstack([xy, xy[:1]]), axis=0)
    heading = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
    ds = np.hypot(d[:, 0], d[:, 1])
    curvature = np.gradient(heading) / np.maximum(ds, 1e-6)
    return np.column_stack([xy, heading, curvature])


def reversed_ring(ring: np.ndarray) -> np.ndarray:
    """A ring path driven the other way round."""
    return closed_path(ring[::-1, :2])


def headland_passes(field: Field, settings: Settings, n: int) -> list[HeadlandPass]:
    """The passes in the order they are worked: after the swaths (``headland_order`` last) from the
    innermost out, before them (first) from the outermost in; ring k at (k + 1/2) w, its corners
    at ``corner_radius``."""
    w = settings.working_width
    order = range(n) if settings.headland_order == "first" else range(n - 1, -1, -1)
    return [HeadlandPass(k, j, ring) for k in order
            for j, ring in enumerate(ring_path(field, (k + 0.5) * w, corner_radius(settings, n, k)))]
