"""Section control: an implement of N sections, each switched off over ground already worked and
outside the field, with on and off latency (ISO 11783-10's TC-SC, AgOpenGPS's section control).

Section i of N spans the lateral offsets [-w/2 + i w/N, -w/2 + (i + 1) w/N] about the working point
(left positive). Each section is wanted where any of its ground ahead is workable (inside the field,
out of holes and obstacles) and not yet worked; it is *commanded* on or off that far ahead that
the command takes effect as it reaches that ground (a look-ahead of v t_on, v t_off), and *is* on
or off t_on or t_off after its command (the valves', clutches' latency).

Worked ground is kept on a raster (``CoverageMap``): each cell the arc length (or distance
travelled) at which it was last worked. A cell counts as worked for a decision only when it was
worked at least ``FRESH`` working widths of travel ago, so that a section does not switch itself
off over the ground it has just worked beside (the inner side of a curve); a headland pass that
closes on itself, or a swath end over the headland, sees its earlier work.
"""
from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np
from shapely import contains_xy
from shapely.geometry import Polygon

from ..field import FieldError

FRESH = 2.0             # working widths of travel before a section's own work counts as worked
MAX_CELLS = 2.0e7       # raster cells at most (80 MB of float32)
ACROSS = 4              # decision points across each section at least


@dataclass(frozen=True)
class SectionLayout:
    """N equal sections across a working width w."""

    width: float
    count: int

    @property
    def section_width(self) -> float:
        return self.width / self.count

    @property
    def centres(self) -> np.ndarray:
        """Lateral offsets [m, left positive] of the sections' centres."""
        return -0.5 * self.width + (np.arange(self.count) + 0.5) * self.section_width

    def across(self, step: float) -> tuple[np.ndarray, np.ndarray]:
        """(offsets, section of each): points across the width at most ``step`` apart, each section
        at least ACROSS of them, the outermost a hair inside its edges."""
        per = max(ACROSS, math.ceil(self.section_width / step))
        share = (np.arange(per) + 0.5) / per
        offsets = -0.5 * self.width + (np.arange(self.count)[:, None] + share[None, :]) * self.section_width
        return offsets.ravel(), np.repeat(np.arange(self.count), per)


def check_sections(count, width: float, where: str) -> int:
    """The section count: a whole number from 1 to 64 whose sections are at least 5 cm wide."""
    try:
        n = int(count)
    except (TypeError, ValueError):
        raise FieldError(f"{where}: sections = {count!r}: expected a whole number of sections") from None
    if n != count or not 1 <= n <= 64:
        raise FieldError(f"{where}: sections = {count!r}: expected a whole number from 1 to 64")
    if width / n < 0.05:
        raise FieldError(f"{where}: sections = {n} on a working width of {width:g} m: sections of "
                         f"{100 * width / n:.1f} cm; expected sections at least 5 cm wide")
    return n


class CoverageMap:
    """The worked ground on a raster over ``region``'s bounds: per cell the distance travelled when
    it was last worked (nan: never); cells outside ``region`` are never workable."""

    def __init__(self, region: Polygon, cell: float) -> None:
        minx, miny, maxx, maxy = region.bounds
        area = max((maxx - minx) * (maxy - miny), 1e-9)
        self.cell = max(cell, math.sqrt(area / MAX_CELLS))
        self.x0, self.y0 = minx - self.cell, miny - self.cell
        self.nx = int(math.ceil((maxx - minx) / self.cell)) + 3
        self.ny = int(math.ceil((maxy - miny) / self.cell)) + 3
        self.worked = np.full((self.ny, self.nx), np.nan, np.float32)
        self.region = region
        gx = self.x0 + (np.arange(self.nx) + 0.5) * self.cell
        gy = self.y0 + (np.arange(self.ny) + 0.5) * self.cell
        self.workable = np.zeros((self.ny, self.nx), bool)
        for r0 in range(0, self.ny, 512):                 # a band of rows at a time: bounded memory
            xx, yy = np.meshgrid(gx, gy[r0:r0 + 512])
            self.workable[r0:r0 + 512] = contains_xy(region, xx, yy)

    def index(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(row, column, on the raster) of points."""
        c = np.floor((np.asarray(x) - self.x0) / self.cell).astype(np.int64)
        r = np.floor((np.asarray(y) - self.y0) / self.cell).astype(np.int64)
        ok = (c >= 0) & (c < self.nx) & (r >= 0) & (r < self.ny)
        return np.where(ok, r, 0), np.where(ok, c, 0), ok

    def open_ground(self, x: np.ndarray, y: np.ndarray, now: float, fresh: float) -> np.ndarray:
        """Whether each point is workable ground not worked before ``now - fresh``."""
        r, c, ok = self.index(x, y)
        done = self.worked[r, c]
        return ok & self.workable[r, c] & ~(done <= now - fresh)

    def paint(self, x: np.ndarray, y: np.ndarray, when: np.ndarray | float) -> None:
        r, c, ok = self.index(x, y)
        when = np.broadcast_to(np.asarray(when, np.float32), np.shape(x))
        self.worked[r[ok], c[ok]] = when[ok]


class SectionControl:
    """The sections' commands and states, step by step (the route component's, in a simulation):
    ``step(t, travelled, x, y, heading, speed, working)`` with the implement's working point, its
    heading and speed, and whether the route wants it working; returns the sections' states."""

    def __init__(self, region: Polygon, layout: SectionLayout, on_delay: float = 0.3, off_delay: float = 0.2,
                 look_ahead: bool = True, cell: float = 0.1) -> None:
        self.layout, self.on_delay, self.off_delay, self.look_ahead = layout, on_delay, off_delay, look_ahead
        self.map = CoverageMap(region, min(cell, layout.section_width / 2))
        self.offsets, self.owner = layout.across(self.map.cell)              # where the sections look
        self.brush, self.brush_owner = layout.across(0.5 * self.map.cell)    # and what they paint
        self.commanded = np.zeros(layout.count, bool)
        self.state = np.zeros(layout.count, bool)
        self.pending: deque[tuple[float, np.ndarray]] = deque()
        self.last: tuple[float, float, float, float] | None = None        # travelled, x, y, heading

    def wanted(self, x: float, y: float, heading: float, travelled: float, ahead: float) -> np.ndarray:
        """Which sections have workable ground not yet worked ``ahead`` m in front of the working point
        (and a raster cell more: the cell under the working point is being worked by the section itself)."""
        return open_sections(self.map, np.array([x]), np.array([y]), np.array([heading]), np.array([travelled]),
                             self.offsets, self.owner, self.layout, ahead + self.map.cell)[0]

    def step(self, t: float, travelled: float, x: float, y: float, heading: float, speed: float,
             working: bool) -> np.ndarray:
        v = max(speed, 0.0) if self.look_ahead else 0.0
        on_ahead = self.wanted(x, y, heading, travelled, v * self.on_delay) if working else np.zeros_like(self.state)
        off_ahead = self.wanted(x, y, heading, travelled, v * self.off_delay) if working else np.zeros_like(self.state)
        command = np.where(self.commanded, off_ahead, on_ahead)
        if not np.array_equal(command, self.commanded):
            self.commanded = command
            self.pending.append((t, command.copy()))
        # the states follow the commands after the latency (on and off each its own)
        while self.pending:
            t_cmd, cmd = self.pending[0]
            switch_on = cmd & ~self.state & (t >= t_cmd + self.on_delay - 1e-9)
            switch_off = ~cmd & self.state & (t >= t_cmd + self.off_delay - 1e-9)
            self.state = (self.state | switch_on) & ~switch_off
            if t >= t_cmd + max(self.on_delay, self.off_delay) - 1e-9:
                self.pending.popleft()
            else:
                break
        self._paint(travelled, x, y, heading)
        return self.state.copy()

    def _paint(self, travelled: float, x: float, y: float, heading: float) -> None:
        """Mark the ground the sections that are on swept since the last step."""
        if self.last is not None and self.state.any():
            t0, x0, y0, h0 = self.last
            paint_strip(self.map, np.array([x0, x]), np.array([y0, y]), np.array([h0, heading]),
                        np.array([t0, travelled]), self.brush, self.brush_owner, self.state[None, :].repeat(2, 0))
        self.last = (travelled, x, y, heading)


def open_sections(cmap: CoverageMap, x: np.ndarray, y: np.ndarray, heading: np.ndarray, travelled: np.ndarray,
                  offsets: np.ndarray, owner: np.ndarray, layout: SectionLayout, ahead: float = 0.0) -> np.ndarray:
    """(poses, sections): whether each section has workable ground not yet worked (before
    ``travelled - FRESH w``) ``ahead`` m in front of each pose, on its decision points ``offsets``."""
    c, s = np.cos(heading)[:, None], np.sin(heading)[:, None]
    px = x[:, None] + ahead * c - offsets[None, :] * s
    py = y[:, None] + ahead * s + offsets[None, :] * c
    open_ = cmap.open_ground(px, py, travelled[:, None], FRESH * layout.width)
    out = np.zeros((len(x), layout.count), bool)
    for j in range(layout.count):
        out[:, j] = open_[:, owner == j].any(axis=1)
    return out


def paint_strip(cmap: CoverageMap, x: np.ndarray, y: np.ndarray, heading: np.ndarray, travelled: np.ndarray,
                offsets: np.ndarray, owner: np.ndarray, on: np.ndarray) -> None:
    """Paint the ground swept between consecutive poses by the sections on at the first of each
    pair: points every half cell along each step and across each section."""
    if len(x) < 2:
        return
    step = np.hypot(np.diff(x), np.diff(y))
    along = max(1, int(math.ceil(float(step.max()) / (0.5 * cmap.cell))))
    f = np.arange(along) / along                                       # shares of each step
    hx = x[:-1, None] + f * np.diff(x)[:, None]
    hy = y[:-1, None] + f * np.diff(y)[:, None]
    hh = heading[:-1, None] + f * (np.angle(np.exp(1j * np.diff(heading))))[:, None]
    hs = travelled[:-1, None] + f * np.diff(travelled)[:, None]
    mask = on[:-1][:, owner]                                           # (steps, points across)
    k, j = np.nonzero(mask)
    if not len(k):
        return
    px = hx[k] - offsets[j, None] * np.sin(hh[k])
    py = hy[k] + offsets[j, None] * np.cos(hh[k])
    cmap.paint(px.ravel(), py.ravel(), hs[k].ravel())
