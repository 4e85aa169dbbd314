"""The whole section-IV pipeline on a simulated experiment, as a user runs it: the
`identify` command in a fresh process (imports, simulated experiments, FRF, fits, validation,
physical mapping, plots). Target: under 10 s.

    python benchmarks/identification.py [--study studies/identification.toml] [--repeat 3]
"""
from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def measure(study_path: Path = ROOT / "studies/identification.toml", repeat: int = 3) -> dict:
    walls = []
    for _ in range(repeat):
        with tempfile.TemporaryDirectory() as out:
            start = time.perf_counter()
            subprocess.run([sys.executable, "-m", "orchestrator", "identify", str(study_path), "--out", out],
                           check=True, capture_output=True, cwd=ROOT)
            walls.append(time.perf_counter() - start)
    return {"study": study_path.name, "walls": walls, "median": statistics.median(walls)}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--study", type=Path, default=ROOT / "studies/identification.toml")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    r = measure(args.study, args.repeat)
    print(f"identify {r['study']} (fresh process each): " + ", ".join(f"{w:.2f}" for w in r["walls"])
          + f" s; median {r['median']:.2f} s (target < 10 s)")


if __name__ == "__main__":
    main()
