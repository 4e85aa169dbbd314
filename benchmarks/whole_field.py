"""The whole field, worked as planned, on every real field of ../shared/realdata up to --max-ha:
one line per field with its area, the share of the whole field covered, the overlap without and
with section control (--sections), the tractor's boundary crossings, the distance driven without
working (turns and transits) for each route order on one headland, and the plan's time; then the
time to plan 1,000 swaths (a 3,050 x 150 m strip worked across).

    python3 benchmarks/whole_field.py [--max-ha 30] [--sections 6] [--headland-corners tight] [--missions N]
        [--leftover-passes on|off] [--no-orders] [--files a.json,b.xml]

The plans work what their routes leave by passes of their own (fields.planner.leftover_passes;
--leftover-passes off leaves it); the idle distances by order leave those passes out. Each field's
leftovers (fields.planner.leftovers) are counted with their area and the largest
named with its kind. With --missions N the first N fields are also driven (studies/field_coverage.toml,
the guidance stack with the trailed implement and the same sections, a section of --mission-swaths
swaths without the headland, which a whole field's mission would take hours): the driven
whole-field coverage and overlap beside the plan's for the same section.

The areas are exact (shapely on the applied strips, fields.planner.applied); times are wall
seconds on a shared machine (CPU seconds beside them).
"""
from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

from shapely.geometry import Polygon

from agrobot.fields import FieldError, read_fields
from agrobot.fields.field import Field
from agrobot.fields.planner import Settings, plan
from agrobot.fields.planner.applied import as_applied, crossings
from agrobot.fields.planner.leftovers import leftovers
from agrobot.fields.planner.pipeline import idle_distance
from plan_every_field import FILES, REAL

ORDERS = ("boustrophedon", "skip", "optimised")


def one_field(field: Field, sections: int, corners: str, orders: bool = True, passes: bool = True) -> str:
    t0, c0 = time.perf_counter(), time.process_time()
    p = plan(field, Settings(headland_corners=corners, leftover_passes=passes))
    seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    whole, cut = as_applied(p), as_applied(p, sections)
    named, slivers = leftovers(p, whole.shape)
    big = named[0] if named else None
    left = (f"{len(named):>5}{100 * sum(x.area for x in named) / whole.field:>8.2f}{100 * slivers / whole.field:>7.2f}"
            f"  {(big.kind + f' {big.area:.0f} m2, {big.width:.1f} m wide') if big else '-':<34}")
    idle = _idle(field, p, corners) if orders else [f"{'-':>10}"] * len(ORDERS)
    return (f"{field.area_ha:>8.2f}{len(p.pieces):>4}{100 * whole.field_coverage_share:>9.2f}"
            f"{100 * whole.coverage_share:>8.2f}{100 * whole.overlap_share:>8.2f}{100 * cut.overlap_share:>8.2f}"
            f"{100 * cut.field_coverage_share:>8.2f}{crossings(p):>6}" + "".join(idle) + f"{seconds:>8.1f}{cpu:>7.1f}"
            + left)


def _idle(field: Field, p, corners: str) -> list[str]:
    """Metres driven without working for each route order on one headland (the leftovers' own passes left out)."""
    idle = []
    try:                          # one headland for every order: the widest the orders need
        n = max(p.headland_passes, plan(field, Settings(order="boustrophedon", headland_corners=corners,
                                                         leftover_passes=False)).headland_passes)
    except FieldError:
        n = p.headland_passes
    for order in ORDERS:
        try:
            q = plan(field, Settings(order=order, headland_passes=n, headland_corners=corners, leftover_passes=False))
            idle.append(f"{idle_distance(q.path.segments):>10.0f}")
        except FieldError:
            idle.append(f"{'refused':>10}")
    return idle


def mission(path: str, name: str, sections: int, swaths: int) -> str:
    """The driven section: whole-field coverage and overlap with the route's sections, beside the plan's."""
    from agrobot.orchestrator.runner import run_study
    from agrobot.orchestrator.study import Study

    study = Study.load(Path(__file__).resolve().parents[1] / "studies" / "field_coverage.toml",
                       [f"field.path={path}", f"field.name={name}", f"field.max_swaths={swaths}", "field.headland_work=0",
                        f"field.sections={sections}"])
    t0 = time.perf_counter()
    m = run_study(study, None, plots=False).metrics
    return (f"{100 * m['plan_field_coverage_share']:>9.3f}{100 * m['field_coverage_share']:>9.3f}"
            f"{100 * m['plan_field_overlap_share']:>9.3f}{100 * m['field_overlap_share']:>9.3f}"
            f"{m['applied_outside_m2']:>9.2f}{100 * m['implement_xte_p95_m']:>8.1f}{time.perf_counter() - t0:>8.0f}")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--max-ha", type=float, default=30.0, help="fields larger than this are listed, not planned")
    parser.add_argument("--sections", type=int, default=6)
    parser.add_argument("--headland-corners", default=Settings().headland_corners, choices=("tight", "parallel"))
    parser.add_argument("--leftover-passes", default="on", choices=("on", "off"),
                        help="work what the route leaves by passes of their own (fields.planner.leftover_passes)")
    parser.add_argument("--no-orders", action="store_true", help="leave out the idle distance by route order (3 more "
                        "plans per field)")
    parser.add_argument("--files", default="", help="comma-separated file names: plan only their fields (and not the "
                        "1,000 swaths)")
    parser.add_argument("--missions", type=int, default=0, help="drive a section of the first N fields")
    parser.add_argument("--mission-swaths", type=int, default=3)
    parser.add_argument("--no-plans", action="store_true", help="only the missions (with --missions)")
    parser.add_argument("--mission-files", default="", help="comma-separated file names: drive only their fields")
    args = parser.parse_args()
    print(f"{'file':<26}{'field':<24}{'ha':>8}{'pcs':>4}{'field %':>9}{'work %':>8}{'ovl %':>8}"
          f"{'ovl S %':>8}{'fld S %':>8}{'cross':>6}" + "".join(f"{o[:9]:>10}" for o in ORDERS) + f"{'plan s':>8}{'cpu s':>7}"
          f"{'left':>5}{'left %':>8}{'sliv %':>7}  largest leftover")
    print(f"{'':<58}(% of the whole field; S: with {args.sections} sections; idle m without working by order)")
    print(f"leftover passes {args.leftover_passes} (--leftover-passes {'off' if args.leftover_passes == 'on' else 'on'} "
          f"to {'leave' if args.leftover_passes == 'on' else 'work'} what the route leaves)")
    chosen = [w for w in args.files.split(",") if w]
    for name in [] if args.no_plans else [f for f in FILES if not chosen or any(f.endswith(w) for w in chosen)]:
        for field in read_fields(REAL / name):
            label = f"{name.split('/')[-1][:25]:<26}{field.name[:23]:<24}"
            if field.area_ha > args.max_ha:
                print(f"{label}{field.area_ha:>8.2f}  (larger than --max-ha {args.max_ha:g})", flush=True)
                continue
            try:
                print(label + one_field(field, args.sections, args.headland_corners, not args.no_orders,
                                        args.leftover_passes == "on"), flush=True)
            except FieldError as exc:
                print(f"{label}{field.area_ha:>8.2f}  refused: {str(exc).split(': ', 2)[-1][:100]}", flush=True)
    if args.missions:
        print(f"\nDriven sections ({args.mission_swaths} swaths, no headland, {args.sections} sections, "
              "studies/field_coverage.toml): % of the whole field")
        print(f"{'file':<26}{'field':<24}{'plan cov':>9}{'driven':>9}{'plan ovl':>9}{'driven':>9}{'out m2':>9}"
              f"{'impl P95':>8}{'wall s':>8}")
        done = 0
        wanted = [w for w in args.mission_files.split(",") if w]
        for name in [f for f in FILES if not wanted or any(f.endswith(w) for w in wanted)]:
            for field in read_fields(REAL / name):
                if done >= args.missions or field.area_ha > args.max_ha:
                    continue
                label = f"{name.split('/')[-1][:25]:<26}{field.name[:23]:<24}"
                try:
                    print(label + mission(str(REAL / name), field.name, args.sections, args.mission_swaths), flush=True)
                    done += 1
                except Exception as exc:             # noqa: BLE001 - a field the mission refuses is named, the rest go on
                    print(f"{label}  not driven: {str(exc).splitlines()[0][:100]}", flush=True)
    if args.no_plans or chosen:
        return
    strip = Field("1,000 swaths", Polygon([(0, 0), (3050, 0), (3050, 150), (0, 150)]), None, "generated", "local metres")
    for order in ("auto", "optimised"):
        t0, c0 = time.perf_counter(), time.process_time()
        p = plan(strip, Settings(order=order, driving_angle=math.pi / 2, headland_work=False))
        print(f"1,000 swaths: {len(p.swaths)} swaths, order {order}: planned in {time.perf_counter() - t0:.1f} s "
              f"({time.process_time() - c0:.1f} CPU s), {idle_distance(p.path.segments):.0f} m without working")


if __name__ == "__main__":
    main()
