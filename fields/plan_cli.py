"""``plan FIELD --out DIR``: a coverage plan of a field (fields.planner) written as one set:
route.csv (s, x, y, heading, curvature, speed, kind, index), route.geojson (longitude/latitude
where the field has a geographic reference), plan.json (swaths, turns, distances, estimated time,
angle and how it was chosen) and plan.png (the field, headland, swaths and turns).

The set is written into a new folder beside ``--out`` and swapped into place when all four are
complete: an interrupted or failed plan leaves ``--out`` as it was (an earlier plan, or nothing).
``--out`` must be new, empty, or a plan folder (it holds plan.json). Every setting is checked before
any work (finite, in range, a turn radius the field can hold), the message naming the option.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

from .planner.sampling import EXPORT_STEP, ROUTE_STEP
from .planner.settings import Settings

OPTIONS = {"working_width": "--width", "headland_passes": "--headland-passes", "driving_angle": "--angle",
           "guidance_line": "--guidance-line", "angle_objective": "--angle-objective", "turn_radius": "--turn-radius",
           "work_speed": "--work-speed", "turn_speed": "--turn-speed", "order": "--order",
           "hitch_offset": "--hitch-offset", "drawbar": "--drawbar", "settle": "--settle", "max_swaths": "--max-swaths"}
FILES = ("route.csv", "route.geojson", "plan.json", "plan.png")


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
    from .planner.objectives import OBJECTIVES

    p.add_argument("field", type=Path, help="a field file or folder (see the fields command)")
    p.add_argument("--out", type=Path, required=True, help="output folder (new, empty, or an earlier plan's)")
    p.add_argument("--crs", default=None, help="the coordinates' CRS when the file does not name it")
    p.add_argument("--name", default=None, help="the field to plan when the file holds several (default: the largest)")
    d = Settings()
    p.add_argument("--width", type=finite, default=d.working_width, help=f"working width [m] ({d.working_width:g})")
    p.add_argument("--headland-passes", type=int, default=d.headland_passes, help="0: as many as the turns need")
    p.add_argument("--angle", type=finite, default=None, help="driving angle [deg, east = 0, counter-clockwise] "
                   "(default: chosen by --angle-objective)")
    p.add_argument("--angle-objective", default=d.angle_objective, choices=sorted(OBJECTIVES),
                   help=f"how the driving angle is chosen ({d.angle_objective})")
    p.add_argument("--guidance-line", default="", metavar="NAME", help="drive along the field's guidance line "
                   "NAME (an AB line of an AgOpenGPS or ISOXML field; '*': its first)")
    p.add_argument("--turn-radius", type=finite, default=d.turn_radius, help=f"m ({d.turn_radius:g})")
    p.add_argument("--work-speed", type=finite, default=d.work_speed, help=f"m/s ({d.work_speed:g})")
    p.add_argument("--turn-speed", type=finite, default=d.turn_speed, help=f"m/s ({d.turn_speed:g})")
    p.add_argument("--order", default=d.order, choices=("auto", "boustrophedon", "skip"))
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


def read_field(args: argparse.Namespace):
    """(the field, why other files of a folder were not read)."""
    from .field import choose_field
    from .readers import read_fields, read_folder

    fields, skipped = read_folder(args.field, args.crs) if args.field.is_dir() else (read_fields(args.field, args.crs), [])
    return choose_field(fields, args.name, str(args.field)), skipped


def check_out(out: Path) -> None:
    """``--out`` must be new, empty, or an earlier plan (it is replaced whole)."""
    from orchestrator.output import OutputError

    if out.is_dir() and any(out.iterdir()) and not (out / "plan.json").exists():
        raise OutputError(f"--out {out}: the folder holds files that are not a plan (no plan.json), and a plan "
                          f"replaces the whole folder; choose a new or empty folder")


def run(args: argparse.Namespace) -> int:
    from orchestrator.output import ResultFolder, check_output
    from orchestrator.results import write_json

    from .field import FieldError
    from .planner import plan
    from .planner.export import draw_plan, write_route_csv, write_route_geojson

    check_output(args.out, overwrite=True)
    check_out(args.out)
    if not args.route_step > 0:
        raise FieldError(f"--route-step {args.route_step:g}: expected a positive number of metres")
    settings = Settings(working_width=args.width, headland_passes=args.headland_passes,
                        driving_angle=None if args.angle is None else math.radians(args.angle),
                        angle_objective=args.angle_objective, turn_radius=args.turn_radius, work_speed=args.work_speed,
                        turn_speed=args.turn_speed, order=args.order, hitch_offset=args.hitch_offset,
                        drawbar=args.drawbar, settle=args.settle, max_swaths=args.max_swaths,
                        guidance_line=args.guidance_line)
    settings.check("plan", OPTIONS)
    field, skipped = read_field(args)
    for why in skipped:
        print(f"not read: {why}")
    p = plan(field, settings)
    summary = p.summary() | {"not_read": skipped}
    with ResultFolder(args.out, overwrite=True) as folder:
        rows = write_route_csv(p, folder.tmp / "route.csv", args.route_step, args.route_uniform)
        write_route_geojson(p, folder.tmp / "route.geojson", args.route_step, args.route_uniform)
        write_json(folder.tmp / "plan.json", summary | {"route_rows": rows, "route_step_m": args.route_step,
                                                        "route_uniform": args.route_uniform})
        draw_plan(p, folder.tmp / "plan.png")
        folder.commit("completed")
    print(f"field {field.name!r} ({field.area_ha:.2f} ha, workable {summary['workable_ha']:.2f} ha) from {args.field}")
    print(f"  driving angle {summary['driving_angle_deg']:.1f} deg ({summary['driving_angle_how']}); order "
          f"{summary['order']}; {summary['headland_passes']} headland pass(es) of {settings.working_width:g} m")
    print(f"  {summary['swaths']} swaths, {summary['turns']} turns; {summary['distance_m'] / 1000:.2f} km in all, "
          f"{summary['working_distance_m'] / 1000:.2f} km working, {summary['turn_distance_m'] / 1000:.2f} km turning; "
          f"about {summary['estimated_time_s'] / 3600:.2f} h")
    for note in summary["notes"]:
        print(f"  note: {note}")
    print(f"written as one set: {args.out}/route.csv ({rows} rows), route.geojson, plan.json, plan.png")
    return 0


def register(registry) -> None:
    registry.add_command("plan", "a coverage plan of a field: headland, swaths, turns, speeds (route.csv, .geojson, .png)",
                         add_arguments, run)
