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

from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.engine import Simulation
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import load_study

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


def measure(study_path: Path = ROOT / "studies/figure8.toml", repeat: int = 3) -> dict:
    study = load_study(study_path)
    cold = Simulation(build_system(resolve(study))).run().wall_time_s      # first run: imports, first calls
    warm = statistics.median(Simulation(build_system(resolve(study))).run().wall_time_s for _ in range(repeat))
    system = build_system(resolve(study))
    spent = timed_components(system)
    timed = Simulation(system).run().wall_time_s
    return {"name": study.study.name, "sim_time": study.study.stop_time - study.study.start_time,
            "cold": cold, "warm": warm, "timed": timed, "repeat": repeat, "spent": dict(spent),
            "orchestrator": max(warm - sum(spent.values()), 0.0)}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--study", type=Path, default=ROOT / "studies/figure8.toml")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    r = measure(args.study, args.repeat)
    sim_time, warm = r["sim_time"], r["warm"]
    print(f"study {r['name']}: {sim_time:.0f} s simulated (target: >= 200x real time)")
    print(f"{'run':<36}{'wall [s]':>10}{'x real time':>14}")
    for label, key in (("cold (first run in the process)", "cold"), (f"warm (median of {r['repeat']})", "warm"),
                       ("warm, with per-component timers", "timed")):
        print(f"{label:<36}{r[key]:>10.3f}{sim_time / r[key]:>14.1f}")
    print()
    print("share of the warm run: component steps timed in the instrumented run, the orchestrator "
          "is the rest of the plain warm run (target: < 20%)")
    print(f"{'':<36}{'wall [s]':>10}{'share':>14}")
    for name, sec in sorted(r["spent"].items(), key=lambda kv: -kv[1]):
        print(f"{name:<36}{sec:>10.3f}{100 * sec / warm:>13.1f}%")
    print(f"{'orchestrator (rest)':<36}{r['orchestrator']:>10.3f}{100 * r['orchestrator'] / warm:>13.1f}%")


if __name__ == "__main__":
    main()
