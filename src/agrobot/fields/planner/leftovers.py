"""What a plan leaves unworked, piece by piece, each named with its area, its width and why.

The leftover is the field (boundary less holes and obstacles) less the applied strips' union
(fields.planner.applied). Pieces under ``MIN_AREA`` (the slivers between a turn's strip and the
boundary) are summed, not listed. Each piece's width is twice its largest inscribed circle's
radius (shapely's maximum_inscribed_circle, a polygon's medial-axis width at its widest), its
length the long side of its smallest rotated rectangle. Its kind, the first that holds:

- ``corner``: mostly outside the workable field (the field opened by the outer headland pass's
  corner radius R): a turn of radius R cannot bring the implement there;
- ``between pieces``: mostly inside the inner field (n headland passes of w in from the boundary)
  but in none of its worked pieces: a neck narrower than twice the headland that split the inner
  field, or a strip the pieces' swaths left between them;
- ``strip``: long and narrow (length over width at least STRIPLIKE) along the headland or a swath;
- ``patch``: anything else.

Whether a pass of its own would work it: one pass of the working width w along its medial axis
covers a piece at most w wide; the tractor can drive that axis when the axis (here the long centre
line of its smallest rotated rectangle, clipped to the piece) keeps the tractor's half width inside
the field. fields.planner.leftover_passes drives such passes, and passes round the corners at the
tightest radius; what they leave is named here with why.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from shapely import maximum_inscribed_circle
from shapely.geometry import LineString, MultiPolygon, Polygon

MIN_AREA = 1.0          # m^2: smaller pieces are summed as slivers, not named
STRIPLIKE = 4.0         # length / width from which a piece is a strip


@dataclass(frozen=True)
class Leftover:
    kind: str                   # corner, between pieces, strip, patch
    area: float                 # m^2
    width: float                # m: twice the largest inscribed circle's radius
    length: float               # m: the long side of its smallest rotated rectangle
    why: str                    # why it is not worked, and what would work it
    centroid: tuple[float, float]
    pass_m: float = 0.0         # m: a pass of its own along its medial axis that would cover it (0: none)
    shape: Polygon | None = None  # the piece itself

    def summary(self) -> dict:
        return {"kind": self.kind, "area_m2": round(self.area, 2), "width_m": round(self.width, 2),
                "length_m": round(self.length, 1), "centroid": [round(c, 1) for c in self.centroid],
                "own_pass_m": round(self.pass_m, 1), "why": self.why}


def _parts(geom) -> list[Polygon]:
    if geom.is_empty:
        return []
    if isinstance(geom, Polygon):
        return [geom]
    return [g for g in getattr(geom, "geoms", []) if isinstance(g, Polygon)]


def long_axis(piece: Polygon) -> tuple[np.ndarray, np.ndarray, float]:
    """(a, b, across): the long centre line a-b of the piece's smallest rotated rectangle (from the
    mid-point of one short side to the other's) and the rectangle's short side."""
    xy = np.asarray(piece.minimum_rotated_rectangle.exterior.coords)[:4]
    sides = np.hypot(*np.diff(np.vstack([xy, xy[:1]]), axis=0).T)
    k = int(np.argmax(sides[:2]))                           # a long side from corner k
    a = 0.5 * (xy[k] + xy[(k + 3) % 4])                     # mid-points of the two short sides
    b = 0.5 * (xy[(k + 1) % 4] + xy[(k + 2) % 4])
    return a, b, float(sides[(k + 1) % 4])


def centre_line(piece: Polygon, offset: float = 0.0) -> LineString:
    """The long centre line of the piece's smallest rotated rectangle (moved ``offset`` to its
    left), clipped to the piece: its longest part inside."""
    a, b, _ = long_axis(piece)
    d = (b - a) / max(float(np.hypot(*(b - a))), 1e-12)
    left = offset * np.array([-d[1], d[0]])
    clipped = LineString([a + left, b + left]).intersection(piece)
    parts = [g for g in getattr(clipped, "geoms", [clipped]) if isinstance(g, LineString) and not g.is_empty]
    return max(parts, key=lambda g: g.length) if parts else LineString()


def leftovers(plan, covered) -> tuple[list[Leftover], float]:
    """(the named pieces, largest first; the area of the slivers under MIN_AREA) of ``plan``'s field
    not in ``covered`` (a shapely geometry: what was applied)."""
    s = plan.settings
    field = plan.field.boundary
    rest = field.difference(covered) if covered is not None and not covered.is_empty else field
    inner = plan.inner if isinstance(plan.inner, (Polygon, MultiPolygon)) else Polygon()
    headland = field.buffer(-plan.headland_passes * s.working_width, join_style="mitre")
    tractor_room = field.buffer(-s.half_width)
    named, slivers = [], 0.0
    for piece in _parts(rest):
        if piece.area < MIN_AREA:
            slivers += piece.area
            continue
        circle = maximum_inscribed_circle(piece, tolerance=0.01)
        width = 2.0 * float(circle.length)
        rect = np.asarray(piece.minimum_rotated_rectangle.exterior.coords)
        length = float(np.hypot(*np.diff(rect, axis=0).T)[:2].max())
        outside = piece.difference(plan.workable).area / piece.area
        in_inner = piece.intersection(headland).area / piece.area
        in_pieces = piece.intersection(inner).area / piece.area
        if outside > 0.5:
            kind = "corner"
            why = (f"outside the workable field: a turn of radius {s.turn_radius:g} m cannot bring the implement "
                   "into it")
        elif in_inner > 0.5 and in_pieces < 0.5:
            kind = "between pieces"
            why = (f"inside the headland ({plan.headland_passes} passes of {s.working_width:g} m) but in no worked "
                   "piece of the inner field: a neck narrower than twice the headland, or a strip the pieces' swaths "
                   "left between them")
        elif length >= STRIPLIKE * width:
            kind, why = "strip", "a strip along a headland pass or a swath that neither reaches"
        else:
            kind, why = "patch", "reached by neither the swaths nor the headland passes"
        pass_m = 0.0
        if width <= s.working_width:
            axis = centre_line(piece)
            if axis.length > 0 and tractor_room.buffer(1e-6).contains(axis):
                pass_m = float(axis.length)
                why += f"; one pass of its own along its medial axis ({pass_m:.0f} m) would cover it" + (
                    ": no such pass keeps its run-in and run-out inside the field and works it" if s.leftover_passes else
                    ", not driven: leftover passes are off (--leftover-passes on)")
            else:
                why += "; a pass along its medial axis would take the tractor within its half width of the boundary"
        else:
            why += f"; wider ({width:.1f} m) than one pass of {s.working_width:g} m"
        named.append(Leftover(kind, float(piece.area), width, length, why,
                              (float(piece.centroid.x), float(piece.centroid.y)), pass_m, piece))
    named.sort(key=lambda x: -x.area)
    return named, slivers
