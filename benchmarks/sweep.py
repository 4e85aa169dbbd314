"""Sweep throughput: points per second with 1 and 2 workers on the shipped speed sweep.

    python benchmarks/sweep.py [--stop-time 160]
"""
from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from orchestrator.study import load_raw, parse_study
from orchestrator.sweep import SweepRun

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--study", type=Path, default=ROOT / "studies/speed_sweep.toml")
    parser.add_argument("--stop-time", type=float, default=None, help="shorten each point's run")
    args = parser.parse_args()
    overrides = [f"study.stop_time={args.stop_time}"] if args.stop_time else []
    raw = load_raw(args.study, overrides)
    study = parse_study(raw, args.study)
    rows = []
    for workers in (1, 2):
        with tempfile.TemporaryDirectory() as out:
            start = time.perf_counter()
            table = SweepRun(study, raw, Path(out)).run(workers, progress=False)
            wall = time.perf_counter() - start
        rows.append((workers, len(table), wall, len(table) / wall))
    print(f"sweep {study.study.name}: {rows[0][1]} points, {study.study.stop_time:.0f} s simulated each")
    print(f"{'workers':>8}{'points':>8}{'wall [s]':>10}{'points/s':>10}{'speed-up':>10}")
    for workers, n, wall, rate in rows:
        print(f"{workers:>8}{n:>8}{wall:>10.2f}{rate:>10.3f}{rate / rows[0][3]:>10.2f}")


if __name__ == "__main__":
    main()
