"""Passes of their own for what a plan leaves (fields.planner.leftovers), driven after the rest of
the route and joined by the planner's own turns and headland transits (fields.planner.turns).

- **Corner passes**: the headland's pass k (0 the outermost) at (k + 1/2) w, its corners rounded at
  the tightest radius R (headland.ring_path), over the stretch whose strip reaches the piece, for
  k = 0, 1, ... while the piece is left. With ``parallel`` corners the outer pass rounds a corner at
  R + (n - 1) w and leaves (R + (n - 1/2) w)^2 (1 - pi/4) of a right-angled corner; a pass at R
  leaves (R + w/2)^2 (1 - pi/4) (6.5 m^2 for R = 4 m, w = 3 m), the most a forward pass can reach.
  The corner pass beside the outer pass is cheaper than a whole extra headland round: only the
  stretch at the corner is driven twice.
- **Medial-axis passes**: along the long centre line of a piece's smallest rotated rectangle
  (leftovers.centre_line; a neck or a strip between the inner field's pieces, a band along the
  middle of a field too narrow for more headland passes, a strip along a pass): one pass for a piece
  at most w across, m side by side (w - overlap apart) for one up to w + (m - 1)(w - overlap).

A pass is kept when its strip works at least MIN_GAIN m^2 not worked before, its curvature is
within 1/R, and the tractor keeps its half width inside the field on it and on its straight run-in
and run-out (the implement's length and ``settle``; on a curve the rear axle runs outside the
implement's line: curved_swaths.tractor_line); where it would not, the pass is cut there (CUT m
either side left out, a straight pass shortened from that end) and its parts judged again. The passes are driven nearest first from where the
route ends, each entered from its nearer end.
"""
from __future__ import annotations

import math

import numpy as np
import shapely
from shapely.geometry import LineString, Polygon
from shapely.ops import unary_union

from .curved_swaths import curvature, smooth_parts, tractor_line
from .headland import ring_path
from .leftovers import MIN_AREA, centre_line, leftovers, long_axis
from .sampling import POLYLINE_STEP
from .turns import outside, polyline_path
from .types import Swath

MIN_GAIN = 2.0          # m^2 of ground not worked before that a pass of its own must work
END_MARGIN = 1.0        # m a corner pass runs on beyond the last point whose strip reaches the piece
MAX_ACROSS = 4          # passes side by side along one leftover's centre line, at most
CUT = 3.0               # m left out either side of where a pass would take the tractor out of the field
KAPPA_SLACK = 1.25      # the rings' arcs at R sampled every 0.5 m read up to this over 1/R; a reflex corner far more


def strip(points: np.ndarray, width: float) -> Polygon:
    """The ground a pass along ``points`` works: its width about the line, flat at the ends."""
    return LineString(points).buffer(0.5 * width, cap_style="flat")


def off_field(points: np.ndarray, settings, inside: Polygon) -> np.ndarray | None:
    """Where the pass is not drivable: its first point with a curvature over 1/R, or the first point
    of the tractor on it (run-in and run-out included) outside ``inside``; None when it is drivable."""
    if len(points) > 2:
        bent = np.flatnonzero(curvature(points) > KAPPA_SLACK / settings.turn_radius)
        if len(bent):
            return points[bent[0] + 1]
    d0 = points[1] - points[0]
    d1 = points[-1] - points[-2]
    run_in = points[0] - settings.lead * d0 / max(float(np.hypot(*d0)), 1e-12)
    run_out = points[-1] + settings.lead * d1 / max(float(np.hypot(*d1)), 1e-12)
    axle = tractor_line(points, settings.hitch_offset, settings.drawbar, settings.lead)
    return outside(polyline_path(np.vstack([run_in, axle, run_out])), inside)


def drivable_parts(points: np.ndarray, settings, inside: Polygon) -> list[np.ndarray]:
    """The pass, or where the tractor would leave the field its drivable parts either side (CUT m
    round the point left out; parts under 2 m dropped)."""
    if len(points) < 2 or float(np.sum(np.hypot(*np.diff(points, axis=0).T))) < 2.0:
        return []
    bad = off_field(points, settings, inside)
    if bad is None:
        return [points]
    i = int(np.argmin(np.hypot(points[:, 0] - bad[0], points[:, 1] - bad[1])))
    cut = max(1, int(math.ceil(CUT / POLYLINE_STEP)))
    if len(points) == 2:                                    # a straight pass: shorten it from its nearer end
        d = points[1] - points[0]
        step = CUT * d / max(float(np.hypot(*d)), 1e-12)
        shorter = np.array([points[0] + step, points[1]]) if i == 0 else np.array([points[0], points[1] - step])
        return drivable_parts(shorter, settings, inside)
    return drivable_parts(points[:max(i - cut, 0)], settings, inside) + \
        drivable_parts(points[i + cut + 1:], settings, inside)


def runs(ring: np.ndarray, near: np.ndarray, margin: int) -> list[np.ndarray]:
    """The stretches of a closed ring (its (N, 2) points) where ``near`` holds, each widened by
    ``margin`` points either way (a stretch that wraps round the ring's start kept whole)."""
    n = len(near)
    if not near.any():
        return []
    grown = near.copy()
    for k in range(1, margin + 1):
        grown |= np.roll(near, k) | np.roll(near, -k)
    if grown.all():
        return [np.vstack([ring, ring[:1]])]
    start = int(np.argmin(grown))                       # a point off every stretch: no stretch wraps round it
    order = (np.arange(n) + start) % n
    flags = grown[order]
    edges = np.diff(np.concatenate([[0], flags.astype(int), [0]]))
    return [ring[order[a:b]] for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)) if b - a >= 2]


def corner_passes(plan, todo, inside: Polygon) -> tuple[list[np.ndarray], object]:
    """Stretches of the headland passes rounded at R that work ``todo`` (what is left), the outer first."""
    s = plan.settings
    w, chosen = s.working_width, []
    margin = int(math.ceil((0.5 * w + END_MARGIN) / POLYLINE_STEP))
    for k in range(plan.headland_passes):
        if todo.is_empty or todo.area < MIN_AREA:
            break
        for ring in ring_path(plan.field, (k + 0.5) * w, s.turn_radius):
            xy = ring[:, :2]
            near = shapely.dwithin(shapely.points(xy), todo, 0.5 * w)
            for part in (p for run in runs(xy, near, margin)
                         for p in smooth_parts(LineString(run), KAPPA_SLACK / s.turn_radius)):   # cut at a reflex corner
                for piece in drivable_parts(part, s, inside):
                    if strip(piece, w).intersection(todo).area >= MIN_GAIN:
                        chosen.append(piece)
                        todo = todo.difference(strip(piece, w))
    return chosen, todo


def axis_passes(plan, todo, inside: Polygon) -> tuple[list[np.ndarray], object]:
    """Straight passes along the centre line of each piece left (leftovers.long_axis): m of them
    side by side, w - overlap apart, m the fewest that span its width (at most MAX_ACROSS)."""
    s = plan.settings
    chosen = []
    for piece in [g for g in getattr(todo, "geoms", [todo]) if isinstance(g, Polygon) and g.area >= MIN_AREA]:
        across = long_axis(piece)[2]
        m = max(1, math.ceil((across - s.working_width) / s.spacing - 1e-9) + 1)
        if m > MAX_ACROSS:
            continue
        for j in range(m):
            axis = centre_line(piece, (j - 0.5 * (m - 1)) * s.spacing)
            if axis.length < POLYLINE_STEP:
                continue
            for part in drivable_parts(np.asarray(axis.coords)[[0, -1]], s, inside):
                if strip(part, s.working_width).intersection(piece).area >= MIN_GAIN:
                    chosen.append(part)
    if chosen:
        todo = todo.difference(unary_union([strip(p, s.working_width) for p in chosen]))
    return chosen, todo


def passes(plan, covered, first_index: int) -> tuple[list[Swath], str]:
    """The passes of their own for what ``plan`` leaves unworked (``covered``: what it works), in
    driving order from where its route ends; and what they work, in words."""
    s = plan.settings
    named, _ = leftovers(plan, covered)
    if not named:
        return [], "nothing left for passes of their own"
    left = unary_union([x.shape for x in named])
    inside = plan.field.boundary.buffer(-s.half_width)
    corners, todo = corner_passes(plan, left, inside)
    axes, todo = axis_passes(plan, todo, inside)
    parts = corners + axes
    if not parts:
        return [], f"no pass of its own works the {left.area:.0f} m^2 left (named in plan.json with why)"
    end = plan.path.segments[-1].points[-1, :2] if plan.path.segments else parts[0][0]
    ordered, at = [], np.asarray(end, float)
    pending = list(parts)
    while pending:                                         # the nearest pass next, from its nearer end
        k = int(np.argmin([min(np.hypot(*(p[0] - at)), np.hypot(*(p[-1] - at))) for p in pending]))
        p = pending.pop(k)
        p = p if np.hypot(*(p[0] - at)) <= np.hypot(*(p[-1] - at)) else p[::-1]
        ordered.append(p)
        at = p[-1]
    swaths = [Swath(first_index + i, first_index + i, p) for i, p in enumerate(ordered)]
    length = sum(sw.length for sw in swaths)
    return swaths, (f"{len(corners)} pass(es) along the boundary at the turn radius {s.turn_radius:g} m (the corners) "
                    f"and {len(axes)} along a leftover's medial axis, {length:.0f} m, to work {left.area - todo.area:.0f} of the "
                    f"{left.area:.0f} m^2 the route leaves")
