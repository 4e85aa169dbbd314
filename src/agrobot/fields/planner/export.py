"""A plan's files: route.csv and route.geojson written a chunk at a time from the path (bounded
memory whatever the route's length), plan.json, and plan.png (the field, headland, swaths, turns).

Imported where used: matplotlib (start-up: 80 ms of CPU, 0.37 s with pyplot, on every command, measured: the
fields plugin loads this module through the plan command; only a drawing needs it).
"""
from __future__ import annotations

import json
import math
from pathlib import Path as FilePath

import numpy as np
import pandas as pd
import shapely
from shapely import contains_xy
from shapely.geometry import mapping

from .path import COLUMNS
from .pipeline import Plan
from .sampling import EXPORT_STEP
from .types import HEADLAND, KINDS, SWATH, TRANSIT, TURN

KIND_NAMES = np.array([KINDS[k] for k in sorted(KINDS)])


def write_route_csv(plan: Plan, target: FilePath, step: float = EXPORT_STEP, uniform: bool = False) -> int:
    """route.csv: COLUMNS, kind by name; rows at ``plan.path.knots(step, uniform)``. Returns the rows."""
    rows = 0
    with open(target, "w", newline="") as f:
        f.write(",".join(COLUMNS) + "\n")
        for s in plan.path.knots(step, uniform):
            table = pd.DataFrame(plan.path.evaluate(s))
            table["kind"] = KIND_NAMES[table["kind"].to_numpy()]
            table.to_csv(f, header=False, index=False, float_format="%.4f")
            rows += len(table)
    return rows


def write_route_geojson(plan: Plan, target: FilePath, step: float = EXPORT_STEP, uniform: bool = False) -> None:
    """route.geojson: one LineString feature per run of one kind and index (a swath, a turn, a
    headland pass ...), each ending where the next begins; longitude/latitude when the field has
    a geographic reference, else its local metres."""
    field = plan.field
    conv = field.to_geodetic if field.origin is not None else (lambda xy: xy)
    with open(target, "w") as f:
        f.write('{"type": "FeatureCollection", "properties": {"coordinates": "%s"}, "features": ['
                % ("lon/lat" if field.origin is not None else "local metres"))
        first, run, key = True, [], None

        def flush(closing_point=None):
            nonlocal first
            if not run:
                return
            xy = np.vstack(run + ([closing_point] if closing_point is not None else []))
            if len(xy) < 2:
                xy = np.vstack([xy, xy])
            feature = {"type": "Feature", "properties": {"kind": KINDS[key[0]], "index": key[1]},
                       "geometry": {"type": "LineString", "coordinates": conv(xy).round(9).tolist()}}
            f.write(("" if first else ",\n") + json.dumps(feature))
            first = False

        for s in plan.path.knots(step, uniform):
            r = plan.path.evaluate(s)
            xy = np.column_stack([r["x"], r["y"]])
            keys = np.column_stack([r["kind"], r["index"]])
            breaks = np.flatnonzero(np.any(np.diff(keys, axis=0) != 0, axis=1)) + 1
            for a, b in zip(np.concatenate([[0], breaks]), np.concatenate([breaks, [len(s)]])):
                k = (int(keys[a, 0]), int(keys[a, 1]))
                if key is not None and k != key:
                    flush(xy[a])
                    run = []
                key = k
                run.append(xy[a:b])
        flush()
        f.write("]}\n")


def draw_plan(plan: Plan, target: FilePath) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    fig, ax = plt.subplots(figsize=(9, 8))
    bx, by = plan.field.boundary.exterior.xy
    ax.fill(bx, by, color="#e8f3dc", edgecolor="#2f6b1f", lw=1.5, label="field")
    for hole in plan.field.boundary.interiors:
        hx, hy = hole.xy
        ax.fill(hx, hy, color="white", edgecolor="#8a3b12", lw=1)
    for k, piece in enumerate(plan.pieces or [plan.inner]):
        ix, iy = piece.exterior.xy
        ax.plot(ix, iy, "--", color="#7a5c00", lw=1, label=None if k else f"headland ({plan.headland_passes} x "
                f"{plan.settings.working_width:g} m)" + (f"; {len(plan.pieces)} pieces inside" if len(plan.pieces) > 1 else ""))
    styles = {SWATH: ("tab:blue", 1.0, "swath"), TURN: ("tab:red", 0.9, "turn"),
              HEADLAND: ("tab:green", 1.0, "headland pass"), TRANSIT: ("tab:purple", 0.9, "transit")}
    segments = plan.path.segments
    minx, miny, maxx, maxy = plan.field.boundary.bounds
    pixels = plan.settings.spacing / max(maxx - minx, maxy - miny, 1e-9) * 750     # between swaths, on the figure
    every = max(1, math.ceil(3.0 / pixels))           # thinned to one in ``every`` when they would merge
    for kind, (color, lw, label) in styles.items():
        lines = [seg.points[:, :2] for seg in segments if seg.kind == kind and (kind != SWATH or seg.index % every == 0)]
        if kind == SWATH and every > 1:
            label = f"swath (one line in {every} shown)"
        if lines:
            ax.add_collection(LineCollection(lines, colors=color, linewidths=lw, label=label))
    x0, y0, _ = plan.path.start_pose()
    ax.plot(x0, y0, "k^", ms=8, label="start")
    s = plan.summary()
    ax.set_title(f"{plan.field.name}: {s['swaths']} swaths at {s['driving_angle_deg']:.0f} deg, {s['turns']} turns, "
                 f"{s['distance_m'] / 1000:.2f} km, about {s['estimated_time_s'] / 3600:.2f} h", fontsize=10)
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    fig.savefig(target, dpi=110, format="png")
    plt.close(fig)


def write_applied_geojson(plan: Plan, applied, target: FilePath) -> None:
    """as_applied.geojson: the ground covered (one feature) and each applied strip (a section's or
    the whole width's run where it was on); longitude/latitude where the field has a geographic
    reference, else its local metres."""
    field = plan.field
    if field.origin is not None:
        def conv(geom):
            return shapely.transform(geom, lambda xy: np.asarray(field.to_geodetic(xy), float).reshape(-1, 2))
    else:
        def conv(geom):
            return geom
    features = [{"type": "Feature", "properties": {"kind": "covered", "area_m2": round(applied.covered, 2)},
                 "geometry": mapping(conv(applied.shape))}]
    features += [{"type": "Feature", "properties": {"kind": "strip"}, "geometry": mapping(conv(s.simplify(0.01)))}
                 for s in applied.strips]
    with open(target, "w") as f:
        json.dump({"type": "FeatureCollection", "properties": {
            "coordinates": "lon/lat" if field.origin is not None else "local metres",
            "field_coverage_share": applied.field_coverage_share, "overlap_share": applied.overlap_share},
            "features": features}, f)


def times_worked(ax, strips, boundary, workable, cells: float = 1.5e6):
    """A raster (at most ``cells`` cells) of how many times each spot of the field was worked,
    drawn on ``ax``: pale grey where the implement cannot reach, dark red skipped, green once, orange
    and purple more; the five classes also differ in lightness (luminance 0.93, 0.13, 0.74, 0.49, 0.32),
    so that the figure reads in grey. Returns the colour mesh (for a colour bar)."""
    from matplotlib.colors import BoundaryNorm, ListedColormap

    minx, miny, maxx, maxy = boundary.bounds
    cell = max(0.1, math.sqrt((maxx - minx) * (maxy - miny) / cells))
    gx, gy = np.meshgrid(np.arange(minx, maxx, cell) + cell / 2, np.arange(miny, maxy, cell) + cell / 2)
    count = np.zeros(gx.shape)
    for st in strips:
        a, b, c, d = st.bounds
        i0, i1 = np.searchsorted(gy[:, 0], [b, d])
        j0, j1 = np.searchsorted(gx[0], [a, c])
        count[i0:i1, j0:j1] += contains_xy(st, gx[i0:i1, j0:j1], gy[i0:i1, j0:j1])
    count = np.clip(count, 0, 3)
    count[~contains_xy(workable, gx, gy) & (count == 0)] = -1       # the implement cannot reach it (corners)
    count[~contains_xy(boundary, gx, gy)] = np.nan
    cmap = ListedColormap(["#eeeeee", "#67000d", "#a6d96a", "#e66101", "#5e3c99"], name="times worked")
    return ax.pcolormesh(gx, gy, count, cmap=cmap, norm=BoundaryNorm([-1.5, -0.5, 0.5, 1.5, 2.5, 3.5], 5),
                         shading="auto")


def times_worked_colorbar(fig, ax, mesh) -> None:
    cb = fig.colorbar(mesh, ax=ax, ticks=[-1, 0, 1, 2, 3], shrink=0.8)
    cb.ax.set_yticklabels(["not reachable", "0 (skipped)", "1", "2 (overlap)", "3+"])
    cb.set_label("times the implement worked the spot [passes]")


def draw_applied(plan: Plan, applied, sections: int, target: FilePath) -> None:
    """as_applied.png: times each spot of the field was worked, as planned."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 8))
    boundary = plan.field.boundary
    mesh = times_worked(ax, applied.strips, boundary, plan.workable)
    times_worked_colorbar(fig, ax, mesh)
    for ring in [boundary.exterior, *boundary.interiors]:
        bx, by = ring.xy
        ax.plot(bx, by, "k-", lw=1)
    how = f"{sections} sections" if sections else "no section control"
    ax.set_title(f"{plan.field.name} as applied ({how}): {100 * applied.field_coverage_share:.2f} % of the field "
                 f"worked, {100 * applied.overlap_share:.2f} % overlap", fontsize=10)
    ax.set(aspect="equal", xlabel="east [m]", ylabel="north [m]")
    fig.tight_layout()
    fig.savefig(target, dpi=110, format="png")
    plt.close(fig)
