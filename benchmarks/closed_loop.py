"""Closed-loop speed of the figure-8 study: simulated seconds per wall second and the share of
each component and of the orchestrator, from one profiled run and one plain run.

    python benchmarks/closed_loop.py [--study studies/figure8.toml]
"""
from __future__ import annotations

import argparse
import statistics
import time
from collections import defaultdict
from pathlib import Path

from orchestrator.build import build_system
from orchestrator.engine import Simulation
from orchestrator.study import load_study

ROOT = Path(__file__).resolve().parents[1]


def timed_components(system):
    """Wrap each component's step with a timer (for the share table)."""
    spent = defaultdict(float)
    for node in system.nodes.values():
        comp = node.component
        original = comp.step

        def wrapped(t, dt, _orig=original, _name=node.name):
            start = time.perf_counter()
            _orig(t, dt)
            spent[_name] += time.perf_counter() - start

        comp.step = wrapped
    return spent


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--study", type=Path, default=ROOT / "studies/figure8.toml")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    study = load_study(args.study)
    sim_time = study.study.stop_time - study.study.start_time

    cold = Simulation(build_system(study)).run().wall_time_s      # first run: imports, first calls
    warm = statistics.median(Simulation(build_system(study)).run().wall_time_s for _ in range(args.repeat))
    system = build_system(study)
    spent = timed_components(system)
    timed = Simulation(system).run().wall_time_s

    print(f"study {study.study.name}: {sim_time:.0f} s simulated (target: >= 200x real time)")
    print(f"{'run':<36}{'wall [s]':>10}{'x real time':>14}")
    print(f"{'cold (first run in the process)':<36}{cold:>10.3f}{sim_time / cold:>14.1f}")
    print(f"{f'warm (median of {args.repeat})':<36}{warm:>10.3f}{sim_time / warm:>14.1f}")
    print(f"{'warm, with per-component timers':<36}{timed:>10.3f}{sim_time / timed:>14.1f}")
    print()
    print("share of the warm run: component steps timed in the instrumented run, the orchestrator "
          "is the rest of the plain warm run (target: < 20%)")
    print(f"{'':<36}{'wall [s]':>10}{'share':>14}")
    for name, sec in sorted(spent.items(), key=lambda kv: -kv[1]):
        print(f"{name:<36}{sec:>10.3f}{100 * sec / warm:>13.1f}%")
    orchestrator = max(warm - sum(spent.values()), 0.0)
    print(f"{'orchestrator (rest)':<36}{orchestrator:>10.3f}{100 * orchestrator / warm:>13.1f}%")


if __name__ == "__main__":
    main()
