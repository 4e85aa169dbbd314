"""The planner's intermediates, stage to stage (local metres of the field, fields.field):

    Field --headland--> inner field, HeadlandPass rings --decomposition--> region --swaths--> Swath lines
          --decomposition--> Cell --route order--> Route --turns--> Segment list --speed--> Path

A ``Swath`` is a polyline (straight swaths have two points; a curved one more), a ``Cell`` the swaths
driven as one boustrophedon block, a ``Route`` the work in driving order (oriented swaths and headland
passes) before the moves between them are known, a ``Segment`` a typed piece of the drivable path
(swath, turn, headland pass, transit) with the heading and curvature at its vertices.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SWATH, TURN, HEADLAND, TRANSIT = 0, 1, 2, 3
KINDS = {SWATH: "swath", TURN: "turn", HEADLAND: "headland", TRANSIT: "transit"}
WORKING = (SWATH, HEADLAND)        # the implement works on these


def _frozen(array) -> np.ndarray:
    """The array as float, read-only (no copy when it is one already)."""
    out = np.asarray(array, float)
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class Swath:
    """A pass the implement works, driven from its first point to its last."""

    index: int                  # its number among the field's swaths (line by line, along each line)
    line: int                   # the line across the field it lies on (several swaths share a line that crosses a hole)
    points: np.ndarray          # (N >= 2, 2) east, north

    def __post_init__(self) -> None:
        object.__setattr__(self, "points", _frozen(self.points))

    @property
    def start(self) -> np.ndarray:
        return self.points[0]

    @property
    def end(self) -> np.ndarray:
        return self.points[-1]

    @property
    def length(self) -> float:
        return float(np.sum(np.hypot(*np.diff(self.points, axis=0).T)))

    def direction(self, at_end: bool = False) -> np.ndarray:
        """Unit tangent at its start (or end), in the driving direction."""
        d = self.points[-1] - self.points[-2] if at_end else self.points[1] - self.points[0]
        return d / max(float(np.hypot(*d)), 1e-12)

    def reversed(self) -> "Swath":
        return Swath(self.index, self.line, self.points[::-1])

    def extended(self, by: float) -> "Swath":
        """Longer by ``by`` at each end, along its end tangents."""
        pts = np.array(self.points)
        pts[0] -= by * self.direction()
        pts[-1] += by * self.direction(at_end=True)
        return Swath(self.index, self.line, pts)


@dataclass(frozen=True, eq=False)
class Cell:
    """Swaths on consecutive lines that continue one another: driven as one block."""

    index: int
    swaths: tuple[Swath, ...]   # in the order of their lines across the field
    piece: int = 0              # the piece of the inner field it lies in


@dataclass(frozen=True, eq=False)
class HeadlandPass:
    """A closed pass round the field (or round a hole) at a headland ring's offset."""

    index: int                  # ring number: 0 the outermost
    hole: int                   # 0: round the field's outer boundary; j: the j-th other ring at this offset
    points: np.ndarray          # (N, 4) x, y, heading (unwrapped), curvature; counter-clockwise round the field

    def __post_init__(self) -> None:
        object.__setattr__(self, "points", _frozen(self.points))


@dataclass(frozen=True, eq=False)
class Route:
    """The work in driving order: oriented, extended swaths, then the headland passes (each driven
    either way round, whichever the turn onto it makes shorter)."""

    passes: tuple[Swath | HeadlandPass, ...]
    cell_starts: frozenset[int]          # positions in ``passes`` where a new cell begins
    how: str                             # the order, in words

    @property
    def swaths(self) -> list[Swath]:
        return [p for p in self.passes if isinstance(p, Swath)]


@dataclass(frozen=True, eq=False)
class Segment:
    """A typed piece of the drivable path: its vertices with the heading and curvature there."""

    kind: int                   # SWATH, TURN, HEADLAND or TRANSIT
    index: int                  # the swath's line, the headland ring, or -1
    points: np.ndarray          # (N >= 2, 4) x, y, heading, curvature
    work: np.ndarray | None = None  # (M, 2): the implement's line where it is not the path's (a curved swath)

    def __post_init__(self) -> None:
        object.__setattr__(self, "points", _frozen(self.points))
        if self.work is not None:
            object.__setattr__(self, "work", _frozen(self.work))

    @property
    def length(self) -> float:
        return float(np.sum(np.hypot(*np.diff(self.points[:, :2], axis=0).T)))
