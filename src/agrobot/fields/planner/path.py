"""The drivable path: typed segments end to end, with the speed profile, evaluated at any arc
length on demand. Its memory is that of its vertices (a straight is two), not of a sampling of
the whole route: the route component evaluates a short window round the vehicle, route.csv is
written a chunk at a time.

At arc length s on the polyline between vertices j and j + 1: position and curvature linear in
s; heading the direction of the chord from s - h to s + h (h = ROUTE_STEP: the central difference
of positions on the trackers' grid), unwrapped along the whole path; the kind and index of the
segment s lies in (a segment runs from its start up to, not including, its end).
"""
from __future__ import annotations

import math
from typing import Callable, Iterator, Sequence

import numpy as np

from .sampling import ROUTE_STEP
from .speed import SpeedProfile
from .types import KINDS, Segment

COLUMNS = ("s", "x", "y", "heading", "curvature", "speed", "kind", "index")
CHUNK = 100_000          # samples evaluated at a time when the whole path is streamed


class Path:
    def __init__(self, segments: Sequence[Segment],
                 speed: Callable[[np.ndarray, np.ndarray, np.ndarray], SpeedProfile]) -> None:
        """``speed(starts, ends, kinds)``: the speed profile over the segments (fields.planner.speed)."""
        segments = [seg for seg in segments if seg.length > 1e-9]
        if not segments:
            raise ValueError("a path needs at least one segment of some length")
        vertices, arc, first = [], [], []
        start = 0.0
        for seg in segments:
            v = seg.points
            if vertices and np.hypot(*(v[0, :2] - vertices[-1][-1, :2])) > 1e-9:   # a gap (a turn's end tolerance):
                v = np.vstack([np.r_[vertices[-1][-1, :2], v[0, 2:]], v])          # bridged by this segment
            step = np.hypot(*np.diff(v[:, :2], axis=0).T)
            keep = np.concatenate([[True], step > 1e-9])          # no zero-length chords
            v, step = v[keep], step[keep[1:]]
            first.append(sum(len(x) for x in vertices))
            vertices.append(v)
            arc.append(start + np.concatenate([[0.0], np.cumsum(step)]))
            start = arc[-1][-1]
        self._v = np.vstack(vertices)
        self._v[:, 2] = np.unwrap(self._v[:, 2])
        self._s = np.concatenate(arc)
        self._first = np.array(first)
        self._last = np.append(self._first[1:], len(self._v)) - 1
        self._kind = np.array([seg.kind for seg in segments])
        self._index = np.array([seg.index for seg in segments])
        self._work = tuple(seg.work for seg in segments)
        self._s0 = self._s[self._first]
        self.length = float(self._s[-1])
        self.speed = speed(self._s0, self._s[self._last], self._kind)
        for a in (self._v, self._s):
            a.setflags(write=False)

    # --- the segments ---------------------------------------------------------------------------------
    def __len__(self) -> int:
        return len(self._kind)

    @property
    def segments(self) -> list[Segment]:
        """The segments (their vertices views into the path's)."""
        return [Segment(int(k), int(i), self._v[a:b + 1], w) for k, i, a, b, w in
                zip(self._kind, self._index, self._first, self._last, self._work)]

    @property
    def starts(self) -> np.ndarray:
        return self._s0

    @property
    def kinds(self) -> np.ndarray:
        return self._kind

    def distances(self) -> dict[int, float]:
        """Length [m] of the path by segment kind."""
        lengths = self._s[self._last] - self._s0
        return {k: float(lengths[self._kind == k].sum()) for k in KINDS}

    def time(self) -> float:
        """Driving time [s] along the speed profile."""
        return self.speed.time()

    # --- evaluation -------------------------------------------------------------------------------------
    def _segment_of(self, s: np.ndarray) -> np.ndarray:
        return np.clip(np.searchsorted(self._s0, s, side="right") - 1, 0, len(self._kind) - 1)

    def _interpolate(self, s: np.ndarray, k: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(vertex j, share t towards j + 1) of the arc lengths s on segments k."""
        j = np.clip(np.searchsorted(self._s, s, side="right") - 1, self._first[k], np.maximum(self._last[k] - 1,
                                                                                               self._first[k]))
        j1 = np.minimum(j + 1, self._last[k])
        span = self._s[j1] - self._s[j]
        t = np.clip((s - self._s[j]) / np.where(span > 0, span, 1.0), 0.0, 1.0)
        return j, t

    def position(self, s) -> np.ndarray:
        """(N, 2) east, north at arc lengths s (clipped to the path)."""
        s = np.clip(np.asarray(s, float), 0.0, self.length)
        k = self._segment_of(s)
        j, t = self._interpolate(s, k)
        j1 = np.minimum(j + 1, self._last[k])
        return self._v[j, :2] + t[:, None] * (self._v[j1, :2] - self._v[j, :2])

    def evaluate(self, s) -> dict[str, np.ndarray]:
        """The columns COLUMNS at arc lengths s (clipped to the path)."""
        s = np.clip(np.atleast_1d(np.asarray(s, float)), 0.0, self.length)
        k = self._segment_of(s)
        j, t = self._interpolate(s, k)
        j1 = np.minimum(j + 1, self._last[k])
        v0, v1 = self._v[j], self._v[j1]
        xy = v0[:, :2] + t[:, None] * (v1[:, :2] - v0[:, :2])
        ahead, behind = self.position(s + ROUTE_STEP), self.position(s - ROUTE_STEP)
        chord = np.arctan2(ahead[:, 1] - behind[:, 1], ahead[:, 0] - behind[:, 0])
        near = v0[:, 2] + t * (v1[:, 2] - v0[:, 2])                 # the vertices' unwrapped heading
        heading = near + (chord - near + math.pi) % (2 * math.pi) - math.pi
        return {"s": s, "x": xy[:, 0], "y": xy[:, 1], "heading": heading,
                "curvature": v0[:, 3] + t * (v1[:, 3] - v0[:, 3]), "speed": self.speed.at(k, s),
                "kind": self._kind[k], "index": self._index[k]}

    def start_pose(self) -> tuple[float, float, float]:
        r = self.evaluate([0.0])
        return float(r["x"][0]), float(r["y"][0]), float(r["heading"][0])

    # --- sampling -------------------------------------------------------------------------------------
    def grid_size(self, step: float = ROUTE_STEP) -> int:
        """Points of the grid s = 0, step, 2 step, ... below the path's length."""
        return max(1, math.ceil(self.length / step))

    def grid(self, first: int, stop: int, step: float = ROUTE_STEP) -> dict[str, np.ndarray]:
        """The columns at s = i step, first <= i < stop."""
        return self.evaluate(np.arange(first, stop) * step)

    def knots(self, step: float, uniform: bool = False) -> Iterator[np.ndarray]:
        """Arc lengths to write the path at, a chunk at a time: its vertices (a straight is its
        start), thinned to one per step / 2 of arc length, so that the rows are exact points of the
        path at most about ``step`` apart where it curves; where the speed ramps, every ``step`` at
        most; the path's end. ``uniform``: every ``step`` m along the whole path."""
        if uniform:
            n = math.ceil(self.length / step)
            for a in range(0, n, CHUNK):
                yield np.arange(a, min(n, a + CHUNK)) * step
            yield np.array([self.length])
            return
        parts, count = [], 0
        for k in range(len(self._kind)):
            a, b = self._s0[k], self._s[self._last[k]]
            s = self._s[self._first[k]:self._last[k]]                      # its vertices but the last
            bins = np.floor((s - a) / (0.5 * step))
            parts.append(s[np.concatenate([[True], bins[1:] != bins[:-1]])])
            for lo, hi in self.speed.ramps(k):
                if hi > lo:
                    n = math.ceil((hi - lo) / step)
                    ramp = lo + (hi - lo) * np.arange(n + 1) / n
                    parts.append(ramp[ramp < b])
            count += len(parts[-1])
            if count >= CHUNK or k == len(self._kind) - 1:
                yield np.unique(np.concatenate(parts))
                parts, count = [], 0
        yield np.array([self.length])
