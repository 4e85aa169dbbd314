"""Turns and transits: the Route joined into a drivable sequence of typed segments.

- **Between swaths**: a straight run-out of the implement's length and ``settle`` after each swath,
  a continuous-curvature turn (fields.planner.curves) within the curvature and the steering-rate
  limits, a straight run-in before the next; each turn checked to stay inside the field by the
  tractor's half width. A move to another cell that would leave the field goes round the innermost
  headland pass (a transit).
- **Headland passes**: after the swaths, each ring from the innermost out, either way round
  (whichever the turn onto it makes shorter), once round and on by the implement's length,
  joined by continuous-curvature transits.
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np
from shapely import contains_xy
from shapely.geometry import Point, Polygon
from shapely.ops import unary_union

from ..field import Field, FieldError
from .curves import Limits, connect
from .headland import corner_radius, reversed_ring, ring_path
from .sampling import POLYLINE_STEP
from .settings import Settings
from .curved_swaths import tractor_line
from .types import HEADLAND, SWATH, TRANSIT, TURN, HeadlandPass, Route, Segment, Swath

VIA_HEADLAND_JOINS = (10.0, 20.0, 30.0)     # m along the ring past the nearest point where a transit joins it
ONTO_RING_JOINS = (8.0, 14.0, 20.0, 30.0)   # m along a headland pass where the turn onto it may join


class TurnOutside(FieldError):
    """A turn between swaths leaves the field (the planner may widen the headland)."""


def polyline_path(points: np.ndarray) -> np.ndarray:
    """(N, 4) x, y, heading (of the chord on), curvature (d heading / ds) of an open polyline."""
    d = np.diff(points, axis=0)
    heading = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
    heading = np.append(heading, heading[-1])
    ds = np.append(np.hypot(d[:, 0], d[:, 1]), 1.0)
    curvature = np.gradient(heading) / np.maximum(ds, 1e-6) if len(points) > 2 else np.zeros(len(points))
    return np.column_stack([points, heading, curvature])


def straight(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return polyline_path(np.array([a, b], float))


def densified(xy: np.ndarray, step: float = POLYLINE_STEP) -> np.ndarray:
    """The polyline with points inserted so that no chord is longer than ``step``."""
    d = np.diff(xy, axis=0)
    n = np.maximum(1, np.ceil(np.hypot(d[:, 0], d[:, 1]) / step).astype(int))
    if n.max() == 1:
        return xy
    chord = np.repeat(np.arange(len(d)), n)                       # each new point's chord
    share = (np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)) / np.repeat(n, n)
    return np.vstack([xy[chord] + share[:, None] * d[chord], xy[-1:]])


def outside(path: np.ndarray, inside: Polygon) -> np.ndarray | None:
    """The first point of the path (its chords checked every POLYLINE_STEP) not inside, or None."""
    xy = densified(path[:, :2])
    ok = contains_xy(inside, xy[:, 0], xy[:, 1])
    return None if ok.all() else xy[int(np.argmin(ok))]


def length_of(path: np.ndarray) -> float:
    return float(np.sum(np.hypot(*np.diff(path[:, :2], axis=0).T)))


class Joiner:
    """Joins a route's passes; ``segments`` grows as it goes, ``notes`` says what was left out."""

    def __init__(self, field: Field, settings: Settings, passes: int, where: str, notes: list[str],
                 pieces: Sequence[Polygon] = ()) -> None:
        self.field, self.settings, self.passes, self.where, self.notes = field, settings, passes, where, notes
        self.limits: Limits = settings.limits
        self.inside = field.boundary.buffer(-settings.half_width)
        # transits keep to the headland: out of the inner field's pieces deeper than a working width
        worked = unary_union([p.buffer(-settings.working_width) for p in pieces]) if pieces else None
        self.headland = self.inside if worked is None or worked.is_empty else self.inside.difference(worked)
        self.segments: list[Segment] = []
        self._rings: dict[int, list[np.ndarray]] = {}

    def join(self, route: Route) -> list[Segment]:
        s = self.settings
        pose, last_swath = None, None
        if s.start_point is not None:
            pose = self._start(route)
        for k, item in enumerate(route.passes):
            if isinstance(item, Swath):
                new_cell = k in route.cell_starts or not isinstance(last_swath, Swath)
                pose = self._swath(item, pose, last_swath, new_cell, self.inside if k == 0 else None)
                last_swath = item
            else:
                pose = self._headland_pass(item, pose)
                last_swath = item
        if s.end_point is not None:
            self._end(pose)
        return self.segments

    def more(self, segments: list[Segment], passes: Sequence[Swath]) -> tuple[list[Segment], list[Swath]]:
        """Further passes after a joined route (before its transit to the end point): each by a
        turn, else a transit along a headland pass, as a move to another cell, driven either way; a
        pass that cannot be joined inside the field is left out (the notes say so). (segments, the
        passes joined, as driven)."""
        s = self.settings
        self.segments = list(segments)
        end = s.end_point
        if end is not None and self.segments and self.segments[-1].kind == TRANSIT and \
                math.hypot(*(self.segments[-1].points[-1, :2] - np.asarray(end))) < 1e-6:
            self.segments.pop()
        p = self.segments[-1].points[-1]
        pose, last, joined, missed = (float(p[0]), float(p[1]), float(p[2])), None, [], []
        for sw in passes:
            for way in (sw, sw.reversed()):                 # either way along it
                try:
                    pose = self._swath(way, pose, last, True, None)
                except FieldError:
                    continue
                joined.append(way)
                last = way
                break
            else:
                missed.append(sw)
        if missed:
            self.notes.append(f"{len(missed)} leftover pass(es), {sum(sw.length for sw in missed):.0f} m: no turn onto "
                              f"them inside the field either way; left out")
        if end is not None:
            self._end(pose)
        return self.segments, joined

    # --- the user's start and end points ------------------------------------------------------------
    def _start(self, route: Route) -> tuple[float, float, float]:
        """The start pose: at the user's point, facing the first pass's entry."""
        x, y = self.settings.start_point
        self._check_point("start_point", x, y)
        first = route.passes[0]
        entry = first.start - self.settings.lead * first.direction() if isinstance(first, Swath) else first.points[0, :2]
        return x, y, math.atan2(entry[1] - y, entry[0] - x)

    def _end(self, pose) -> None:
        x, y = self.settings.end_point
        self._check_point("end_point", x, y)
        if math.hypot(x - pose[0], y - pose[1]) < 1e-6:
            return
        goal = (x, y, math.atan2(y - pose[1], x - pose[0]))
        path = self._transit(pose, goal, self.inside)
        if path is None:
            raise FieldError(f"{self.where}: end_point = ({x:g}, {y:g}) m: no drivable way to it inside the field from "
                             f"the route's last pass (a continuous-curvature path within turn radius "
                             f"{self.settings.turn_radius:g} m, the tractor's half width inside the boundary)")
        self.segments.append(Segment(TRANSIT, -1, path))

    def _check_point(self, name: str, x: float, y: float) -> None:
        point = Point(x, y)
        if self.inside.contains(point):
            return
        if not Polygon(self.field.boundary.exterior).contains(point):
            what = "outside the field"
        elif not self.field.boundary.contains(point):
            what = "inside a hole or an obstacle of the field"
        else:
            what = f"within the tractor's half width ({self.settings.half_width:g} m) of the field's boundary"
        raise FieldError(f"{self.where}: {name} = ({x:g}, {y:g}) m (east, north of the field's origin): {what}; "
                         f"expected a point the tractor can stand on inside the field")

    # --- passes ------------------------------------------------------------------------------------------
    def _swath(self, sw: Swath, previous, last, new_cell: bool, zone: Polygon | None) -> tuple[float, float, float]:
        """The swath with its run-in and run-out, and the turn onto it from ``previous``: within the
        field; a move to another cell or piece (``new_cell``) within ``zone`` (the headland), else
        along a headland pass."""
        s = self.settings
        d_in, d_out = sw.direction(), sw.direction(at_end=True)
        heading_in = math.atan2(d_in[1], d_in[0])
        run_in = sw.start - s.lead * d_in
        goal = (run_in[0], run_in[1], heading_in)
        if previous is not None:
            turn = connect(previous, goal, self.limits)
            off = crossing = None
            if turn is not None:
                path = np.vstack([turn, straight(run_in, sw.start)[1:]])
                off = outside(path, self.inside)
                if off is None and new_cell and zone is None:
                    crossing = outside(turn, self.headland)        # across the inner field: round it if it can
            if (turn is None or off is not None or crossing is not None) and new_cell:
                via = self._via_rings(previous, goal, zone)          # to another cell or piece: by the headland
                if via is not None:
                    self.segments.append(Segment(TRANSIT, -1, via))
                    path, off, turn = straight(run_in, sw.start), None, via
            if turn is None:
                raise FieldError(f"{self.where}: no turn within the limits from {_name(last)} to swath {sw.line}")
            if off is not None:
                raise TurnOutside(f"{self.where}: the turn from {_name(last)} to swath {sw.line} leaves the field "
                                  f"near ({off[0]:.1f}, {off[1]:.1f}) m: the headland ({self.passes} x "
                                  f"{s.working_width:g} m) cannot hold a turn of radius {s.turn_radius:g} m")
        else:
            path = straight(run_in, sw.start)
        run_out = sw.end + s.lead * d_out
        axle = tractor_line(sw.points, s.hitch_offset, s.drawbar, s.lead)
        work = sw.points if len(sw.points) > 2 else None             # a curved swath: the implement on it, not the axle
        self.segments += [Segment(TURN, -1, path), Segment(SWATH, sw.line, polyline_path(axle), work),
                          Segment(TURN, -1, straight(sw.end, run_out))]
        return run_out[0], run_out[1], math.atan2(d_out[1], d_out[0])

    def _headland_pass(self, ring: HeadlandPass, last) -> tuple[float, float, float] | None:
        s = self.settings
        if last is not None and self.segments and self.segments[-1].kind == HEADLAND:   # leave a pass along its last chord
            p = self.segments[-1].points
            last = (last[0], last[1], math.atan2(p[-1, 1] - p[-2, 1], p[-1, 0] - p[-2, 0]))
        best = None
        for way in (ring.points, reversed_ring(ring.points)):   # either way round: the shorter way on
            found = (None, 0) if last is None else self._onto_ring(last, way)
            if found is not None and (best is None or length_of(found[0]) < length_of(best[0])):
                best = (*found, way)
            if last is None:
                break
        if best is None:
            self.notes.append(f"headland pass {ring.index + 1}{'' if ring.hole == 0 else f' (ring {ring.hole + 1})'}: "
                              f"no way onto it within the field; left out")
            return last
        path, i, way = best
        if path is not None:
            self.segments.append(Segment(TRANSIT, ring.index, path))
        # once round and on by the implement's length, so that it closes the loop where it came in
        more = int(math.ceil((s.hitch_offset + s.drawbar + 1.0) / POLYLINE_STEP))
        loop = np.vstack([way[i:], way[:i + 1], way[i + 1:][:more], way[:max(0, more - (len(way) - i - 1))]])
        self.segments.append(Segment(HEADLAND, ring.index, loop))
        return float(loop[-1, 0]), float(loop[-1, 1]), float(loop[-1, 2])

    def _onto_ring(self, pose, ring: np.ndarray) -> tuple[np.ndarray, int] | None:
        """(path, index): a turn from pose onto the ring a little along it from its nearest points,
        inside the field (directly, else round another headland pass), or None."""
        candidates = np.argsort(np.hypot(ring[:, 0] - pose[0], ring[:, 1] - pose[1]))
        for lead in ONTO_RING_JOINS:
            for i0 in candidates[:5]:
                i = (i0 + int(lead / POLYLINE_STEP)) % len(ring)
                path = connect(pose, ring[i, :3], self.limits)
                if path is not None and outside(path, self.inside) is None:
                    return path, int(i)
        i = int((candidates[0] + int(ONTO_RING_JOINS[-1] / POLYLINE_STEP)) % len(ring))
        path = self._via_rings(pose, ring[i, :3])
        return None if path is None else (path, i)

    # --- transits -----------------------------------------------------------------------------------
    def _transit(self, a, b, zone: Polygon | None = None) -> np.ndarray | None:
        """A drivable way from pose a to pose b in ``zone`` (the headland: the field but the inner
        field's pieces deeper than a working width): directly, else along a headland pass."""
        zone = self.headland if zone is None else zone
        path = connect(a, b, self.limits)
        if path is not None and outside(path, zone) is None:
            return path
        return self._via_rings(a, b, zone)

    def _ring_loops(self, k: int) -> list[np.ndarray]:
        """The closed paths of headland pass k (0 the outermost), as many as the field gives at its offset."""
        if k not in self._rings:
            s = self.settings
            self._rings[k] = ring_path(self.field, (k + 0.5) * s.working_width, corner_radius(s, self.passes, k))
        return self._rings[k]

    def _via_rings(self, a, b, zone: Polygon | None = None) -> np.ndarray | None:
        """A transit from pose a to pose b along a headland pass (either way round, round the field
        or a hole), joined by continuous-curvature turns: the innermost pass first, the next ones out
        when it gives none (a narrow waist splits the inner passes); the shortest inside the field, or None."""
        for k in range(self.passes - 1, -1, -1):
            best = None
            for ring in self._ring_loops(k):
                for way in (ring, reversed_ring(ring)):
                    n = len(way)
                    i0 = int(np.argmin(np.hypot(way[:, 0] - a[0], way[:, 1] - a[1])))
                    j0 = int(np.argmin(np.hypot(way[:, 0] - b[0], way[:, 1] - b[1])))
                    for lead in VIA_HEADLAND_JOINS:
                        i, j = (i0 + int(lead / POLYLINE_STEP)) % n, (j0 - int(lead / POLYLINE_STEP)) % n
                        along = way[i:j + 1] if j >= i else np.vstack([way[i:], way[:j + 1]])
                        if len(along) < 2:
                            continue
                        onto, off = connect(a, way[i, :3], self.limits), connect(way[j, :3], b, self.limits)
                        if onto is None or off is None:
                            continue
                        path = np.vstack([onto, along[1:-1], off])
                        length = length_of(path)
                        if (best is None or length < best[0]) and outside(path, zone or self.headland) is None:
                            best = (length, path)
                            break
            if best is not None:
                return best[1]
        return None


def _name(item) -> str:
    if isinstance(item, Swath):
        return f"swath {item.line}"
    if isinstance(item, HeadlandPass):
        return f"headland pass {item.index + 1}"
    return "the start"
