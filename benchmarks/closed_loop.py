"""Closed-loop speed of the figure-8 study: simulated seconds per wall second and the share of
each component and of the orchestrator, from one profiled run and one plain run.

    python benchmarks/closed_loop.py [--study studies/figure8.toml]
"""
from __future__ import annotations

import argparse
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
    args = parser.parse_args()
    study = load_study(args.study)
    sim_time = study.study.stop_time - study.study.start_time

    plain = Simulation(build_system(study)).run().wall_time_s
    system = build_system(study)
    spent = timed_components(system)
    total = Simulation(system).run().wall_time_s

    print(f"study {study.study.name}: {sim_time:.0f} s simulated")
    print(f"{'run':<28}{'wall [s]':>10}{'x real time':>14}")
    print(f"{'plain':<28}{plain:>10.3f}{sim_time / plain:>14.1f}")
    print(f"{'with per-component timers':<28}{total:>10.3f}{sim_time / total:>14.1f}")
    print()
    print(f"{'share of the timed run':<28}{'wall [s]':>10}{'share':>14}")
    for name, s in sorted(spent.items(), key=lambda kv: -kv[1]):
        print(f"{name:<28}{s:>10.3f}{100 * s / total:>13.1f}%")
    orchestrator = total - sum(spent.values())
    print(f"{'orchestrator (rest)':<28}{orchestrator:>10.3f}{100 * orchestrator / total:>13.1f}%")


if __name__ == "__main__":
    main()
