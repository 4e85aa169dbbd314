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

Imported where used: matplotlib (start-up: pyplot, about 1.1 s here, would be paid by every run of a field study
and by each of its sweep workers, which read this module for their metrics, plots or not).
"""
from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
from shapely import contains_xy
from shapely.affinity import affine_transform
from shapely.ops import unary_union

from agrobot.fields.planner import HEADLAND, SWATH, TRANSIT, TURN
from agrobot.fields.planner.applied import applied_outside, as_applied
from agrobot.fields.planner.export import times_worked, times_worked_colorbar
from agrobot.orchestrator.atomic_files import atomic_write
from agrobot.orchestrator.key_figures import bounds
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study

from .field_ground import ground_metrics
from .field_tracks import (_cross_track, _in_field_frame, _pass_to_pass, _samples, _shape, _stats, _swath_frames,
                           applied_strips, field_frame, mission, sections_of)
from .mcap_scene import mcap_scene  # noqa: F401 - the run's MCAP scene (orchestrator.mcap_out)
from .signal_roles import component_named


def metrics(frame: pd.DataFrame, study: Study) -> dict[str, float]:
    field, plan, conv, _ = mission(study)
    settings = plan.settings
    s = _samples(frame, study)
    frames = _swath_frames(plan, conv)
    swath = s["swath"].to_numpy().astype(int)
    seg, iseg = s["segment"].to_numpy(), s["impl_segment"].to_numpy()
    xte_t = _cross_track(s["x"].to_numpy(), s["y"].to_numpy(), np.where(seg == SWATH, swath, -99), frames)
    xte_i = _cross_track(s["ix"].to_numpy(), s["iy"].to_numpy(), np.where(iseg == SWATH, swath, -99), frames)
    boundary = _shape(field.boundary, conv)
    sections = sections_of(study)
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
        out.update({f"{name}_xte_rms_m": rms, f"{name}_xte_p95_m": p95, f"{name}_xte_max_m": mx,
                    f"{name}_xte_swaths_p95_m": p95})       # the judged part in the name: swaths, turns excluded
    out["pass_to_pass_p95_m"] = float(np.percentile(np.abs(p2p), 95)) if len(p2p) else math.nan
    out["pass_to_pass_mean_m"] = float(np.mean(p2p)) if len(p2p) else math.nan
    out.update(coverage(s, study, field, plan, conv)[1], boundary_crossings=float(crossings), sections=float(sections))
    out.update(plan_figures(plan, sections))
    for kind, name in ((SWATH, "swath"), (HEADLAND, "headland"), (TURN, "turn"), (TRANSIT, "transit")):
        m = seg == kind
        out[f"{name}_time_s"] = float(dt[m].sum())
        out[f"{name}_distance_m"] = float(dist[m].sum())
    out["mission_time_s"] = float(s["t"].iloc[-1] - s["t"].iloc[0])
    out.update(ground_metrics(frame, study, s, plan, conv, frames))
    return out


def coverage(s: pd.DataFrame, study: Study, field, plan, conv) -> tuple[list, dict[str, float]]:
    """(the implement's applied strips in the mission frame, the coverage figures): the strips united
    (shapely) against the workable area and the whole field: covered, overlap (swept area - covered
    area: worked more than once) and skipped area, their shares; and how much of the route was run."""
    strips = applied_strips(s, plan.settings.working_width, sections_of(study))
    workable, boundary = _shape(plan.workable, conv), _shape(field.boundary, conv)
    union = unary_union(strips) if strips else None
    covered = union.intersection(workable).area if union is not None else 0.0
    overlap = max(sum(st.intersection(workable).area for st in strips) - covered, 0.0)
    area = workable.area
    field_covered = union.intersection(boundary).area if union is not None else 0.0
    field_swept = sum(st.intersection(boundary).area for st in strips)
    return strips, dict(field_coverage_share=field_covered / boundary.area, coverage_share=covered / area,
                        overlap_share=overlap / area, skipped_area_m2=area - covered,
                        covered_area_m2=covered, overlap_area_m2=overlap, workable_area_m2=area,
                        field_area_m2=boundary.area,
                        field_overlap_share=max(field_swept - field_covered, 0.0) / boundary.area,
                        field_skipped_area_m2=boundary.area - field_covered,
                        applied_outside_m2=union.difference(boundary).area if union is not None else 0.0,
                        route_done_share=float(s["progress"].max()), swaths_planned=float(len(plan.swaths)))


GOAL_NAMES = {"coverage_share": "coverage", "field_coverage_share": "whole-field coverage", "overlap_share": "overlap"}


def coverage_verdict(values: dict[str, float], study: Study) -> str:
    """The coverage figure's conclusion: coverage and overlap of the workable area, the skipped area, and
    whether the goal holds (the coverage, field coverage and overlap bounds, with the study's own
    ``[study] bounds`` over ours), the bounds that do not fit the run said not judged (``unjudged``)."""
    why_not = unjudged(values, study)
    goal = {k: b for k, b in bounds(SimpleNamespace(METRICS=METRICS), study.study.bounds).items()
            if k in GOAL_NAMES and k not in why_not}
    missed = [f"{GOAL_NAMES[k]} {100 * values[k]:.1f} % (goal {b.op} {100 * b.value:g} %)"
              for k, b in goal.items() if not b.holds(values[k])]
    verdict = "within the goal" if not missed else "MISSES the goal: " + ", ".join(missed)
    if why_not:
        judged = f"{', '.join(GOAL_NAMES[k] for k in goal)} {verdict}; " if goal else ""
        verdict = f"{judged}coverage not judged: {next(iter(why_not.values()))}"
    return (f"Coverage {100 * values['coverage_share']:.1f} %, overlap {100 * values['overlap_share']:.1f} %, "
            f"{values['skipped_area_m2']:.0f} m² skipped (workable area {values['workable_area_m2'] / 1e4:.2f} ha):\n"
            f"{verdict}")


def plan_figures(plan, sections: int) -> dict[str, float]:
    """The plan's own as-applied figures (fields.planner.applied, the same sections with perfect
    look-ahead on the planned path), beside the driven ones: ``plan_*`` of the same names."""
    a = as_applied(plan, sections)
    return {"plan_field_coverage_share": a.field_coverage_share, "plan_field_overlap_share": a.overlap_share,
            "plan_field_skipped_area_m2": a.skipped, "plan_applied_outside_m2": applied_outside(a, plan.field.boundary)}


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
           "outage_drift_max_m": ("m", None), "guidance_stops": ("count", None),
           "field_overlap_share": ("1", None), "plan_field_coverage_share": ("1", None),
           "plan_field_overlap_share": ("1", None), "field_skipped_area_m2": ("m2", None),
           "plan_field_skipped_area_m2": ("m2", None), "applied_outside_m2": ("m2", None),
           "plan_applied_outside_m2": ("m2", None), "tractor_xte_swaths_p95_m": ("m", None),
           "implement_xte_swaths_p95_m": ("m", None)}
METRIC_UNITS = {**{k: unit for k, (unit, _) in METRICS.items()},
                **{f"{kind}_{q}": unit for kind in ("swath", "headland", "turn", "transit")
                   for q, unit in (("time_s", "s"), ("distance_m", "m"))},
                **{k: "m" for k in ("tractor_xte_max_m", "pass_to_pass_mean_m")},
                **{k: "m2" for k in ("covered_area_m2", "overlap_area_m2", "workable_area_m2", "field_area_m2")},
                "route_done_share": "1", "swaths_planned": "count", "events": "count", "sections": "count",
                **{k: "m" for k in ("route_xte_rms_m", "route_xte_max_m", "line_acquisition_max_m")},
                **{k: "count" for k in ("line_acquisitions", "line_acquisition_failures", "outages")}}



def unjudged(values: dict[str, float], study: Study) -> dict[str, str]:
    """The coverage bounds are for the whole field and the whole route: a plan of the first
    ``max_swaths`` swaths, one without headland passes, or a run that ended before its route did is
    shown against them, not judged (orchestrator.key_figures prints why on the figure's line)."""
    p = resolve(study).parameters(component_named(study, "route"))
    n = int(values.get("swaths_planned", 0))
    whole = ("field_coverage_share", "coverage_share")
    if p.get("max_swaths"):
        return dict.fromkeys(whole, f"bounds for the whole field; this run plans {n} swath{'s' if n != 1 else ''} "
                                    f"(max_swaths = {p['max_swaths']})")
    done = values.get("route_done_share", 1.0)
    if done < 0.999:
        return dict.fromkeys(whole, f"bounds for the whole route; this run ended at {100 * done:.0f}% of it "
                                    f"(stop_time {study.study.stop_time:g} s)")
    if not p.get("headland_work", True):
        return {"field_coverage_share": "bounds for the whole field; this run drives no headland pass (headland_work = 0)"}
    return {}


def reasons(values: dict[str, float], study: Study) -> dict[str, str]:
    """Why a figure is nan: no adjacent passes for pass-to-pass, no sample of a kind."""
    out = {}
    for key in ("pass_to_pass_p95_m", "pass_to_pass_mean_m", "tractor_pass_to_pass_p95_m", "pass_to_pass_interval_s"):
        out[key] = f"no two adjacent passes were driven ({int(values.get('swaths_planned', 0))} planned)"
    for who in ("tractor", "implement"):
        for q in ("rms", "p95", "max"):
            out[f"{who}_xte_{q}_m"] = f"the {who} was never on a swath in this run"
    out["xte_max_in_outage_m"] = out["outage_drift_max_m"] = "no GNSS outage in this run"
    n = int(values.get("line_acquisitions", 0))
    out["line_acquisition_p95_m"] = out["line_acquisition_p95_s"] = (
        f"none of the {n} line acquisitions after a turn settled on its line" if n else "no turn into a line in this run")
    return out


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


def coverage_figure(frame: pd.DataFrame, study: Study):
    """The field in east/north coloured by the times the implement worked each spot (from the strips
    the metrics judge, carried back from the mission frame), titled with its conclusion
    (coverage_verdict on the same figures as metrics)."""
    import matplotlib.pyplot as plt

    field, plan, conv, _ = mission(study)
    strips, values = coverage(_samples(frame, study), study, field, plan, conv)
    to_field, _ = field_frame(plan)
    fig, ax = plt.subplots(figsize=(9, 8))
    times_worked_colorbar(fig, ax, times_worked(ax, [affine_transform(st, to_field) for st in strips],
                                                field.boundary, plan.workable))
    for geom, style, label in ((field.boundary, "k-", "field"), (plan.workable, "k:", "workable area")):
        bx, by = geom.exterior.xy
        ax.plot(bx, by, style, lw=1, label=label)
    ax.set(aspect="equal", xlabel="east [m]", ylabel="north [m]")
    ax.set_title(f"Field {field.name!r} ({field.area_ha:.2f} ha). {coverage_verdict(values, study)}", fontsize=9)
    ax.legend(fontsize=8, loc="lower right")
    return fig


def plots(frame: pd.DataFrame, study: Study, out_dir: Path) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    field, plan, _, _ = mission(study)
    s = _in_field_frame(_samples(frame, study), plan)        # east/north, the frame of plan.png
    boundary = field.boundary
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

    save(coverage_figure(frame, study), "coverage.png")

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
