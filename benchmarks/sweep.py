"""Sweep throughput: points per second with 1 and 2 workers on the shipped speed sweep.

    python benchmarks/sweep.py [--stop-time 160]
"""
from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from agrobot.orchestrator.study import Study
from agrobot.orchestrator.sweep import SweepRun

ROOT = Path(__file__).resolve().parents[1]


def measure(study_path: Path = ROOT / "studies/speed_sweep.toml", stop_time: float | None = None) -> dict:
    """Wall time of the whole sweep with 1 and 2 worker processes (fresh output folders)."""
    overrides = [f"study.stop_time={stop_time}"] if stop_time else []
    study = Study.load(study_path, overrides)
    rows = []
    for workers in (1, 2):
        with tempfile.TemporaryDirectory() as out:
            start = time.perf_counter()
            table = SweepRun(study, Path(out)).run(workers, progress=False)
            wall = time.perf_counter() - start
        rows.append((workers, len(table), wall, len(table) / wall))
    return {"name": study.study.name, "stop_time": study.study.stop_time, "rows": rows}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--study", type=Path, default=ROOT / "studies/speed_sweep.toml")
    parser.add_argument("--stop-time", type=float, default=None, help="shorten each point's run")
    args = parser.parse_args()
    r = measure(args.study, args.stop_time)
    rows = r["rows"]
    print(f"sweep {r['name']}: {rows[0][1]} points, {r['stop_time']:.0f} s simulated each")
    print(f"{'workers':>8}{'points':>8}{'wall [s]':>10}{'points/s':>10}{'speed-up':>10}")
    for workers, n, wall, rate in rows:
        print(f"{workers:>8}{n:>8}{wall:>10.2f}{rate:>10.3f}{rate / rows[0][3]:>10.2f}")


if __name__ == "__main__":
    main()
