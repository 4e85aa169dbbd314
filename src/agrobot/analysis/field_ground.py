"""Guidance on real ground, the figures autosteer vendors and ISO 12188-2 quote: the tractor's
cross-track error to the whole route by interpolation (its projection on the route's segments,
not the nearest route point), line acquisition after each turn, the cross-track error and the
estimator's drift in GNSS outages (the samples whose fix is not RTK fixed, or is bridged on aged
corrections), the watchdog's stops and the time between adjacent passes.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

from agrobot.components.hardware.nmea import RTK_FIXED
from agrobot.fields.planner import SWATH, TURN
from agrobot.fields.planner.sampling import ROUTE_STEP
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study

from .field_tracks import TRACTOR, _pass_to_pass, _stats, station
from .signal_roles import component_named, runs, signal

# line acquisition
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
        station_along, across = station(frames[k], x[on], y[on])
        e = np.abs(across)
        inside = e < ACQUIRED
        found = math.nan, math.nan
        for first, last in runs(inside):
            if t[on[last - 1]] - t[on[first]] >= ACQUIRED_HOLD or last == len(on):
                j0, j1 = on[0], on[first]
                along = station_along[first] - station_along[0]
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
    age_column = f"{gps}.correction_age"
    bridged = rows[age_column].to_numpy() > 0 if age_column in rows else np.zeros(len(quality), bool)
    windows = runs((quality != RTK_FIXED) | bridged)          # a bridged fix reports RTK fixed on aged corrections
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
