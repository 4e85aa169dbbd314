"""The margins of every shipped study with a guidance loop, predicted (analysis.margins) against the
steering command delay at which its simulation loses stability (bisection, two runs per delay: one
started 0.3 m aside; the loop holds when they come together).

    python3 benchmarks/margins.py [--studies figure8 figure8_stanley ...] [--duration S]

Columns: the whole loop opened at the steering command at the reference's first operating point
(gain margin, phase margin, crossover, delay margin), the delay limit from the closed-loop poles,
the simulated bracket, simulated / predicted. Takes 10-30 min (two 160 s runs per bisection step).
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

from agrobot.analysis.margins import analyse
from agrobot.analysis.margins_simulation import simulated_delay_limit
from agrobot.orchestrator.study import Study

ROOT = Path(__file__).resolve().parent.parent

STUDIES = ["figure8", "figure8_pure_pursuit", "figure8_stanley", "figure8_rlfr", "figure8_hardware_layout",
           "field_coverage", "field_plot_mounted", "field_plot_pure_pursuit", "field_plot_stanley"]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--studies", nargs="+", default=STUDIES)
    parser.add_argument("--duration", type=float, default=None, help="simulated seconds per run "
                        "(default 160 for the figure-8, 120 for the fields)")
    args = parser.parse_args()
    rows = []
    for name in args.studies:
        study = Study.load(ROOT / "studies" / f"{name}.toml")
        start = time.perf_counter()
        analysis = analyse(study)
        main_point = analysis.points[0]
        duration = args.duration or (120.0 if name.startswith("field") else 160.0)
        lo, hi, runs = simulated_delay_limit(study, analysis.anatomy, main_point.delay_limit, duration,
                                             progress=lambda line: print(f"{name}: {line.strip()}", flush=True))
        m = main_point.loops["whole loop"]
        rows.append((name, study.components[analysis.anatomy.tracker].type, f"{main_point.op.speed:g} m/s",
                     f"{m.gain:.2f}", f"{m.phase_deg:.1f}", f"{m.crossover:.2f}", f"{m.delay:.3f}",
                     f"{main_point.delay_limit:.2f}", f"{lo:.3f} .. {hi:.3f}",
                     f"{0.5 * (lo + hi) / main_point.delay_limit:.2f}" if math.isfinite(hi) else "n/a",
                     f"{time.perf_counter() - start:.0f}"))
    head = ("study", "tracker", "speed", "GM", "PM [deg]", "wc [rad/s]", "DM [s]", "limit [s]",
            "simulated [s]", "sim/pred", "wall [s]")
    widths = [max(len(str(r[i])) for r in rows + [head]) for i in range(len(head))]
    print()
    print("  ".join(h.ljust(w) for h, w in zip(head, widths)))
    print("  ".join("-" * w for w in widths))
    for r in rows:
        print("  ".join(str(c).ljust(w) for c, w in zip(r, widths)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
