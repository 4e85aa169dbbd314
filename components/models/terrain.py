"""The ground under a vehicle: a height field z(x, y) over the mission's east/north plane, and
what it does to a body standing on it.

Ground models:

- ``Plane(slope_angle, downhill_heading)``: a tilted plane (a constant side slope is a plane
  whose fall line crosses the swaths), gradient grad z = -tan(phi) (cos psi_d, sin psi_d);
- ``HeightGrid``: heights on a regular east/north grid (CSV columns x, y, z in metres),
  bilinear between the nodes, the gradient by central differences of that surface.

A body (tractor, implement) whose forward axis points at horizontal heading psi rests on the
tangent plane. With the rise per metre forward s_f = grad z . (cos psi, sin psi) and to the
left s_l = grad z . (-sin psi, cos psi):

    pitch = atan(s_f)                       (positive: nose up)
    roll  = atan(s_l cos(pitch))            (positive: left side up, the body leans right)

and its attitude is R = Rz(psi) Ry(-pitch) Rx(roll) (east/north/up world, forward/left/up body;
tests: equal to the rotation whose axes are the surface's tangent and normal). A point at
(forward, left, up) in the body sits at R (forward, left, up) from the body's ground point: an
antenna h above the ground moves h sin(roll) downhill on a side slope. Gravity pulls a body on
the slope along the fall line with g sin(phi) = g |grad z| / sqrt(1 + |grad z|^2).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.interpolate import RegularGridInterpolator

GRAVITY = 9.81


@dataclass(frozen=True)
class Plane:
    """A tilted plane through the origin: slope angle phi, fall line (downhill) at azimuth psi_d
    (from east, counter-clockwise)."""

    slope_angle: float = 0.0
    downhill_heading: float = 0.0

    def gradient(self, x: float, y: float) -> tuple[float, float]:
        t = -math.tan(self.slope_angle)
        return t * math.cos(self.downhill_heading), t * math.sin(self.downhill_heading)

    def height(self, x: float, y: float) -> float:
        gx, gy = self.gradient(x, y)
        return gx * x + gy * y


class HeightGrid:
    """Heights on a regular grid (x ascending, y ascending), bilinear in between; outside the
    grid the edge values hold (flat beyond the edge)."""

    def __init__(self, xs: np.ndarray, ys: np.ndarray, z: np.ndarray, where: str = "height grid") -> None:
        try:
            xs, ys, z = np.asarray(xs, float), np.asarray(ys, float), np.asarray(z, float)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"{where}: a coordinate or a height is not a number ({exc})") from None
        if len(xs) < 2 or len(ys) < 2 or z.shape != (len(xs), len(ys)):
            raise ValueError(f"{where}: expected at least a 2 x 2 grid of heights, got {z.shape}")
        if not (np.all(np.diff(xs) > 0) and np.all(np.diff(ys) > 0)):
            raise ValueError(f"{where}: the grid's x and y must each be strictly increasing")
        if not np.all(np.isfinite(z)):
            raise ValueError(f"{where}: a height is missing or not a number")
        self.where = where
        self._z = RegularGridInterpolator((xs, ys), z, method="linear", bounds_error=False, fill_value=None)
        self._lo, self._hi = np.array([xs[0], ys[0]]), np.array([xs[-1], ys[-1]])
        self._h = 0.25 * min(np.min(np.diff(xs)), np.min(np.diff(ys)))

    @classmethod
    def read_csv(cls, path: str | Path) -> "HeightGrid":
        """A CSV with columns x, y, z (metres, the mission frame), one row per node of a full grid."""
        where = str(path)
        try:
            table = pd.read_csv(path)
        except (OSError, ValueError) as exc:
            raise ValueError(f"{where}: cannot read the height grid: {exc}") from None
        missing = [c for c in ("x", "y", "z") if c not in table.columns]
        if missing:
            raise ValueError(f"{where}: column(s) {missing} missing; expected x, y, z (metres)")
        try:
            grid = table.pivot(index="x", columns="y", values="z").sort_index().sort_index(axis=1)
        except ValueError as exc:
            raise ValueError(f"{where}: a node (x, y) appears twice: {exc}") from None
        return cls(grid.index.to_numpy(), grid.columns.to_numpy(), grid.to_numpy(), where)

    def height(self, x: float, y: float) -> float:
        p = np.clip([x, y], self._lo, self._hi)
        return float(self._z(p[None, :])[0])

    def gradient(self, x: float, y: float) -> tuple[float, float]:
        h = self._h
        p = np.clip([x, y], self._lo, self._hi)
        pts = np.array([[p[0] + h, p[1]], [p[0] - h, p[1]], [p[0], p[1] + h], [p[0], p[1] - h]])
        pts = np.clip(pts, self._lo, self._hi)
        z = self._z(pts)
        dx, dy = pts[0, 0] - pts[1, 0], pts[2, 1] - pts[3, 1]
        return (float((z[0] - z[1]) / dx) if dx > 0 else 0.0, float((z[2] - z[3]) / dy) if dy > 0 else 0.0)


def ground_of(slope_angle: float, downhill_heading: float, height_file: str = ""):
    """The ground a study describes: the height grid when a file is named, else the plane."""
    if height_file:
        return HeightGrid.read_csv(height_file)
    return Plane(float(slope_angle), float(downhill_heading))


def attitude(gx: float, gy: float, heading: float) -> tuple[float, float]:
    """(roll, pitch) of a body at horizontal ``heading`` on ground of gradient (gx, gy)."""
    c, s = math.cos(heading), math.sin(heading)
    pitch = math.atan(gx * c + gy * s)
    roll = math.atan((-gx * s + gy * c) * math.cos(pitch))
    return roll, pitch


def rotation(roll: float, pitch: float, heading: float) -> np.ndarray:
    """R = Rz(heading) Ry(-pitch) Rx(roll): body (forward, left, up) -> world (east, north, up)."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    ch, sh = math.cos(heading), math.sin(heading)
    return np.array([[ch * cp, -sh * cr - ch * sp * sr, sh * sr - ch * sp * cr],
                     [sh * cp, ch * cr - sh * sp * sr, -ch * sr - sh * sp * cr],
                     [sp, cp * sr, cp * cr]])


def lever_offset(roll: float, pitch: float, heading: float, forward: float, left: float, up: float) -> tuple[float, float]:
    """Horizontal (east, north) offset of the body point (forward, left, up) from the body's origin."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    ch, sh = math.cos(heading), math.sin(heading)
    # the first two rows of rotation(roll, pitch, heading) times (forward, left, up), written out
    a = forward * cp - left * sp * sr - up * sp * cr          # along the heading
    b = left * cr - up * sr                                   # to the left of it
    return ch * a - sh * b, sh * a + ch * b


def body_of(roll: float, pitch: float, heading: float, east: float, north: float, up: float) -> tuple[float, float, float]:
    """R^T (east, north, up): a world vector in the body's (forward, left, up) (rotation's transpose, written out)."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    ch, sh = math.cos(heading), math.sin(heading)
    a, b = ch * east + sh * north, -sh * east + ch * north         # along and across the heading, level
    return cp * a + sp * up, cr * b + sr * (-sp * a + cp * up), -sr * b + cr * (-sp * a + cp * up)


def slope_pull(gx: float, gy: float) -> tuple[float, float]:
    """In-plane gravity on ground of gradient (gx, gy): g sin(phi) along the fall line (downhill)."""
    k = -GRAVITY / math.sqrt(1.0 + gx * gx + gy * gy)
    return k * gx, k * gy


def gradient_of_pull(pull_east: float, pull_north: float) -> tuple[float, float]:
    """The gradient whose slope_pull is (pull_east, pull_north) (a plane known by its pull)."""
    n2 = min(pull_east ** 2 + pull_north ** 2, (GRAVITY * 0.999) ** 2)
    k = -1.0 / math.sqrt(GRAVITY ** 2 - n2)
    return k * pull_east, k * pull_north
