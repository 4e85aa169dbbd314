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

import numpy as np
from shapely import contains_xy
from shapely.geometry import Polygon

from ..field import Field, FieldError
from .curves import Limits, connect
from .headland import reversed_ring, ring_path
from .sampling import POLYLINE_STEP
from .settings import Settings
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
    parts = [xy[i] + np.linspace(0.0, 1.0, k + 1)[:-1, None] * d[i] for i, k in enumerate(n)]
    return np.vstack(parts + [xy[-1:]])


def outside(path: np.ndarray, inside: Polygon) -> np.ndarray | None:
    """The first point of the path (its chords checked every POLYLINE_STEP) not inside, or None."""
    xy = densified(path[:, :2])
    ok = contains_xy(inside, xy[:, 0], xy[:, 1])
    return None if ok.all() else xy[int(np.argmin(ok))]


def length_of(path: np.ndarray) -> float:
    return float(np.sum(np.hypot(*np.diff(path[:, :2], axis=0).T)))


class Joiner:
    """Joins a route's passes; ``segments`` grows as it goes, ``notes`` says what was left out."""

    def __init__(self, field: Field, settings: Settings, passes: int, where: str, notes: list[str]) -> None:
        self.field, self.settings, self.passes, self.where, self.notes = field, settings, passes, where, notes
        self.limits: Limits = settings.limits
        self.inside = field.boundary.buffer(-settings.half_width)
        self.segments: list[Segment] = []
        self._innermost: list[np.ndarray] | None = None

    def join(self, route: Route) -> list[Segment]:
        previous, last_swath = None, None
        for k, item in enumerate(route.passes):
            if isinstance(item, Swath):
                previous = self._swath(item, previous, last_swath, k in route.cell_starts)
                last_swath = item
            else:
                self._headland_pass(item)
        return self.segments

    def _swath(self, sw: Swath, previous, last: Swath | None, new_cell: bool) -> tuple[float, float, float]:
        s = self.settings
        d_in, d_out = sw.direction(), sw.direction(at_end=True)
        heading_in = math.atan2(d_in[1], d_in[0])
        run_in = sw.start - s.lead * d_in
        if previous is not None:
            turn = connect(previous, (run_in[0], run_in[1], heading_in), self.limits)
            if turn is None:
                raise FieldError(f"{self.where}: no turn within the limits from swath {last.line} to swath {sw.line}")
            path = np.vstack([turn, straight(run_in, sw.start)[1:]])
            off = outside(path, self.inside)
            if off is not None and new_cell:               # to another cell: round by the headland
                via = self._via_headland(previous, (run_in[0], run_in[1], heading_in))
                if via is not None:
                    self.segments.append(Segment(TRANSIT, -1, via))
                    path, off = straight(run_in, sw.start), None
            if off is not None:
                raise TurnOutside(f"{self.where}: the turn from swath {last.line} to swath {sw.line} leaves the field "
                                  f"near ({off[0]:.1f}, {off[1]:.1f}) m: the headland ({self.passes} x "
                                  f"{s.working_width:g} m) cannot hold a turn of radius {s.turn_radius:g} m")
        else:
            path = straight(run_in, sw.start)
        run_out = sw.end + s.lead * d_out
        self.segments += [Segment(TURN, -1, path), Segment(SWATH, sw.line, polyline_path(sw.points)),
                          Segment(TURN, -1, straight(sw.end, run_out))]
        return run_out[0], run_out[1], math.atan2(d_out[1], d_out[0])

    def _via_headland(self, a, b) -> np.ndarray | None:
        """A transit from pose a to pose b along the innermost headland pass (either way round, the
        field's outer ring or a hole's), joined by continuous-curvature turns; the shortest inside
        the field, or None."""
        s = self.settings
        if self._innermost is None:
            self._innermost = ring_path(self.field, (self.passes - 0.5) * s.working_width, s.turn_radius)
        best = None
        for ring in self._innermost:
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
                    if (best is None or length < best[0]) and outside(path, self.inside) is None:
                        best = (length, path)
                        break
        return None if best is None else best[1]

    def _headland_pass(self, ring: HeadlandPass) -> None:
        s = self.settings
        last = self.segments[-1].points[-1, :3].copy()
        if self.segments[-1].kind == HEADLAND:                 # leave a pass along its last chord
            p = self.segments[-1].points
            last[2] = math.atan2(p[-1, 1] - p[-2, 1], p[-1, 0] - p[-2, 0])
        best = None
        for way in (ring.points, reversed_ring(ring.points)):   # either way round: the shorter way on
            found = self._onto_ring(last, way)
            if found is not None and (best is None or length_of(found[0]) < length_of(best[0])):
                best = (*found, way)
        if best is None:
            self.notes.append(f"headland pass {ring.index + 1}{'' if ring.hole == 0 else f' (hole {ring.hole})'}: "
                              f"no turn onto it within the field; left out")
            return
        path, i, way = best
        self.segments.append(Segment(TRANSIT, ring.index, path))
        # once round and on by the implement's length, so that it closes the loop where it came in
        more = int(math.ceil((s.hitch_offset + s.drawbar + 1.0) / POLYLINE_STEP))
        loop = np.vstack([way[i:], way[:i + 1], way[i + 1:][:more], way[:max(0, more - (len(way) - i - 1))]])
        self.segments.append(Segment(HEADLAND, ring.index, loop))

    def _onto_ring(self, pose, ring: np.ndarray) -> tuple[np.ndarray, int] | None:
        """(path, index): a turn from pose onto the ring a little along it from its nearest points,
        inside the field, or None."""
        candidates = np.argsort(np.hypot(ring[:, 0] - pose[0], ring[:, 1] - pose[1]))
        for lead in ONTO_RING_JOINS:
            for i0 in candidates[:5]:
                i = (i0 + int(lead / POLYLINE_STEP)) % len(ring)
                path = connect(pose, ring[i, :3], self.limits)
                if path is not None and outside(path, self.inside) is None:
                    return path, int(i)
        return None
