"""Farmers' and autosteer vendors' figures of a field mission, from the true positions
(the plant's CG, the implement's working point), not the estimates:

- cross-track error on swaths (RMS, P95, max) of the tractor's CG and of the implement, against
  the swath line (straight, from the plan);
- pass-to-pass error: adjacent implement passes, their spacing minus the planned one, along the
  common part (P95 of its magnitude, as autosteer vendors quote it);
- coverage: the implement's swept strips (its working width about its working point, while it
  works: on a swath or a headland pass) united with shapely, against the workable area (the field
  the implement can reach: fields.planner.headland); covered, overlapping (worked more than once) and
  skipped area, and their shares;
- boundary crossings: the tractor's CG or the implement leaving the field (must be 0);
- time and distance on swaths, headland passes and in turns;
- real ground (ground_metrics): the tractor's cross-track error to the whole route by
  interpolation (its projection on the route's segments, not the nearest route point), line
  acquisition after each turn, the cross-track error and the estimator's drift in GNSS outages
  (the samples whose fix is not RTK fixed), the watchdog's stops, and the time between adjacent
  passes (pass-to-pass is quoted at an interval: ISO 12188-2 takes 15 min).

Plots: the field coloured by coverage count, the track coloured by cross-track error, and the
error histograms.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from fields.planner import HEADLAND, SWATH, TRANSIT, TURN
from orchestrator.resolver import resolve
from orchestrator.study import Study

from .signals import component_named, runs, signal

STEP = 0.1          # s: the geometry's sampling of the trajectories


def mission(study: Study):
    """(field, plan, to_mission) of the study's route component (planned as the run planned it)."""
    from components.field_route import planned, route_frame, settings_of, to_mission

    name = component_named(study, "route")
    p = resolve(study).parameters(name)
    field, plan = planned(str(p["path"]), str(p["crs"]), str(p["name"]), settings_of(p))
    origin, rotation = route_frame(plan.path)
    return field, plan, lambda xy: to_mission(xy, origin, rotation), name


def _shape(geom, conv):
    from shapely.geometry import Polygon

    return Polygon(conv(np.asarray(geom.exterior.coords)), [conv(np.asarray(h.coords)) for h in geom.interiors])


def _samples(frame: pd.DataFrame, study: Study) -> pd.DataFrame:
    t = frame["t"].to_numpy()
    h = float(np.median(np.diff(t))) if len(t) > 1 else STEP
    every = max(1, int(round(STEP / h)))
    f = frame.iloc[::every].reset_index(drop=True)
    route = component_named(study, "route")
    return pd.DataFrame({
        "t": f["t"], "x": signal(f, study, "yaw_plant", "x_cg"), "y": signal(f, study, "yaw_plant", "y_cg"),
        "ix": signal(f, study, "implement", "x"), "iy": signal(f, study, "implement", "y"),
        "segment": f[f"{route}.segment"], "swath": f[f"{route}.swath"], "impl_segment": f[f"{route}.implement_segment"],
        "working": f[f"{route}.working"], "speed": signal(f, study, "drivetrain", "speed"),
        "progress": f[f"{route}.progress"]})


def _in_field_frame(s: pd.DataFrame, plan) -> pd.DataFrame:
    """The samples' positions from the mission frame back to the field's east/north frame:
    p_field = R(rotation) p_mission + origin (the inverse of components.field_route.to_mission)."""
    from components.field_route import route_frame

    origin, rotation = route_frame(plan.path)
    c, sn = math.cos(rotation), math.sin(rotation)
    out = s.copy()
    for a, b in (("x", "y"), ("ix", "iy")):
        mx, my = s[a].to_numpy(), s[b].to_numpy()
        out[a], out[b] = origin[0] + c * mx - sn * my, origin[1] + sn * mx + c * my
    return out


def _swath_frames(plan, conv) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Swath index -> (start, unit direction) in the mission frame."""
    out = {}
    for seg in (s for s in plan.path.segments if s.kind == SWATH):
        a2, b2 = conv(seg.points[[0, -1], :2])
        d = (b2 - a2) / max(np.hypot(*(b2 - a2)), 1e-9)
        out[int(seg.index)] = (a2, d)
    return out


def _cross_track(px, py, swath, frames):
    """Signed distance (left positive) of each point to its swath's line; NaN off swaths."""
    out = np.full(len(px), np.nan)
    for k, (a, d) in frames.items():
        m = swath == k
        if m.any():
            out[m] = -d[1] * (px[m] - a[0]) + d[0] * (py[m] - a[1])
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
    from shapely.geometry import LineString

    work = s["working"].to_numpy() > 0.5
    edges = np.diff(np.concatenate([[0], work.astype(int), [0]]))
    strips = []
    for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
        xy = _thinned(np.column_stack([s["ix"].to_numpy()[a:b], s["iy"].to_numpy()[a:b]]))
        if len(xy) >= 2:
            line = LineString(xy)
            strips.append(line.buffer(0.5 * width, cap_style="flat", join_style="round"))
    return strips


IMPLEMENT, TRACTOR = ("ix", "iy", "impl_segment"), ("x", "y", "segment")     # a track's columns in _samples


def _track(s: pd.DataFrame, j: int, frame, point=IMPLEMENT) -> tuple[np.ndarray, np.ndarray] | None:
    """The implement's (or the tractor's) track on swath j as (along, across) in ``frame`` (start,
    direction), sorted along; None with fewer than 10 samples."""
    a, d = frame
    px, py, segment = point
    m = (s[segment].to_numpy() == SWATH) & (s["swath"].to_numpy() == j)
    if m.sum() < 10:
        return None
    rel = np.column_stack([s[px].to_numpy()[m] - a[0], s[py].to_numpy()[m] - a[1]])
    along, across = rel @ d, rel @ np.array([-d[1], d[0]])
    order = np.argsort(along)
    return along[order], across[order]


def _gap(one, other) -> np.ndarray:
    """other's across minus one's, 1 m apart along their common part (interpolated on both)."""
    if one is None or other is None:
        return np.zeros(0)
    lo, hi = max(one[0][0], other[0][0]), min(one[0][-1], other[0][-1])
    if hi - lo < 2.0:
        return np.zeros(0)
    grid = np.arange(lo, hi, 1.0)
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


def metrics(frame: pd.DataFrame, study: Study) -> dict[str, float]:
    from shapely import contains_xy
    from shapely.ops import unary_union

    field, plan, conv, _ = mission(study)
    settings = plan.settings
    s = _samples(frame, study)
    frames = _swath_frames(plan, conv)
    swath = s["swath"].to_numpy().astype(int)
    seg, iseg = s["segment"].to_numpy(), s["impl_segment"].to_numpy()
    xte_t = _cross_track(s["x"].to_numpy(), s["y"].to_numpy(), np.where(seg == SWATH, swath, -99), frames)
    xte_i = _cross_track(s["ix"].to_numpy(), s["iy"].to_numpy(), np.where(iseg == SWATH, swath, -99), frames)
    boundary = _shape(field.boundary, conv)
    workable = _shape(plan.workable, conv)
    strips = _strips(s, settings.working_width)
    union = unary_union(strips) if strips else None
    covered = union.intersection(workable).area if union is not None else 0.0
    swept = sum(st.intersection(workable).area for st in strips)
    overlap = max(swept - covered, 0.0)
    crossings = 0
    for xs, ys in ((s["x"], s["y"]), (s["ix"], s["iy"])):
        inside = contains_xy(boundary, xs.to_numpy(), ys.to_numpy())
        crossings += int(np.sum(inside[:-1] & ~inside[1:]))
    p2p = _pass_to_pass(s, frames, settings.working_width - settings.overlap)
    dt = np.diff(s["t"].to_numpy(), append=s["t"].iloc[-1])
    dist = s["speed"].to_numpy() * dt
    out: dict[str, float] = {}
    for name, e in (("tractor", xte_t), ("implement", xte_i)):
        rms, p95, mx = _stats(e)
        out.update({f"{name}_xte_rms_m": rms, f"{name}_xte_p95_m": p95, f"{name}_xte_max_m": mx})
    out["pass_to_pass_p95_m"] = float(np.percentile(np.abs(p2p), 95)) if len(p2p) else math.nan
    out["pass_to_pass_mean_m"] = float(np.mean(p2p)) if len(p2p) else math.nan
    area = workable.area
    field_covered = union.intersection(boundary).area if union is not None else 0.0
    out.update(field_coverage_share=field_covered / boundary.area, coverage_share=covered / area,
               overlap_share=overlap / area, skipped_area_m2=area - covered,
               covered_area_m2=covered, overlap_area_m2=overlap, workable_area_m2=area,
               field_area_m2=boundary.area, boundary_crossings=float(crossings))
    for kind, name in ((SWATH, "swath"), (HEADLAND, "headland"), (TURN, "turn"), (TRANSIT, "transit")):
        m = seg == kind
        out[f"{name}_time_s"] = float(dt[m].sum())
        out[f"{name}_distance_m"] = float(dist[m].sum())
    out["mission_time_s"] = float(s["t"].iloc[-1] - s["t"].iloc[0])
    out["route_done_share"] = float(s["progress"].max())
    out["swaths_planned"] = float(len(plan.swaths))
    out.update(ground_metrics(frame, study, s, plan, conv, frames))
    return out


# --- real ground: route cross-track by interpolation, line acquisition, GNSS outages ------------------------
ACQUIRED = 0.05         # m: |XTE| under which a line counts as acquired
ACQUIRED_HOLD = 2.0     # s: ... and stays so this long (or to the swath's end)


def route_cross_track(px: np.ndarray, py: np.ndarray, rx: np.ndarray, ry: np.ndarray, back: float = 2.0,
                      ahead: float = 10.0) -> tuple[np.ndarray, np.ndarray]:
    """(signed distance, left positive; arc length) of each point of a track to a route polyline:
    the foot of the perpendicular on the nearest segment (interpolation, not the nearest route
    point), searched from the previous point's segment back ``back`` and ahead ``ahead`` metres,
    so that a turn crossing a swath does not capture the track."""
    dx, dy = np.diff(rx), np.diff(ry)
    seg = np.hypot(dx, dy)
    seg = np.where(seg > 1e-12, seg, 1e-12)
    s_at = np.concatenate([[0.0], np.cumsum(seg)])
    step = float(np.median(seg)) if len(seg) else 0.1
    nb, na = int(back / step) + 1, int(ahead / step) + 2
    dist, arc = np.full(len(px), np.nan), np.full(len(px), np.nan)
    j = 0
    for k in range(len(px)):
        a, b = max(0, j - nb), min(len(seg), j + na)
        ux, uy = dx[a:b] / seg[a:b], dy[a:b] / seg[a:b]
        wx, wy = px[k] - rx[a:b], py[k] - ry[a:b]
        along = np.clip(wx * ux + wy * uy, 0.0, seg[a:b])
        ex, ey = wx - along * ux, wy - along * uy
        i = int(np.argmin(ex * ex + ey * ey))
        j = a + i
        side = ux[i] * wy[i] - uy[i] * wx[i]
        dist[k] = math.copysign(math.hypot(ex[i], ey[i]), side if side != 0 else 1.0)
        arc[k] = s_at[j] + along[i]
    return dist, arc


class _RowsAt:
    """The rows of a signal table (a DataFrame or the result's column-wise table) at the sample times
    ``t``, read a column at a time when asked: ``rows[name]`` (a Series), ``name in rows``."""

    def __init__(self, frame, t: np.ndarray) -> None:
        self._frame = frame
        self._idx = np.clip(np.searchsorted(frame["t"].to_numpy(), t - 1e-9), 0, len(frame) - 1)

    def __contains__(self, name: object) -> bool:
        return name in self._frame

    def __getitem__(self, name: str) -> pd.Series:
        return pd.Series(self._frame[name].to_numpy()[self._idx])

    def __len__(self) -> int:
        return len(self._idx)


def _tractor_gps(study: Study) -> str | None:
    """The receiver whose fixes the pose estimator reads (a study may have one on the implement too)."""
    estimator = resolve(study).find(role="pose_estimator")
    if len(estimator) != 1:
        return None
    return next((c.source for c in study.connections if c.target == estimator[0] and c.input == "gps_x"), None)


def route_samples(path, until: float) -> dict[str, np.ndarray]:
    """The route's columns (fields.planner.path.COLUMNS) on the trackers' grid s = k ROUTE_STEP up to
    arc length ``until`` (the part a run drove: memory that of the drive, not of the whole plan)."""
    from fields.planner.sampling import ROUTE_STEP

    stop = min(path.grid_size(ROUTE_STEP), int(math.ceil(max(until, 0.0) / ROUTE_STEP)) + 2)
    return path.grid(0, stop, ROUTE_STEP)


def _acquisitions(s: pd.DataFrame, route: dict[str, np.ndarray], frames,
                  path_length: np.ndarray) -> list[tuple[float, float]]:
    """(distance, time) from the end of each turn (where the route straightens before a swath) until
    the tractor's CG is within ACQUIRED of the swath's line and stays so for ACQUIRED_HOLD (or to the
    swath's end); NaN when it never does. The first swath, entered from rest, is not a turn's.
    ``route``: route_samples of the driven part."""
    kind, index, kappa, arc = route["kind"], route["index"], route["curvature"], route["s"]
    t, x, y = s["t"].to_numpy(), s["x"].to_numpy(), s["y"].to_numpy()
    out = []
    firsts = [int(np.flatnonzero((kind == SWATH) & (index == k))[0]) for k in frames
              if np.any((kind == SWATH) & (index == k))]
    for i_swath in sorted(firsts)[1:]:
        k = int(index[i_swath])
        i = i_swath
        while i > 0 and kind[i - 1] == TURN and abs(kappa[i - 1]) < 1e-3:
            i -= 1
        s_start, s_end = arc[i], arc[min(len(arc) - 1, i_swath + int(np.sum((kind == SWATH) & (index == k))) - 1)]
        on = np.flatnonzero((path_length >= s_start) & (path_length <= s_end))
        if len(on) < 2:
            continue
        a, d = frames[k]
        e = np.abs(-d[1] * (x[on] - a[0]) + d[0] * (y[on] - a[1]))
        inside = e < ACQUIRED
        found = math.nan, math.nan
        for first, last in runs(inside):
            if t[on[last - 1]] - t[on[first]] >= ACQUIRED_HOLD or last == len(on):
                j0, j1 = on[0], on[first]
                along = (x[j1] - x[j0]) * d[0] + (y[j1] - y[j0]) * d[1]
                found = float(along), float(t[j1] - t[j0])
                break
        out.append(found)
    return out


def ground_metrics(frame: pd.DataFrame, study: Study, s: pd.DataFrame, plan, conv, frames) -> dict[str, float]:
    """Route cross-track error by interpolation, line acquisition, GNSS outages, guidance stops and
    the interval between adjacent passes (see the module's docstring)."""
    out: dict[str, float] = {}
    rows = _RowsAt(frame, s["t"].to_numpy())
    name = component_named(study, "route")
    path_length = rows[f"{name}.path_length"].to_numpy()
    route = route_samples(plan.path, float(np.max(path_length, initial=0.0)) + 20.0)
    rxy = conv(np.column_stack([route["x"], route["y"]]))
    x, y = s["x"].to_numpy(), s["y"].to_numpy()
    xte, _ = route_cross_track(x, y, rxy[:, 0], rxy[:, 1])
    rms, p95, mx = _stats(xte)
    out.update(route_xte_rms_m=rms, route_xte_p95_m=p95, route_xte_max_m=mx)
    acq = np.array(_acquisitions(s, route, frames, path_length), float).reshape(-1, 2)
    if len(acq):
        ok = np.isfinite(acq[:, 0])
        out["line_acquisitions"] = float(len(acq))
        out["line_acquisition_failures"] = float(np.sum(~ok))
        out["line_acquisition_p95_m"] = float(np.percentile(acq[ok, 0], 95)) if ok.any() else math.nan
        out["line_acquisition_p95_s"] = float(np.percentile(acq[ok, 1], 95)) if ok.any() else math.nan
        out["line_acquisition_max_m"] = float(np.max(acq[ok, 0])) if ok.any() else math.nan
    # time between adjacent passes: their starts (the implement entering each swath)
    iseg, sw, t = s["impl_segment"].to_numpy(), s["swath"].to_numpy(), s["t"].to_numpy()
    starts = {}
    for k in frames:
        on = np.flatnonzero((iseg == SWATH) & (sw == k))
        if len(on):
            starts[k] = t[on[0]]
    gaps = [abs(starts[k + 1] - starts[k]) for k in starts if k + 1 in starts]
    if gaps:
        out["pass_to_pass_interval_s"] = float(np.median(gaps))
    # ISO 12188-2 takes a point of the vehicle: the tractor's CG passes too
    p2p = _pass_to_pass(s, frames, plan.settings.working_width - plan.settings.overlap, TRACTOR)
    out["tractor_pass_to_pass_p95_m"] = float(np.percentile(np.abs(p2p), 95)) if len(p2p) else math.nan
    out.update(_outage_metrics(rows, study, s, xte))
    return out


def _outage_metrics(rows: _RowsAt, study: Study, s: pd.DataFrame, xte: np.ndarray) -> dict[str, float]:
    """Per stretch without an RTK fix: its length, the true cross-track error at its end and at most,
    the estimate's drift at its end (estimated CG - true CG: horizontal, as receivers quote their
    accuracy, and across the tractor's heading, what guidance feels), and when the watchdog stopped
    the tractor in it."""
    from components.hardware.nmea import RTK_FIXED

    out: dict[str, float] = {}
    gps = _tractor_gps(study)
    if gps is None or f"{gps}.fix_quality" not in rows:
        return out
    quality = rows[f"{gps}.fix_quality"].to_numpy()
    estimator = component_named(study, "pose_estimator")
    ex, ey = rows[f"{estimator}.x_cg"].to_numpy(), rows[f"{estimator}.y_cg"].to_numpy()
    heading = signal(rows, study, "yaw_plant", "heading")
    dx, dy = ex - s["x"].to_numpy(), ey - s["y"].to_numpy()
    drift, across = np.hypot(dx, dy), -np.sin(heading) * dx + np.cos(heading) * dy
    watchdog = resolve(study).find(role="watchdog")
    safe = rows[f"{watchdog[0]}.safe_state"].to_numpy() if len(watchdog) == 1 else np.zeros(len(rows))
    t = s["t"].to_numpy()
    windows = runs(quality != RTK_FIXED)
    out["outages"] = float(len(windows))
    stops = [a for a, _ in runs(safe > 0.5)]
    out["guidance_stops"] = float(len(stops))
    if not windows:
        return out
    in_outage = np.zeros(len(t), bool)
    for k, (a, b) in enumerate(windows, 1):
        in_outage[a:b] = True
        end = b - 1
        out[f"outage_{k}_start_s"] = float(t[a])
        out[f"outage_{k}_duration_s"] = float(t[end] - t[a] + (t[1] - t[0] if len(t) > 1 else 0.0))
        out[f"outage_{k}_quality"] = float(np.max(quality[a:b]))
        out[f"outage_{k}_xte_end_m"] = float(abs(xte[end]))
        out[f"outage_{k}_drift_m"] = float(drift[end])
        out[f"outage_{k}_drift_across_m"] = float(abs(across[end]))
        stopped = np.flatnonzero(safe[a:b] > 0.5)
        out[f"outage_{k}_stopped_after_s"] = float(t[a + stopped[0]] - t[a]) if len(stopped) else math.nan
    out["xte_max_in_outage_m"] = float(np.nanmax(np.abs(xte[in_outage])))
    out["outage_drift_max_m"] = float(max(out[f"outage_{k}_drift_m"] for k in range(1, len(windows) + 1)))
    return out


IMPLEMENT_XTE_P95_TARGET = 0.05       # m: the implement's P95 cross-track target (RTK class +-0.025 m)
COVERAGE_TARGET, OVERLAP_TARGET = 0.99, 0.05       # shares of the workable area: at least, at most
METRICS = {"field_coverage_share": ("1", f">= {COVERAGE_TARGET} (of the whole field)"),
           "coverage_share": ("1", f">= {COVERAGE_TARGET}"), "overlap_share": ("1", f"<= {OVERLAP_TARGET}"),
           "skipped_area_m2": ("m2", None),
           "boundary_crossings": ("count", "0"), "tractor_xte_p95_m": ("m", None),
           "implement_xte_p95_m": ("m", f"<= {IMPLEMENT_XTE_P95_TARGET} (RTK class +-0.025)"), "pass_to_pass_p95_m": ("m", None),
           "tractor_xte_rms_m": ("m", None), "implement_xte_rms_m": ("m", None), "implement_xte_max_m": ("m", None),
           "swath_time_s": ("s", None), "turn_time_s": ("s", None), "headland_time_s": ("s", None),
           "mission_time_s": ("s", None), "wall_time_s": ("s", None),
           "route_xte_p95_m": ("m", None), "line_acquisition_p95_m": ("m", None), "line_acquisition_p95_s": ("s", None),
           "pass_to_pass_interval_s": ("s", None), "tractor_pass_to_pass_p95_m": ("m", None),
           "xte_max_in_outage_m": ("m", None),
           "outage_drift_max_m": ("m", None), "guidance_stops": ("count", None)}
METRIC_UNITS = {**{k: unit for k, (unit, _) in METRICS.items()},
                **{f"{kind}_{q}": unit for kind in ("swath", "headland", "turn", "transit")
                   for q, unit in (("time_s", "s"), ("distance_m", "m"))},
                **{k: "m" for k in ("tractor_xte_max_m", "pass_to_pass_mean_m")},
                **{k: "m2" for k in ("covered_area_m2", "overlap_area_m2", "workable_area_m2", "field_area_m2")},
                "route_done_share": "1", "swaths_planned": "count", "events": "count",
                **{k: "m" for k in ("route_xte_rms_m", "route_xte_max_m", "line_acquisition_max_m")},
                **{k: "count" for k in ("line_acquisitions", "line_acquisition_failures", "outages")}}



# What a sweep plots (orchestrator.sweep.sweep_plots), with the bound each is judged by: the farmer's
# figures (coverage, overlap, accuracy of the implement, time) and the field's limit.
SWEEP_METRICS = {"coverage_share": COVERAGE_TARGET, "overlap_share": OVERLAP_TARGET, "implement_xte_p95_m": IMPLEMENT_XTE_P95_TARGET,
                 "pass_to_pass_p95_m": None, "mission_time_s": None, "boundary_crossings": 0.0}


def summary(values: dict[str, float]) -> str:
    lines = [f"{'metric':<26}{'value':>14}  {'unit':<6} target", "-" * 64]
    for key, (unit, target) in METRICS.items():
        if key in values:
            lines.append(f"{key:<26}{values[key]:>14.4f}  {unit:<6} {target or ''}")
    return "\n".join(lines)


def plots(frame: pd.DataFrame, study: Study, out_dir: Path) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    from orchestrator.results import atomic_write

    field, plan, _, _ = mission(study)
    s = _in_field_frame(_samples(frame, study), plan)        # east/north, the frame of plan.png
    boundary, workable = field.boundary, plan.workable
    frames = _swath_frames(plan, np.asarray)
    swath = s["swath"].to_numpy().astype(int)
    xte_t = _cross_track(s["x"].to_numpy(), s["y"].to_numpy(), np.where(s["segment"] == SWATH, swath, -99), frames)
    xte_i = _cross_track(s["ix"].to_numpy(), s["iy"].to_numpy(), np.where(s["impl_segment"] == SWATH, swath, -99), frames)
    written = []

    def save(fig, name):
        fig.tight_layout()
        atomic_write(out_dir / name, lambda p: fig.savefig(p, dpi=110, format="png"))
        plt.close(fig)
        written.append(out_dir / name)

    from fields.planner.export import times_worked, times_worked_colorbar

    fig, ax = plt.subplots(figsize=(9, 8))
    times_worked_colorbar(fig, ax, times_worked(ax, _strips(s, plan.settings.working_width), boundary, workable))
    for geom, style, label in ((boundary, "k-", "field"), (workable, "k:", "workable")):
        bx, by = geom.exterior.xy
        ax.plot(bx, by, style, lw=1, label=label)
    ax.set(aspect="equal", xlabel="east [m]", ylabel="north [m]",
           title=f"field {field.name!r} ({field.area_ha:.2f} ha): times the implement worked each spot")
    ax.legend(fontsize=8, loc="lower right")
    save(fig, "coverage.png")

    fig, ax = plt.subplots(figsize=(9, 8))
    bx, by = boundary.exterior.xy
    ax.plot(bx, by, "k-", lw=1)
    ax.plot(s["x"], s["y"], color="0.75", lw=0.5, label="tractor's CG (whole route)")
    on = np.isfinite(xte_i)
    pts = np.column_stack([s["ix"], s["iy"]])
    segs = np.stack([pts[:-1], pts[1:]], axis=1)[on[:-1] & on[1:]]
    lc = LineCollection(segs, cmap="viridis", array=100 * np.abs(xte_i[:-1][on[:-1] & on[1:]]), linewidths=1.5)
    lc.set_clim(0, max(5.0, 100 * np.nanpercentile(np.abs(xte_i), 99) if on.any() else 5.0))
    ax.add_collection(lc)
    fig.colorbar(lc, ax=ax, shrink=0.6, label="implement |cross-track error| on swaths [cm]")
    ax.set(aspect="equal", xlabel="east [m]", ylabel="north [m]", title="the implement's track on the swaths, "
           "coloured by its cross-track error")
    ax.legend(fontsize=8, loc="lower right")
    save(fig, "track_error.png")

    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    p2p = _pass_to_pass(s, frames, plan.settings.working_width - plan.settings.overlap)
    for ax, e, title in ((axes[0], xte_t, "tractor CG on swaths"), (axes[1], xte_i, "implement on swaths"),
                         (axes[2], p2p, "pass to pass (spacing - planned)")):
        e = 100 * e[np.isfinite(e)]
        if len(e):
            ax.hist(e, bins=60, color="tab:blue", alpha=0.8)
            p95 = np.percentile(np.abs(e), 95)
            for v in (-p95, p95):
                ax.axvline(v, color="k", ls="--", lw=1)
            ax.set_title(f"{title}\nP95 |error| {p95:.1f} cm", fontsize=9)
            if ax is axes[1]:           # the judged figure: the implement's P95 against its target
                for v in (-1, 1):
                    ax.axvline(100 * v * IMPLEMENT_XTE_P95_TARGET, color="tab:red", lw=1.2,
                               label=f"target: P95 <= {100 * IMPLEMENT_XTE_P95_TARGET:g} cm" if v > 0 else None)
                ax.plot([], [], "k--", lw=1, label="P95 |error|")
                ax.legend(fontsize=7)
        ax.set_xlabel("error [cm]")
        ax.set_ylabel("samples")
        ax.grid(alpha=0.3)
    save(fig, "error_histograms.png")
    return written
