"""Closed-loop speed of the figure-8 study with the Python engine: simulated seconds per wall second,
with the BLAS libraries limited to one thread during the run (the engine's default, threadpoolctl)
and with their default thread pools, on this machine as it is and with two processes spinning
beside (a loaded machine), in-process and through ``python -m agrobot run``; then the share of
each component and of the orchestrator, from one run with per-component timers.

    python benchmarks/closed_loop.py [--study studies/figure8.toml] [--repeat 3] [--no-load]
"""
from __future__ import annotations

import argparse
import contextlib
import json
import statistics
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

from agrobot.orchestrator import engine as engine_module
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


class _NoLimit:
    """Stands in for threadpoolctl's limit: the BLAS libraries keep their default thread pools."""

    def __init__(self, *args, **kwargs) -> None:
        pass

    def restore_original_limits(self) -> None:
        pass


@contextlib.contextmanager
def blas_threads(limited: bool):
    original = engine_module.threadpool_limits
    if not limited:
        engine_module.threadpool_limits = _NoLimit
    try:
        yield
    finally:
        engine_module.threadpool_limits = original


@contextlib.contextmanager
def spinning(n: int):
    """``n`` processes spinning on the CPU while the block runs (a loaded machine)."""
    procs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(n)]
    try:
        time.sleep(0.5)
        yield
    finally:
        for p in procs:
            p.kill()
            p.wait()


def warm(study, repeat: int, limited: bool) -> float:
    with blas_threads(limited):
        return statistics.median(Simulation(build_system(resolve(study))).run().wall_time_s for _ in range(repeat))


def measure(study_path: Path = ROOT / "studies/figure8.toml", repeat: int = 3) -> dict:
    """The figures benchmarks/all.py reports: cold and warm runs, per-component time (BLAS 1 thread)."""
    study = load_study(study_path)
    cold = Simulation(build_system(resolve(study))).run().wall_time_s
    warm_s = warm(study, repeat, True)
    system = build_system(resolve(study))
    spent = timed_components(system)
    timed = Simulation(system).run().wall_time_s
    return {"name": study.study.name, "sim_time": study.study.stop_time - study.study.start_time,
            "cold": cold, "warm": warm_s, "timed": timed, "repeat": repeat, "spent": dict(spent),
            "orchestrator": max(warm_s - sum(spent.values()), 0.0)}


def through_run(study_path: Path, threads: str | None) -> float:
    """wall_time_s of ``python -m agrobot run`` (metrics.json); ``threads``: OPENBLAS_NUM_THREADS."""
    import os

    env = dict(os.environ)
    if threads is not None:
        env["OPENBLAS_NUM_THREADS"] = threads
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([sys.executable, "-m", "agrobot", "run", str(study_path), "--out", f"{tmp}/r", "--no-plots",
                        "--engine", "python"],
                       check=True, capture_output=True, env=env)
        return json.loads(Path(f"{tmp}/r/metrics.json").read_text())["wall_time_s"]


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--study", type=Path, default=ROOT / "studies/figure8.toml")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--no-load", action="store_true", help="skip the rows with two spinning processes")
    args = parser.parse_args()
    study = load_study(args.study)
    sim_time = study.study.stop_time - study.study.start_time
    cold = Simulation(build_system(resolve(study))).run().wall_time_s      # first run: imports, first calls
    rows = [("cold (first run in the process)", "", cold)]
    loads = [0] if args.no_load else [0, 2]
    for load in loads:
        with spinning(load):
            for limited in (False, True):
                label = f"warm, median of {args.repeat}"
                rows.append((label, f"{'+2 spinning' if load else 'as is'}, BLAS {'1 thread' if limited else 'default'}",
                             warm(study, args.repeat, limited)))
            rows.append(("python -m agrobot run", f"{'+2 spinning' if load else 'as is'}, BLAS 1 thread",
                         through_run(args.study, None)))
    print(f"study {study.study.name}: {sim_time:.0f} s simulated (target: >= 507x real time, the speed of the wave "
          f"before the observers; a loaded machine within 30 % of the same machine as is)")
    print(f"{'run':<34}{'machine, BLAS threads':<30}{'wall [s]':>10}{'x real time':>14}")
    for label, where, wall in rows:
        print(f"{label:<34}{where:<30}{wall:>10.3f}{sim_time / wall:>14.1f}")

    system = build_system(resolve(study))
    spent = timed_components(system)
    timed = Simulation(system).run().wall_time_s
    plain = [w for label, where, w in rows if where == "as is, BLAS 1 thread" and label.startswith("warm")][0]
    print()
    print(f"share of the warm run ({plain:.3f} s, BLAS 1 thread): component steps timed in an instrumented run "
          f"({timed:.3f} s), the orchestrator is the rest of the plain warm run (target: < 20%)")
    print(f"{'':<36}{'wall [s]':>10}{'share':>14}")
    for name, sec in sorted(spent.items(), key=lambda kv: -kv[1]):
        print(f"{name:<36}{sec:>10.3f}{100 * sec / plain:>13.1f}%")
    rest = max(plain - sum(spent.values()), 0.0)
    print(f"{'orchestrator (rest)':<36}{rest:>10.3f}{100 * rest / plain:>13.1f}%")


if __name__ == "__main__":
    main()
