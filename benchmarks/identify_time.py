"""How long identification takes, as a user runs it.

1. The whole section-IV pipeline on a simulated experiment: the `identify` command in a fresh
   process (imports, simulated experiments, FRF, fits, validation, physical mapping, plots).
   Target: under 10 s.
2. ``--hour``: a one-hour log at 100 Hz of ordinary driving (the F1TENTH study simulated for an
   hour, its log holding the command only: t, delta_cmd, v, yaw_rate, x, y), identified
   (`identify --method driving`) and diagnosed (`diagnose`) in fresh processes, their progress
   lines shown. Target: under 2 minutes each; ``--minutes`` shorter logs show how the cost grows.

    python benchmarks/identify_time.py [--study studies/identification.toml] [--repeat 3]
    python benchmarks/identify_time.py --hour [--minutes 15 30 60]
    python benchmarks/identify_time.py --truth 5 [--trees /work/a /work/b] [--repeat 3]

3. ``--truth SEED``: a healthy generated tractor (harness.truth_tractor.make_log(SEED, duration=200 s),
   20 Hz) identified (`identify --method driving`) by each source tree of ``--trees`` in turn
   (PYTHONPATH=TREE/src; default this one), ``--repeat`` times, the same log for all: wall and CPU.
"""
from __future__ import annotations

import argparse
import os
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
            subprocess.run([sys.executable, "-m", "agrobot", "identify", str(study_path), "--out", out],
                           check=True, capture_output=True, cwd=ROOT)
            walls.append(time.perf_counter() - start)
    return {"study": study_path.name, "walls": walls, "median": statistics.median(walls)}


def long_log(minutes: float, folder: Path) -> Path:
    """The F1TENTH study driven for ``minutes`` at 100 Hz, as a command-only canonical log."""
    import pandas as pd

    from agrobot.orchestrator.runner import simulate
    from agrobot.orchestrator.study import Study

    seconds = 60.0 * minutes
    study = Study.load(ROOT / "studies/f1tenth.toml").with_values({"study.stop_time": seconds, "plan.duration": seconds})
    rec, _ = simulate(study)
    f = rec.to_frame()
    f = f.iloc[:: int(round(0.01 / study.study.base_step))].reset_index(drop=True)        # 100 Hz
    log = pd.DataFrame({"t": f["t"], "delta_cmd": f["plan.steer_angle_cmd"], "v": f["plan.speed_cmd"],
                        "yaw_rate": f["gyro.yaw_rate_measured"], "x": f["gps.x"], "y": f["gps.y"]})
    path = folder / f"drive_{minutes:g}min.parquet"
    log.to_parquet(path)
    return path


def timed(command: list[str]) -> tuple[float, float]:
    """(wall, CPU) seconds of the command in a fresh process (CPU: user + system of the child, which
    a shared machine's load does not inflate)."""
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    for line in proc.stdout.splitlines():
        if line.startswith("[") or line.startswith("verdict") or line.startswith("understeer") or "error" in line:
            print("    " + line)
    if proc.returncode not in (0,):
        print(f"    exit {proc.returncode}")
    return wall, cpu


def hour(minutes: list[float]) -> None:
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for m in minutes:
            path = long_log(m, Path(folder))
            print(f"{m:g} min log at 100 Hz ({int(m * 6000)} rows):")
            ident = timed([sys.executable, "-m", "agrobot", "identify", str(path), "--study", "studies/f1tenth.toml",
                           "--method", "driving", "--out", f"{folder}/ident", "--no-plots"])
            diag = timed([sys.executable, "-m", "agrobot", "diagnose", str(path), "--study", "studies/f1tenth.toml",
                          "--out", f"{folder}/diag", "--no-plots"])
            rows.append((m, ident, diag))
    print(f"\n(load average while measuring: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)")
    print("| log | identify wall [s] | identify CPU [s] | diagnose wall [s] | diagnose CPU [s] |\n|---|---:|---:|---:|---:|")
    for m, (iw, ic), (dw, dc) in rows:
        print(f"| {m:g} min at 100 Hz | {iw:.1f} | {ic:.1f} | {dw:.1f} | {dc:.1f} |")
    print("target: under 120 s each for the one-hour log")


def truth(seed: int, trees: list[Path], repeat: int) -> None:
    from harness.truth_tractor import make_log

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"tractor_{seed}.csv"
        make_log(seed, duration=200.0)[0].to_csv(path, index=False)
        times: dict[Path, list[tuple[float, float]]] = {tree: [] for tree in trees}
        for i in range(repeat):                 # trees alternate: the machine's load falls on each alike
            for k, tree in enumerate(trees):
                os.environ["PYTHONPATH"] = str(tree / "src")
                times[tree].append(timed([sys.executable, "-m", "agrobot", "identify", str(path), "--method", "driving",
                                          "--out", f"{folder}/ident_{i}_{k}", "--no-plots"]))
    print(f"\n(load average while measuring: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)")
    print(f"| tree | identify wall [s], median of {repeat} | identify CPU [s], median |\n|---|---:|---:|")
    for tree, rows in times.items():
        print(f"| {tree} | {statistics.median(w for w, _ in rows):.2f} | {statistics.median(c for _, c in rows):.2f} |")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--study", type=Path, default=ROOT / "studies/identification.toml")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--hour", action="store_true", help="time a one-hour 100 Hz driving log instead")
    parser.add_argument("--minutes", type=float, nargs="+", default=[60.0])
    parser.add_argument("--truth", type=int, help="time a generated tractor's log of this seed instead")
    parser.add_argument("--trees", type=Path, nargs="+", default=[ROOT], help="source trees to time (--truth)")
    args = parser.parse_args()
    if args.truth is not None:
        truth(args.truth, args.trees, args.repeat)
        return
    if args.hour:
        hour(args.minutes)
        return
    r = measure(args.study, args.repeat)
    print(f"identify {r['study']} (fresh process each): " + ", ".join(f"{w:.2f}" for w in r["walls"])
          + f" s; median {r['median']:.2f} s (target < 10 s)")


if __name__ == "__main__":
    main()
