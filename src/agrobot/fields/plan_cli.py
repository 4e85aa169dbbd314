"""``plan FIELD --out DIR``: a coverage plan of a field (fields.planner) written as one set:
route.csv (s, x, y, heading, curvature, speed, kind, index), route.geojson (longitude/latitude
where the field has a geographic reference), plan.json (swaths, turns, distances, estimated time,
angle and how it was chosen, the as-applied figures: share of the whole field covered, overlap,
boundary crossings), plan.png (the field, headland, swaths and turns), as_applied.geojson and
as_applied.png (the ground worked, with ``--sections N`` by an implement of N sections switched off
over worked ground and outside the field).

Obstacles (``--obstacles FILE``, ``--obstacle E,N,R``) are cut out of the field before planning
(fields.obstacles): headland passes go round them, swaths stop short, sections switch off.

The set is written into a new folder beside ``--out`` and swapped into place when all four are
complete: an interrupted or failed plan leaves ``--out`` as it was (an earlier plan, or nothing).
``--out`` must be new, empty, or a plan folder (it holds plan.json). Every setting is checked before
any work (finite, in range, a turn radius the field can hold), the message naming the option.

Imported where used: agrobot.api (start-up: 9 ms of CPU on every command, measured: the fields plugin loads
this module; only the plan command's run needs it), agrobot.fields.planner (start-up: with the planner's stages
it loads, 0.2 s on every command, ``--help`` included, measured with ``python3 -X importtime -m agrobot --help``;
only a plan's files need it), agrobot.fields.readers (the same: only a plan reads a field), agrobot.fields.field (the
same), agrobot.fields.obstacles (the same).
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

from agrobot.orchestrator.atomic_files import write_json
from agrobot.orchestrator.cli import add_output_options

from .planner.objectives import OBJECTIVES
from .planner.sampling import EXPORT_STEP, ROUTE_STEP
from .planner.settings import Settings

OPTIONS = {"working_width": "--width", "headland_passes": "--headland-passes", "driving_angle": "--angle",
           "guidance_line": "--guidance-line", "swath_pattern": "--swath-pattern", "angle_objective": "--angle-objective", "turn_radius": "--turn-radius",
           "work_speed": "--work-speed", "turn_speed": "--turn-speed", "order": "--order",
           "hitch_offset": "--hitch-offset", "drawbar": "--drawbar", "settle": "--settle", "max_swaths": "--max-swaths",
           "headland_order": "--headland", "headland_corners": "--headland-corners", "route_seconds": "--route-seconds",
           "start_point": "--start", "end_point": "--end", "overlap": "--overlap"}
FILES = ("route.csv", "route.geojson", "plan.json", "plan.png", "as_applied.geojson", "as_applied.png")


def point(text: str) -> tuple[float, float]:
    """``E,N`` metres east and north of the field's origin (argparse type)."""
    try:
        x, y = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected east,north in metres (e.g. 10,-25.5), got {text!r}") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise argparse.ArgumentTypeError(f"expected finite numbers, got {text!r}")
    return x, y


def finite(text: str) -> float:
    """A finite number (argparse type): inf and nan are refused at once, the value named."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("field", type=Path, help="a field file or folder (see the fields command)")
    add_output_options(p, "output folder (route.csv, route.geojson, plan.json, figures)")
    p.add_argument("--crs", default=None, help="the coordinates' CRS when the file does not name it")
    p.add_argument("--name", default=None, help="the field to plan when the file holds several (default: the largest)")
    d = Settings()
    p.add_argument("--width", type=finite, default=d.working_width, help=f"working width [m] ({d.working_width:g})")
    p.add_argument("--headland-passes", type=int, default=d.headland_passes, help="0: as many as the turns need")
    p.add_argument("--angle", type=finite, default=None, help="driving angle [deg, east = 0, counter-clockwise] "
                   "(default: chosen by --angle-objective)")
    p.add_argument("--angle-objective", default=d.angle_objective, choices=sorted(OBJECTIVES),
                   help=f"how the driving angle is chosen ({d.angle_objective})")
    p.add_argument("--swath-pattern", default=d.swath_pattern, choices=("straight", "curved"),
                   help="straight swaths, or curved: offsets of the guidance line (a curve; --guidance-line, default "
                        "the field's first) at the working width")
    p.add_argument("--guidance-line", default="", metavar="NAME", help="drive along the field's guidance line "
                   "NAME (an AB line of an AgOpenGPS or ISOXML field; '*': its first)")
    p.add_argument("--turn-radius", type=finite, default=d.turn_radius, help=f"m ({d.turn_radius:g})")
    p.add_argument("--work-speed", type=finite, default=d.work_speed, help=f"m/s ({d.work_speed:g})")
    p.add_argument("--turn-speed", type=finite, default=d.turn_speed, help=f"m/s ({d.turn_speed:g})")
    p.add_argument("--order", default=d.order, choices=("auto", "boustrophedon", "skip", "optimised"),
                   help="the swaths' order; optimised: the least non-working distance (OR-tools routing)")
    p.add_argument("--route-seconds", type=finite, default=d.route_seconds, help="--order optimised: seconds of "
                   "guided local search (0: a greedy descent of a bounded number of improving moves, the same on every machine)")
    p.add_argument("--start", type=point, default=None, metavar="E,N", help="the route starts here [m east, north of "
                   "the field's origin]")
    p.add_argument("--end", type=point, default=None, metavar="E,N", help="and ends here")
    p.add_argument("--headland", dest="headland_order", default=d.headland_order, choices=("first", "last"),
                   help=f"drive the headland passes before or after the swaths ({d.headland_order})")
    p.add_argument("--headland-corners", default=d.headland_corners, choices=("tight", "parallel"),
                   help=f"tight: every pass rounds its corners at the turn radius; parallel: each outer pass a "
                        f"working width wider ({d.headland_corners})")
    p.add_argument("--leftover-passes", default="on" if d.leftover_passes else "off", choices=("on", "off"),
                   help="work what the route leaves (corners beyond the headland's, necks, strips) by passes of their "
                        "own after the rest (on)")
    p.add_argument("--overlap", type=finite, default=d.overlap, help=f"m between adjacent passes ({d.overlap:g})")
    p.add_argument("--sections", type=int, default=0, help="the implement's sections, switched off over worked "
                   "ground and outside the field, for the as-applied map (0: no section control)")
    p.add_argument("--obstacles", type=Path, default=None, metavar="FILE", help="GeoJSON of obstacles: Points with a "
                   "'radius' [m] property, Polygons (lon/lat when the field has a geographic reference, else local m)")
    p.add_argument("--obstacle", action="append", default=[], metavar="E,N,R", help="a round obstacle: metres east, "
                   "north of the field's origin and its radius (repeatable)")
    p.add_argument("--hitch-offset", type=finite, default=d.hitch_offset,
                   help=f"m behind the rear axle ({d.hitch_offset:g})")
    p.add_argument("--drawbar", type=finite, default=d.drawbar,
                   help=f"m, hitch to implement axle; 0: mounted ({d.drawbar:g})")
    p.add_argument("--settle", type=finite, default=d.settle, help=f"m driven straight before a swath beyond the "
                   f"implement's length ({d.settle:g})")
    p.add_argument("--max-swaths", type=int, default=0, help="plan only the first N swaths (a section)")
    p.add_argument("--route-step", type=finite, default=EXPORT_STEP, help=f"m: route.csv and route.geojson rows at most "
                   f"this far apart where the route curves or the speed changes, straights by their ends "
                   f"({EXPORT_STEP:g}; the trackers use {ROUTE_STEP:g})")
    p.add_argument("--route-uniform", action="store_true", help="route rows every --route-step m along the whole "
                   "route (a large file for a large field)")


def read_field(path: Path, crs: str | None = None, name: str | None = None):
    """(the field ``name`` of a file or folder, else its largest; why other files of a folder were not read)."""
    from .field import choose_field
    from .readers import read_fields, read_folder

    fields, skipped = read_folder(path, crs) if Path(path).is_dir() else (read_fields(path, crs), [])
    return choose_field(fields, name, str(path)), skipped


def write_plan_files(folder: Path, p, applied, sections: int, summary: dict, route_step: float,
                     route_uniform: bool) -> int:
    """The plan's set (FILES) written into ``folder``; returns route.csv's rows."""
    from .planner import export

    rows = export.write_route_csv(p, folder / "route.csv", route_step, route_uniform)
    export.write_route_geojson(p, folder / "route.geojson", route_step, route_uniform)
    write_json(folder / "plan.json", summary | {"route_rows": rows, "route_step_m": route_step,
                                                "route_uniform": route_uniform})
    export.draw_plan(p, folder / "plan.png")
    export.write_applied_geojson(p, applied, folder / "as_applied.geojson")
    export.draw_applied(p, applied, sections, folder / "as_applied.png")
    return rows


def run(args: argparse.Namespace) -> int:
    """Parse, plan through agrobot.api, print."""
    from agrobot.api import plan

    from .obstacles import parse_point

    settings = dict(working_width=args.width, headland_passes=args.headland_passes,
                    driving_angle=None if args.angle is None else math.radians(args.angle),
                    angle_objective=args.angle_objective, turn_radius=args.turn_radius, work_speed=args.work_speed,
                    turn_speed=args.turn_speed, order=args.order, hitch_offset=args.hitch_offset,
                    drawbar=args.drawbar, settle=args.settle, max_swaths=args.max_swaths,
                    guidance_line=args.guidance_line, swath_pattern=args.swath_pattern,
                    headland_order=args.headland_order, headland_corners=args.headland_corners,
                    route_seconds=args.route_seconds, start_point=args.start, end_point=args.end,
                    overlap=args.overlap, leftover_passes=args.leftover_passes == "on")
    obstacles = [parse_point(text, "plan", k) for k, text in enumerate(args.obstacle)]
    made = plan(args.field, name=args.name, crs=args.crs, sections=args.sections,
                obstacles=obstacles + ([args.obstacles] if args.obstacles is not None else []), out=args.out,
                overwrite=args.overwrite, route_step=args.route_step, route_uniform=args.route_uniform,
                option_names=OPTIONS, **settings)
    summary, field, sections = made.summary, made.plan.field, made.sections
    for why in summary["not_read"]:
        print(f"not read: {why}")
    rows = made.route_rows
    print(f"field {field.name!r} ({field.area_ha:.2f} ha, workable {summary['workable_ha']:.2f} ha) from {args.field}")
    print(f"  driving angle {summary['driving_angle_deg']:.1f} deg ({summary['driving_angle_how']}); order "
          f"{summary['order']}; {summary['headland_passes']} headland pass(es) of {args.width:g} m")
    print(f"  {summary['swaths']} swaths, {summary['turns']} turns; {summary['distance_m'] / 1000:.2f} km in all, "
          f"{summary['working_distance_m'] / 1000:.2f} km working, {summary['turn_distance_m'] / 1000:.2f} km turning; "
          f"about {summary['estimated_time_s'] / 3600:.2f} h")
    a = summary["as_applied"]
    print(f"  as applied ({f'{sections} sections' if sections else 'no section control'}): "
          f"{100 * a['field_coverage_share']:.2f} % of the whole field, {100 * a['coverage_share']:.2f} % of its "
          f"workable part, overlap {100 * a['overlap_share']:.2f} %, {a['boundary_crossings']} boundary crossing(s)")
    for note in summary["notes"]:
        print(f"  note: {note}")
    print(f"written as one set: {args.out}/route.csv ({rows} rows), " + ", ".join(FILES[1:]))
    return 0


def register(registry) -> None:
    registry.add_command("plan", "a coverage plan of a field: headland, swaths, turns, speeds (route.csv, .geojson, .png)",
                         add_arguments, run)
