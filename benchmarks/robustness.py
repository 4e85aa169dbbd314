"""Monte Carlo robustness of the figure-8 guidance for the paper's tracker + MPC and the two
baselines: 200 seeded runs each on the sweep machinery, one table, one figure.

    python3 benchmarks/robustness.py [--out results/robustness] [--samples 200] [--workers 2]

Prints P50 / P95 / max of both max errors, the fraction within the paper's bounds and the wall
time (target: 200 runs within 2 minutes on the 2-core machine); writes each study's sweep folder
and max_error_vs_delay.png comparing the three.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

from agrobot.analysis.robustness import compare, summarise
from agrobot.orchestrator.study import Study
from agrobot.orchestrator.sweep import SweepRun, sweep_plots

ROOT = Path(__file__).resolve().parent.parent
STUDIES = {"kinematic + MPC (shipped)": "robustness.toml", "pure pursuit + MPC": "robustness_pure_pursuit.toml",
           "Stanley + MPC": "robustness_stanley.toml"}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "robustness")
    parser.add_argument("--samples", type=int, default=200)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    tables, rows = {}, []
    for label, name in STUDIES.items():
        study = Study.load(ROOT / "studies" / name, [f"sweep.samples={args.samples}"])
        out = args.out / study.study.name
        start = time.perf_counter()
        table = SweepRun(study, out).run(args.workers, progress=False)
        wall = time.perf_counter() - start
        sweep_plots(study, table, out / "plots")
        tables[label] = table
        rows.append((label, summarise(table), wall))
    print(f"{'tracker':<28}{'runs':>5}{'straight P50/P95/max [m]':>28}{'curved P50/P95/max [m]':>26}"
          f"{'in bounds':>11}{'(delay<=0.1)':>14}{'wall [s]':>10}")
    for label, s, wall in rows:
        st, cu = s["euclid_max_straight"], s["euclid_max_curved"]
        print(f"{label:<28}{s['runs']:>5}{st['p50']:>12.2f}{st['p95']:>8.2f}{st['max']:>8.2f}"
              f"{cu['p50']:>10.2f}{cu['p95']:>8.2f}{cu['max']:>8.2f}{s['within_bounds']:>11.0%}"
              f"{s['within_bounds_delay_le_0.1s']:>14.0%}{wall:>10.1f}")
    print(f"figure: {compare(tables, args.out / 'max_error_vs_delay.png')}")


if __name__ == "__main__":
    main()
