"""The field-mission table (docs/field-missions.md): whole real fields covered by the guidance stack.

    python3 benchmarks/field_mission.py [--quick]

Each row runs a study to the end of its route (studies/field_*.toml, the field set with --set as
shown) and prints the farmers' figures (analysis.field_coverage) with the wall time of the whole
run (planning included) and how many times faster than real time it ran. --quick leaves out the
two largest fields. Fields from ../shared/realdata are skipped when it is not there.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.study import Study

ROOT = Path(__file__).resolve().parent.parent
REAL = next((p / "shared" / "realdata" for p in ROOT.parents if (p / "shared" / "realdata").is_dir()),
            ROOT.parent / "shared" / "realdata")
PARTFIELDS = REAL / "isoxml_dev4ag_timelogs" / "PARTFIELDS_TASKDATA.XML"
TASKDATA = REAL / "isoxml_dev4ag_timelogs" / "TASKDATA.XML"

# (label, study, overrides, in --quick)
ROWS = [
    ("IAM plot ro1-a, 2 m mounted, kinematic tracker", "field_plot_mounted.toml", (), True),
    ("IAM plot ro1-a, pure pursuit", "field_plot_pure_pursuit.toml", (), True),
    ("IAM plot ro1-a, Stanley", "field_plot_stanley.toml", (), True),
    ("F2C test parcel, 3 m trailed", "field_coverage.toml", (), True),
    ("TASKDATA euDZYo7 (a bay)", "field_coverage.toml", (f"field.path={TASKDATA}", "field.name=euDZYo7"), True),
    ("PARTFIELDS NO_Warschau_Simple at 2.5 m/s", "field_coverage.toml",
     (f"field.path={PARTFIELDS}", "field.name=NO_Warschau_Simple", "field.work_speed=2.5"), False),
    ("F2C test1.xml (17 ha)", "field_coverage.toml", (f"field.path={REAL / 'fields2cover_data' / 'test1.xml'}",), False),
]


def measure(study: str, overrides: tuple[str, ...]) -> tuple[dict, float]:
    t0 = time.perf_counter()
    m = run_study(Study.load(ROOT / "studies" / study, list(overrides)), None, plots=False).metrics
    return m, time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    head = (f"{'field / study':<46}{'ha':>6}{'swaths':>7}{'cover':>7}{'overlap':>8}{'cross':>6}{'P95 tr':>8}"
            f"{'P95 imp':>8}{'P2P95':>7}{'mission':>9}{'wall':>7}{'x real':>8}")
    measure("field_plot_mounted.toml", ("field.max_swaths=1", "field.headland_work=0"))    # warm up: imports
    print(head)
    print("-" * len(head))
    for label, study, overrides, quick in ROWS:
        if args.quick and not quick:
            continue
        if any(str(REAL) in o for o in overrides) and not REAL.exists():
            print(f"{label:<46} (skipped: ../shared/realdata is not here)")
            continue
        m, wall = measure(study, overrides)
        print(f"{label:<46}{m['field_area_m2'] / 1e4:>6.2f}{m['swaths_planned']:>7.0f}{m['coverage_share']:>7.3f}"
              f"{m['overlap_share']:>8.3f}{m['boundary_crossings']:>6.0f}{100 * m['tractor_xte_p95_m']:>6.1f}cm"
              f"{100 * m['implement_xte_p95_m']:>6.1f}cm{100 * m['pass_to_pass_p95_m']:>5.1f}cm"
              f"{m['mission_time_s'] / 3600:>8.2f}h{wall:>6.0f}s{m['mission_time_s'] / wall:>7.0f}x", flush=True)
    print("\ncover, overlap: shares of the workable area; cross: boundary crossings; P95 tr / imp: cross-track "
          "error on swaths of the tractor's CG / the implement; P2P95: pass-to-pass; mission: simulated time; "
          "wall: the whole run, planning included")


if __name__ == "__main__":
    main()
