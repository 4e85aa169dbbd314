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
- time and distance on swaths, headland passes and in turns.

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

from .signals import component_named, signal

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


def _strips(s: pd.DataFrame, width: float):
    """The implement's swept strips: one per run of working samples."""
    from shapely.geometry import LineString

    work = s["working"].to_numpy() > 0.5
    edges = np.diff(np.concatenate([[0], work.astype(int), [0]]))
    strips = []
    for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
        if b - a >= 2:
            line = LineString(np.column_stack([s["ix"].to_numpy()[a:b], s["iy"].to_numpy()[a:b]]))
            strips.append(line.buffer(0.5 * width, cap_style="flat", join_style="round"))
    return strips


def _pass_to_pass(s: pd.DataFrame, frames, spacing: float) -> np.ndarray:
    """Spacing errors between adjacent implement passes (line k and k + 1), 1 m apart along them."""
    on = (s["impl_segment"].to_numpy() == SWATH)
    px, py, k_of = s["ix"].to_numpy(), s["iy"].to_numpy(), s["swath"].to_numpy()
    errors = []
    keys = sorted(frames)
    for k in keys:
        if k + 1 not in frames:
            continue
        a, d = frames[k]
        n = np.array([-d[1], d[0]])
        tracks = []
        for j in (k, k + 1):
            m = on & (k_of == j)
            if m.sum() < 10:
                break
            rel = np.column_stack([px[m] - a[0], py[m] - a[1]])
            along, across = rel @ d, rel @ n
            order = np.argsort(along)
            tracks.append((along[order], across[order]))
        if len(tracks) < 2:
            continue
        lo = max(tracks[0][0][0], tracks[1][0][0])
        hi = min(tracks[0][0][-1], tracks[1][0][-1])
        if hi - lo < 2.0:
            continue
        grid = np.arange(lo, hi, 1.0)
        gap = np.interp(grid, *tracks[1]) - np.interp(grid, *tracks[0])
        errors.append(np.abs(gap) - spacing)
    return np.concatenate(errors) if errors else np.zeros(0)


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
    return out


METRICS = {"field_coverage_share": ("1", ">= 0.99 (of the whole field)"), "coverage_share": ("1", ">= 0.99"),
           "overlap_share": ("1", "<= 0.05"), "skipped_area_m2": ("m2", None),
           "boundary_crossings": ("count", "0"), "tractor_xte_p95_m": ("m", None),
           "implement_xte_p95_m": ("m", "<= 0.05 (RTK class +-0.025)"), "pass_to_pass_p95_m": ("m", None),
           "tractor_xte_rms_m": ("m", None), "implement_xte_rms_m": ("m", None), "implement_xte_max_m": ("m", None),
           "swath_time_s": ("s", None), "turn_time_s": ("s", None), "headland_time_s": ("s", None),
           "mission_time_s": ("s", None), "wall_time_s": ("s", None)}
METRIC_UNITS = {**{k: unit for k, (unit, _) in METRICS.items()},
                **{f"{kind}_{q}": unit for kind in ("swath", "headland", "turn", "transit")
                   for q, unit in (("time_s", "s"), ("distance_m", "m"))},
                **{k: "m" for k in ("tractor_xte_max_m", "pass_to_pass_mean_m")},
                **{k: "m2" for k in ("covered_area_m2", "overlap_area_m2", "workable_area_m2", "field_area_m2")},
                "route_done_share": "1", "swaths_planned": "count", "events": "count"}


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

    field, plan, conv, _ = mission(study)
    s = _samples(frame, study)
    boundary, workable = _shape(field.boundary, conv), _shape(plan.workable, conv)
    frames = _swath_frames(plan, conv)
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
    ax.set(aspect="equal", xlabel="x [m] (mission frame: the route starts at 0, 0 heading along x)", ylabel="y [m]",
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
    fig.colorbar(lc, ax=ax, shrink=0.8, label="implement |cross-track error| on swaths [cm]")
    ax.set(aspect="equal", xlabel="x [m] (mission frame)", ylabel="y [m]", title="the implement's track on the swaths, "
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
        ax.set_xlabel("error [cm]")
        ax.set_ylabel("samples")
        ax.grid(alpha=0.3)
    save(fig, "error_histograms.png")
    return written
