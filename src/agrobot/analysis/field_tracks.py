"""The trajectories of a field mission in the plan's geometry: the run's samples (tractor CG and
implement working point) in the mission frame or the field's east/north frame, the swath lines'
frames, cross-track errors to them, the implement's swept strips and pass-to-pass gaps.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
from shapely.geometry import LineString, Polygon

from agrobot.components.field_route import planned, route_frame, section_mask, settings_of, to_mission
from agrobot.fields.planner import SWATH
from agrobot.fields.planner.applied import block_strips
from agrobot.fields.planner.sections import SectionLayout
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study

from .signal_roles import component_named, signal
STEP = 0.1          # s: the geometry's sampling of the trajectories


def mission(study: Study):
    """(field, plan, to_mission) of the study's route component (planned as the run planned it)."""
    name = component_named(study, "route")
    p = resolve(study).parameters(name)
    field, plan = planned(str(p["path"]), str(p["crs"]), str(p["name"]), settings_of(p))
    origin, rotation = route_frame(plan.path)
    return field, plan, lambda xy: to_mission(xy, origin, rotation), name


def _shape(geom, conv):
    return Polygon(conv(np.asarray(geom.exterior.coords)), [conv(np.asarray(h.coords)) for h in geom.interiors])


def _samples(frame: pd.DataFrame, study: Study) -> pd.DataFrame:
    t = frame["t"].to_numpy()
    h = float(np.median(np.diff(t))) if len(t) > 1 else STEP
    every = max(1, int(round(STEP / h)))
    f = frame.iloc[::every].reset_index(drop=True)
    route = component_named(study, "route")
    out = pd.DataFrame({
        "t": f["t"], "x": signal(f, study, "yaw_plant", "x_cg"), "y": signal(f, study, "yaw_plant", "y_cg"),
        "ix": signal(f, study, "implement", "x"), "iy": signal(f, study, "implement", "y"),
        "ih": signal(f, study, "implement", "heading"),
        "segment": f[f"{route}.segment"], "swath": f[f"{route}.swath"], "impl_segment": f[f"{route}.implement_segment"],
        "working": f[f"{route}.working"], "speed": signal(f, study, "drivetrain", "speed"),
        "progress": f[f"{route}.progress"]})
    for k in (0, 1):
        column = f"{route}.section_mask_{k}"
        out[f"mask{k}"] = f[column].to_numpy() if column in f else 0.0
    return out


def field_frame(plan) -> tuple[list[float], float]:
    """(the affine map from the mission frame back to the field's east/north frame, as shapely's
    ``affine_transform`` takes it: p_field = R(rotation) p_mission + origin, the inverse of
    components.field_route.to_mission; the rotation [rad])."""
    origin, rotation = route_frame(plan.path)
    c, sn = math.cos(rotation), math.sin(rotation)
    return [c, -sn, sn, c, float(origin[0]), float(origin[1])], rotation


def _in_field_frame(s: pd.DataFrame, plan) -> pd.DataFrame:
    """The samples' positions and headings from the mission frame back to the field's east/north frame
    (field_frame)."""
    (a11, a12, a21, a22, ox, oy), rotation = field_frame(plan)
    out = s.copy()
    for a, b in (("x", "y"), ("ix", "iy")):
        mx, my = s[a].to_numpy(), s[b].to_numpy()
        out[a], out[b] = ox + a11 * mx + a12 * my, oy + a21 * mx + a22 * my
    if "ih" in s:
        out["ih"] = s["ih"].to_numpy() + rotation
    return out


def _swath_frames(plan, conv) -> dict[int, np.ndarray]:
    """Swath line -> its polyline (N >= 2, 2) in the mission frame (two points for a straight swath):
    where the implement works (on a curve the tractor drives outside it: fields.planner.curved_swaths).
    The swaths of a line that crosses a hole or a bay are parts of one line (one offset of a curve):
    they are joined, turned the same way, in their order along it."""
    parts: dict[int, list[np.ndarray]] = {}
    for sw in [*plan.swaths, *plan.leftover_passes]:           # the leftovers' own passes: lines of their own
        parts.setdefault(int(sw.line), []).append(np.asarray(conv(sw.points[:, :2]), float))
    out = {}
    for line, pieces in parts.items():
        d = pieces[0][-1] - pieces[0][0]
        pieces = [p if (p[-1] - p[0]) @ d >= 0 else p[::-1] for p in pieces]
        out[line] = np.vstack(sorted(pieces, key=lambda p: float(p.mean(axis=0) @ d)))
    return out


def station(line: np.ndarray, px: np.ndarray, py: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(along, across: left positive) of points relative to a polyline: the foot of the
    perpendicular on its nearest segment, the first and last segments extended beyond the ends
    (so that a straight swath is its infinite line: along = (p - a).d, across = d x (p - a))."""
    a, b = line[:-1], line[1:]
    seg = np.maximum(np.hypot(*(b - a).T), 1e-12)
    d = (b - a) / seg[:, None]
    wx, wy = px[:, None] - a[:, 0], py[:, None] - a[:, 1]
    t = wx * d[:, 0] + wy * d[:, 1]
    lo = np.where(np.arange(len(seg)) == 0, -np.inf, 0.0)
    hi = np.where(np.arange(len(seg)) == len(seg) - 1, np.inf, seg)
    t = np.clip(t, lo, hi)
    ex, ey = wx - t * d[:, 0], wy - t * d[:, 1]
    i = np.argmin(ex * ex + ey * ey, axis=1)
    r = np.arange(len(px))
    s_at = np.concatenate([[0.0], np.cumsum(seg)])
    across = d[i, 0] * wy[r, i] - d[i, 1] * wx[r, i]
    return s_at[i] + t[r, i], across


def _cross_track(px, py, swath, frames):
    """Signed distance (left positive) of each point to its swath's polyline; NaN off swaths."""
    out = np.full(len(px), np.nan)
    for k, line in frames.items():
        m = swath == k
        if m.any():
            out[m] = station(line, px[m], py[m])[1]
    return out


def _stats(e: np.ndarray) -> tuple[float, float, float]:
    e = np.abs(e[np.isfinite(e)])
    if not len(e):
        return math.nan, math.nan, math.nan
    return float(np.sqrt(np.mean(e ** 2))), float(np.percentile(e, 95)), float(e.max())


def _thinned(xy: np.ndarray, spacing: float = 0.05) -> np.ndarray:
    """The points of a track at least ``spacing`` from the last one kept (and its last point): a
    standing implement's jitter would otherwise make a line GEOS cannot buffer in memory."""
    keep, last = [0], xy[0]
    for i in range(1, len(xy)):
        if abs(xy[i, 0] - last[0]) + abs(xy[i, 1] - last[1]) >= spacing:
            keep.append(i)
            last = xy[i]
    if keep[-1] != len(xy) - 1:
        keep.append(len(xy) - 1)
    return xy[keep]


def _strips(s: pd.DataFrame, width: float):
    """The implement's swept strips: one per run of working samples."""
    work = s["working"].to_numpy() > 0.5
    edges = np.diff(np.concatenate([[0], work.astype(int), [0]]))
    strips = []
    for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
        xy = _thinned(np.column_stack([s["ix"].to_numpy()[a:b], s["iy"].to_numpy()[a:b]]))
        if len(xy) >= 2:
            line = LineString(xy)
            strips.append(line.buffer(0.5 * width, cap_style="flat", join_style="round"))
    return strips


def applied_strips(s: pd.DataFrame, width: float, sections: int) -> list:
    """What the implement applied: the whole width while working (``sections`` 0), else each
    section's strips where the route's section control had it on (fields.planner.applied's strips
    of a run of poses), about the implement's true working point and heading."""
    if not sections:
        return _strips(s, width)
    on = section_mask(s["mask0"].to_numpy(), s["mask1"].to_numpy(), sections)
    return block_strips(s["ix"].to_numpy(), s["iy"].to_numpy(), s["ih"].to_numpy(), on, SectionLayout(width, sections))


def sections_of(study: Study) -> int:
    """The route component's section count (0: no section control)."""
    p = resolve(study).parameters(component_named(study, "route"))
    return int(p.get("sections", 0) or 0)


IMPLEMENT, TRACTOR = ("ix", "iy", "impl_segment"), ("x", "y", "segment")     # a track's columns in _samples


def _track(s: pd.DataFrame, j: int, frame, point=IMPLEMENT) -> tuple[np.ndarray, np.ndarray] | None:
    """The implement's (or the tractor's) track on swath j as (along, across) the swath polyline
    ``frame``, sorted along; None with fewer than 10 samples."""
    px, py, segment = point
    m = (s[segment].to_numpy() == SWATH) & (s["swath"].to_numpy() == j)
    if m.sum() < 10:
        return None
    along, across = station(frame, s[px].to_numpy()[m], s[py].to_numpy()[m])
    order = np.argsort(along)
    return along[order], across[order]


def _gap(one, other) -> np.ndarray:
    """other's across minus one's, 1 m apart along their common part (interpolated on both), where
    both tracks have samples less than 1 m apart either side (not across a hole or bay that splits a
    line into swaths)."""
    if one is None or other is None:
        return np.zeros(0)
    lo, hi = max(one[0][0], other[0][0]), min(one[0][-1], other[0][-1])
    if hi - lo < 2.0:
        return np.zeros(0)
    grid = np.arange(lo, hi, 1.0)
    covered = np.ones(len(grid), bool)
    for along, _ in (one, other):
        i = np.clip(np.searchsorted(along, grid, side="right"), 1, len(along) - 1)
        covered &= along[i] - along[i - 1] <= 1.0
    grid = grid[covered]
    return np.interp(grid, *other) - np.interp(grid, *one)


def _pass_to_pass(s: pd.DataFrame, frames, spacing: float, point=IMPLEMENT) -> np.ndarray:
    """Spacing errors between adjacent implement (or tractor) passes (line k and k + 1), 1 m apart
    along them."""
    errors = []
    for k in sorted(frames):
        if k + 1 in frames:
            gap = _gap(_track(s, k, frames[k], point), _track(s, k + 1, frames[k], point))
            if len(gap):
                errors.append(np.abs(gap) - spacing)
    return np.concatenate(errors) if errors else np.zeros(0)


def repeatability(first: tuple[pd.DataFrame, Study], second: tuple[pd.DataFrame, Study], swath: int) -> np.ndarray:
    """The same line driven twice (two runs: another day, another realisation of every sensor's
    errors): the implement's across-track difference between the two tracks of ``swath``, 1 m apart
    along their common part."""
    tracks = []
    for frame, study in (first, second):
        _, plan, conv, _ = mission(study)
        frames = _swath_frames(plan, conv)
        tracks.append(_track(_samples(frame, study), swath, frames[swath]) if swath in frames else None)
    return _gap(*tracks)
