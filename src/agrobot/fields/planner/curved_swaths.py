"""Swaths parallel to a curved guidance line: offset curves of the line at k x spacing (shapely's
``offset_curve``, GEOS), the line's ends first extended along their tangents so that the offsets
reach across the whole piece. An offset d to the concave side of an arc of radius r has radius
r - d: where that falls under the turn radius R (kappa > 1/R), or the offset folds into a cusp or a
loop, the swath is cut there (the parts either side kept, each with kappa <= 1/R). Each swath is
clipped to where its strip (width w) touches the piece, as the straight swaths are."""
from __future__ import annotations

import math

import numpy as np
import shapely
from scipy.interpolate import splev, splprep
from shapely.geometry import LineString, MultiLineString, Point, Polygon

from .decomposition import Along
from .types import Swath

STEP = 0.5          # m: the offsets are resampled this finely before their curvature is judged
SHORTEST = 1.0      # m: a shorter piece is not a swath


def smoothed(line: np.ndarray, step: float = STEP) -> np.ndarray:
    """The guidance line as an interpolating cubic spline through its vertices (chord-length
    parameter; scipy's splprep), sampled every ``step``: a recorded curve's vertices a few metres
    apart would give its offsets a kink at each vertex, the spline a continuous curvature."""
    p = np.asarray(line, float)
    keep = np.concatenate([[True], np.hypot(*np.diff(p, axis=0).T) > 1e-6])
    p = p[keep]
    if len(p) < 4:
        return p
    u = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))])
    tck, _ = splprep(p.T, u=u, s=0.0, k=3)
    return np.column_stack(splev(np.linspace(0.0, u[-1], max(int(math.ceil(u[-1] / step)), 2) + 1), tck))


def extended(line: np.ndarray, reach: float) -> LineString:
    """The polyline lengthened at both ends along its end tangents by ``reach``."""
    p = np.asarray(line, float)
    d0 = (p[0] - p[1]) / max(np.hypot(*(p[0] - p[1])), 1e-12)
    d1 = (p[-1] - p[-2]) / max(np.hypot(*(p[-1] - p[-2])), 1e-12)
    return LineString(np.vstack([p[0] + reach * d0, p, p[-1] + reach * d1]))


def resampled(g: LineString, step: float = STEP) -> np.ndarray:
    n = max(int(math.ceil(g.length / step)), 1)
    return shapely.get_coordinates(shapely.line_interpolate_point(g, np.linspace(0.0, g.length, n + 1)))


def curvature(p: np.ndarray) -> np.ndarray:
    """Discrete curvature at the interior points of a polyline: the turning angle over the mean of
    the two segment lengths (the circle through three points, to first order)."""
    d = np.diff(p, axis=0)
    h = np.arctan2(d[:, 1], d[:, 0])
    turn = np.angle(np.exp(1j * np.diff(h)))
    seg = np.hypot(*d.T)
    return np.abs(turn) / np.maximum(0.5 * (seg[:-1] + seg[1:]), 1e-12)


def smooth_parts(g: LineString, kappa_max: float) -> list[np.ndarray]:
    """The parts of a curve with curvature <= ``kappa_max`` (cut where it is above, i.e. at cusps
    and tight bends; a loop closes with a cusp, so it is cut apart and its short pieces dropped)."""
    if g.is_empty or g.length < SHORTEST:
        return []
    p = resampled(g)
    if len(p) < 3:
        return [p]
    bad = np.flatnonzero(curvature(p) > kappa_max) + 1        # interior point indices
    cuts = np.concatenate([[0], bad, [len(p) - 1]])
    parts = []
    for a, b in zip(cuts[:-1], cuts[1:]):
        a, b = (a + 1 if a in bad else a), (b - 1 if b in bad else b)
        if b - a >= 1 and np.sum(np.hypot(*np.diff(p[a:b + 1], axis=0).T)) >= SHORTEST:
            parts.append(p[a:b + 1])
    return parts


def curved_lines(region: Polygon, guide: np.ndarray, spacing: float, width: float, turn_radius: float,
                 first_index: int = 0, first_line: int = 0) -> tuple[list[list[Swath]], Along]:
    """Per offset of the guidance line across the region (in order across it), its swaths; and the
    coordinate along them (the distance along the extended guidance line of a point's projection)."""
    minx, miny, maxx, maxy = region.bounds
    reach = 2.0 * math.hypot(maxx - minx, maxy - miny) + 2.0 * width
    base = extended(smoothed(guide), reach)
    # the farthest point of the region from the line may lie inside it (towards a curve's centre):
    # the region's diagonal bounds every distance
    count = int(math.ceil((math.hypot(maxx - minx, maxy - miny) + base.distance(region) + width) / spacing))
    near = region.buffer(0.5 * width, join_style="mitre", mitre_limit=3.0)
    out: list[list[Swath]] = []
    number = first_index
    for k in range(-count, count + 1):
        off = base if k == 0 else base.offset_curve(k * spacing, join_style="round")
        if off.is_empty or not off.intersects(near):
            continue
        found = []
        for g in (off.geoms if isinstance(off, MultiLineString) else [off]):
            for part in smooth_parts(g, 1.0 / turn_radius):
                cut = near.intersection(LineString(part))
                found += [c for c in (cut.geoms if hasattr(cut, "geoms") else [cut])
                          if isinstance(c, LineString) and c.length >= SHORTEST]
        if not found:
            continue
        found.sort(key=lambda c: base.project(Point(c.coords[0])))
        swaths = []
        for c in found:
            pts = np.asarray(c.coords)
            if base.project(Point(pts[0])) > base.project(Point(pts[-1])):
                pts = pts[::-1]
            swaths.append(Swath(number, first_line + len(out), pts))
            number += 1
        out.append(swaths)
    return out, lambda p: float(base.project(Point(np.asarray(p)[:2])))


def tractor_line(points: np.ndarray, hitch_offset: float, drawbar: float, ramp: float) -> np.ndarray:
    """Where the rear axle drives so that a trailed implement runs on a curved swath: in a steady
    turn the implement axle (drawbar L behind a hitch c behind the rear axle) runs on
    r_i^2 = r^2 + c^2 - L^2, so the axle is put on r = sqrt(r_i^2 - c^2 + L^2), outside the swath
    by r - r_i (zero on a straight swath). The shift grows from zero over ``ramp`` metres at each end
    (the path joins its straight run-in and run-out)."""
    p = np.asarray(points, float)
    if len(p) < 3:
        return p
    kappa = signed_curvature(p)
    r_i = 1.0 / np.maximum(np.abs(kappa), 1e-9)
    shift = np.sqrt(np.maximum(r_i ** 2 - hitch_offset ** 2 + drawbar ** 2, 0.0)) - r_i
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))])
    shift *= np.clip(np.minimum(s, s[-1] - s) / max(ramp, 1e-9), 0.0, 1.0)
    t = np.gradient(p, s, axis=0)
    t /= np.maximum(np.hypot(*t.T), 1e-12)[:, None]
    left = np.column_stack([-t[:, 1], t[:, 0]])
    return p - (np.sign(kappa) * shift)[:, None] * left


def signed_curvature(p: np.ndarray, base: float = 2.0) -> np.ndarray:
    """Curvature (left positive) at every point of a polyline: the heading change over about
    ``base`` metres either side, over the arc length between (a smooth estimate)."""
    d = np.diff(p, axis=0)
    h = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*d.T))])
    mid = 0.5 * (s[:-1] + s[1:])
    lo = np.interp(np.clip(s - base, mid[0], mid[-1]), mid, h)
    hi = np.interp(np.clip(s + base, mid[0], mid[-1]), mid, h)
    span = np.clip(s + base, mid[0], mid[-1]) - np.clip(s - base, mid[0], mid[-1])
    return np.where(span > 1e-9, (hi - lo) / np.maximum(span, 1e-9), 0.0)
