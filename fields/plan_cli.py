"""``plan FIELD --out DIR``: a coverage plan of a field (fields.coverage) written as route.csv
(s, x, y, heading, curvature, speed, kind, index), route.geojson (longitude/latitude where the
field has a geographic reference), plan.json (swaths, turns, distances, estimated time, angle and
how it was chosen) and plan.png (the field, headland, swaths and turns)."""
from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from .coverage import HEADLAND, KINDS, SWATH, TRANSIT, TURN, Settings


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("field", type=Path, help="a field file or folder (see the fields command)")
    p.add_argument("--out", type=Path, required=True, help="output folder")
    p.add_argument("--crs", default=None, help="the coordinates' CRS when the file does not name it")
    p.add_argument("--name", default=None, help="the field to plan when the file holds several (default: the largest)")
    d = Settings()
    p.add_argument("--width", type=float, default=d.working_width, help=f"working width [m] ({d.working_width:g})")
    p.add_argument("--headland-passes", type=int, default=d.headland_passes, help="0: as many as the turns need")
    p.add_argument("--angle", type=float, default=None, help="driving angle [deg, east = 0, counter-clockwise] "
                   "(default: chosen for the fewest swaths)")
    p.add_argument("--guidance-line", default="", metavar="NAME", help="drive along the field's guidance line "
                   "NAME (an AB line of an AgOpenGPS or ISOXML field; '*': its first)")
    p.add_argument("--turn-radius", type=float, default=d.turn_radius, help=f"m ({d.turn_radius:g})")
    p.add_argument("--work-speed", type=float, default=d.work_speed, help=f"m/s ({d.work_speed:g})")
    p.add_argument("--turn-speed", type=float, default=d.turn_speed, help=f"m/s ({d.turn_speed:g})")
    p.add_argument("--order", default=d.order, choices=("auto", "boustrophedon", "skip"))
    p.add_argument("--hitch-offset", type=float, default=d.hitch_offset, help=f"m behind the rear axle ({d.hitch_offset:g})")
    p.add_argument("--drawbar", type=float, default=d.drawbar, help=f"m, hitch to implement axle; 0: mounted ({d.drawbar:g})")
    p.add_argument("--settle", type=float, default=d.settle, help=f"m driven straight before a swath beyond the "
                   f"implement's length ({d.settle:g})")
    p.add_argument("--max-swaths", type=int, default=0, help="plan only the first N swaths (a section)")


def choose_field(fields, name: str | None, where: str):
    from .field import FieldError

    if name is None:
        return max(fields, key=lambda f: f.boundary.area)
    found = [f for f in fields if f.name == name]
    if not found:
        raise FieldError(f"{where}: no field named {name!r}; fields: {', '.join(f.name for f in fields)}")
    return found[0]


def run(args: argparse.Namespace) -> int:
    from orchestrator.output import check_output
    from orchestrator.results import atomic_write, write_json

    from .coverage import plan
    from .readers import read_fields

    check_output(args.out, overwrite=True)
    field = choose_field(read_fields(args.field, args.crs), args.name, str(args.field))
    settings = Settings(working_width=args.width, headland_passes=args.headland_passes,
                        driving_angle=None if args.angle is None else math.radians(args.angle),
                        turn_radius=args.turn_radius, work_speed=args.work_speed, turn_speed=args.turn_speed,
                        order=args.order, hitch_offset=args.hitch_offset, drawbar=args.drawbar,
                        settle=args.settle, max_swaths=args.max_swaths, guidance_line=args.guidance_line)
    p = plan(field, settings)
    summary = p.summary()
    write_route(p, args.out)
    write_json(args.out / "plan.json", summary)
    draw_plan(p, args.out / "plan.png")
    print(f"field {field.name!r} ({field.area_ha:.2f} ha, workable {summary['workable_ha']:.2f} ha) from {args.field}")
    print(f"  driving angle {summary['driving_angle_deg']:.1f} deg ({summary['driving_angle_how']}); order "
          f"{summary['order']}; {summary['headland_passes']} headland pass(es) of {settings.working_width:g} m")
    print(f"  {summary['swaths']} swaths, {summary['turns']} turns; {summary['distance_m'] / 1000:.2f} km in all, "
          f"{summary['working_distance_m'] / 1000:.2f} km working, {summary['turn_distance_m'] / 1000:.2f} km turning; "
          f"about {summary['estimated_time_s'] / 3600:.2f} h")
    for note in summary["notes"]:
        print(f"  note: {note}")
    print(f"written: {args.out}/route.csv, route.geojson, plan.json, plan.png")
    return 0


def write_route(p, out: Path) -> None:
    import pandas as pd

    from orchestrator.results import atomic_write

    r = p.route
    table = pd.DataFrame({k: r[k] for k in ("s", "x", "y", "heading", "curvature", "speed", "kind", "index")})
    table["kind"] = [KINDS[int(k)] for k in r["kind"]]
    atomic_write(out / "route.csv", lambda f: table.to_csv(f, index=False, float_format="%.4f"))
    feats = []
    conv = p.field.to_geodetic if p.field.origin is not None else (lambda xy: xy)
    import numpy as np

    kinds, s = r["kind"], 0
    breaks = np.flatnonzero(np.diff(kinds) != 0) + 1
    for a, b in zip(np.concatenate([[0], breaks]), np.concatenate([breaks, [len(kinds)]])):
        xy = conv(np.column_stack([r["x"][a:b + 1], r["y"][a:b + 1]]))
        feats.append({"type": "Feature", "properties": {"kind": KINDS[int(kinds[a])], "index": int(r["index"][a])},
                      "geometry": {"type": "LineString", "coordinates": xy.round(9).tolist()}})
    doc = {"type": "FeatureCollection", "features": feats,
           "properties": {"coordinates": "lon/lat" if p.field.origin is not None else "local metres"}}
    atomic_write(out / "route.geojson", lambda f: f.write_text(json.dumps(doc)))


def draw_plan(p, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from orchestrator.results import atomic_write

    fig, ax = plt.subplots(figsize=(9, 8))
    bx, by = p.field.boundary.exterior.xy
    ax.fill(bx, by, color="#e8f3dc", edgecolor="#2f6b1f", lw=1.5, label="field")
    for hole in p.field.boundary.interiors:
        hx, hy = hole.xy
        ax.fill(hx, hy, color="white", edgecolor="#8a3b12", lw=1)
    ix, iy = p.inner.exterior.xy
    ax.plot(ix, iy, "--", color="#7a5c00", lw=1, label=f"headland ({p.headland_passes} x {p.settings.working_width:g} m)")
    styles = {SWATH: ("tab:blue", 1.0, "swath"), TURN: ("tab:red", 0.9, "turn"), HEADLAND: ("tab:green", 1.0, "headland pass"),
              TRANSIT: ("tab:purple", 0.9, "transit")}
    seen = set()
    for seg in p.segments:
        color, lw, label = styles[seg.kind]
        ax.plot(seg.path[:, 0], seg.path[:, 1], color=color, lw=lw, label=None if seg.kind in seen else label)
        seen.add(seg.kind)
    start = p.route
    ax.plot(start["x"][0], start["y"][0], "k^", ms=8, label="start")
    s = p.summary()
    ax.set_title(f"{p.field.name}: {s['swaths']} swaths at {s['driving_angle_deg']:.0f} deg, {s['turns']} turns, "
                 f"{s['distance_m'] / 1000:.2f} km, about {s['estimated_time_s'] / 3600:.2f} h", fontsize=10)
    ax.set_aspect("equal")
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    atomic_write(path, lambda f: fig.savefig(f, dpi=110, format="png"))
    plt.close(fig)
    return path


def register(registry) -> None:
    registry.add_command("plan", "a coverage plan of a field: headland, swaths, turns, speeds (route.csv, .geojson, .png)",
                         add_arguments, run)
