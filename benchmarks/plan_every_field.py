"""Plan every field of ../shared/realdata whole: one line per field with its area, the planning
time, the route's length and estimated time, swaths, headland passes, the share of the workable
area the plan's working strips cover and overlap, order, driving angle and the planner's notes,
or the reason it is refused.

    python3 benchmarks/plan_every_field.py [--width 3] [--turn-radius 4]

About 10 minutes on the 2-core machine (the 664 ha Nowosibirsk partfield alone takes 1.5).
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

from agrobot.fields import FieldError, read_fields
from agrobot.fields.planner import Settings, plan

REAL = next((p / "shared" / "realdata" for p in Path(__file__).resolve().parents if (p / "shared" / "realdata").is_dir()),
            Path("../shared/realdata"))
FILES = ["fields2cover_data/Envelope.xml", "fields2cover_data/envelope1.xml", "fields2cover_data/strips.geojson",
         "fields2cover_data/test.json", "fields2cover_data/test1.xml", "fields2cover_data/test_2_cell.json",
         "fields2cover_data/test_ring.json", "iam_field_open_autonomous_tractor/datasets/iam_field/field_boundaries.csv",
         "isoxml_dev4ag_timelogs/PARTFIELDS_TASKDATA.XML", "isoxml_dev4ag_timelogs/TASKDATA.XML"]


def planned_cover(p) -> tuple[float, float]:
    """(covered, overlap) shares of the workable area by the plan's own working strips (swaths and
    headland passes, the working width about the implement's line: fields.planner.applied)."""
    from agrobot.fields.planner.applied import areas, working_strips

    a = areas(working_strips(p), p.workable, p.workable)
    return a.covered / p.workable.area, a.overlap / p.workable.area


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--width", type=float, default=Settings().working_width)
    parser.add_argument("--turn-radius", type=float, default=Settings().turn_radius)
    args = parser.parse_args()
    settings = Settings(working_width=args.width, turn_radius=args.turn_radius)
    planned = refused = 0
    print(f"{'file':<34}{'field':<32}{'ha':>8}{'plan s':>8}{'km':>8}{'h':>7}{'swaths':>7}{'hl':>4}{'cover':>7}{'overlap':>8}  order / angle / notes")
    for name in FILES:
        for field in read_fields(REAL / name):
            t0 = time.perf_counter()
            try:
                p = plan(field, settings)
                s = p.summary()
                seconds = time.perf_counter() - t0
            except FieldError as exc:
                refused += 1
                print(f"{name.split('/')[-1]:<34}{field.name[:31]:<32}{field.area_ha:>8.2f}{time.perf_counter() - t0:>8.1f}"
                      f"  refused: {str(exc).split(': ', 2)[-1]}", flush=True)
                continue
            planned += 1
            cover, overlap = planned_cover(p)
            print(f"{name.split('/')[-1]:<34}{field.name[:31]:<32}{field.area_ha:>8.2f}{seconds:>8.1f}"
                  f"{s['distance_m'] / 1000:>8.2f}{s['estimated_time_s'] / 3600:>7.2f}{s['swaths']:>7}{s['headland_passes']:>4}{cover:>7.4f}{overlap:>8.4f}  {s['order']}, {s['driving_angle_deg']:.0f} deg"
                  f"{'; ' + '; '.join(s['notes']) if s['notes'] else ''}", flush=True)
    print(f"\n{planned} planned, {refused} refused")


if __name__ == "__main__":
    main()
