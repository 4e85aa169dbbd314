"""How long ``identify`` and ``diagnose`` take against the log's duration, now and on the code before,
in one run (the machine is shared: both sides see the same load).

    python benchmarks/diagnosis_speed.py [--cases tractor f1tenth hour] [--before 1368bd1] [--no-before]

Logs:

- ``tractor``: a 240 s log of the truth tractor (harness/truth_tractor.py, seed 1000, one hidden
  actuator delay, 20 Hz), against studies/figure8.toml;
- ``f1tenth``: the 39 s F1TENTH excerpt the documentation diagnoses (tests/data/f1tenth_frictionmaps DS5,
  converted as docs/hooks/quoted.py does), against studies/f1tenth.toml;
- ``hour``: the F1TENTH study driven for an hour, logged at 100 Hz (benchmarks/identify_time.long_log).

Each command runs in a fresh process (``python -m agrobot``, PYTHONPATH the tree's ``src``) under
/usr/bin/time: wall and CPU seconds, and the peak resident memory. The code before is the commit
``--before`` unpacked by ``git archive`` into a temporary folder. Targets (on two idle cores): the
tractor log diagnosed in 10 s, the excerpt in 15 s, the hour identified and diagnosed in 120 s,
peak memory under 2 GB.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))                      # harness/ (the truth tractor)
sys.path.insert(0, str(ROOT / "benchmarks"))       # identify_time.long_log
TARGETS = {("tractor", "diagnose"): 10.0, ("f1tenth", "diagnose"): 15.0, ("hour", "identify"): 120.0,
           ("hour", "diagnose"): 120.0}
DS5 = ["--signal", "delta_cmd=commandData.delta[rad]", "--signal", "yaw_rate=imuData.wz[deg/s]",
       "--signal", "v=pfOdomData.vx[m/s]", "--signal", "x=pfOdomData.x[m]", "--signal", "y=pfOdomData.y[m]"]


def tractor_log(folder: Path) -> tuple[Path, float, str]:
    from harness.truth_tractor import make_log

    frame, _ = make_log(1000, "actuator_delay", duration=240.0)
    path = folder / "tractor_240s.parquet"
    frame.to_parquet(path)
    return path, float(frame["t"].iloc[-1] - frame["t"].iloc[0]), "studies/figure8.toml"


def f1tenth_log(folder: Path) -> tuple[Path, float, str]:
    import pandas as pd

    path = folder / "ds5.csv"
    subprocess.run([sys.executable, "-m", "agrobot", "convert", "tests/data/f1tenth_frictionmaps/DataSets/DS5",
                    *DS5, "--out", str(path), "--overwrite"], cwd=ROOT, check=True, capture_output=True,
                   env={**os.environ, "PYTHONPATH": str(ROOT / "src")})
    t = pd.read_csv(path)["t"]
    return path, float(t.iloc[-1] - t.iloc[0]), "studies/f1tenth.toml"


def hour_log(folder: Path) -> tuple[Path, float, str]:
    from identify_time import long_log

    return long_log(60.0, folder), 3600.0, "studies/f1tenth.toml"


LOGS = {"tractor": tractor_log, "f1tenth": f1tenth_log, "hour": hour_log}


def timed(tree: Path, argv: list[str]) -> dict:
    """Wall and CPU seconds and peak memory (MB) of ``python -m agrobot ARGV`` with ``tree``'s code."""
    start = time.perf_counter()
    proc = subprocess.run(["/usr/bin/time", "-f", "TIME %e %U %S %M", sys.executable, "-m", "agrobot", *argv],
                          cwd=tree, capture_output=True, text=True, env={**os.environ, "PYTHONPATH": str(tree / "src")})
    wall = time.perf_counter() - start
    last = [line for line in proc.stderr.splitlines() if line.startswith("TIME ")][-1].split()
    verdict = next((line for line in proc.stdout.splitlines() if line.lower().startswith("verdict")), "")
    return {"wall": wall, "cpu": float(last[2]) + float(last[3]), "peak_mb": float(last[4]) / 1024,
            "exit": proc.returncode, "verdict": verdict.strip()}


def unpack(commit: str, folder: Path) -> Path:
    """The tree at ``commit`` (git archive), with its package's links to the top-level folders."""
    folder.mkdir(parents=True)
    archive = subprocess.run(["git", "archive", commit], cwd=ROOT, check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(folder)], input=archive, check=True)
    return folder


def measure(cases: list[str], before: str | None) -> list[tuple]:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        trees = {"now": ROOT, **({f"before ({before})": unpack(before, tmp / "before")} if before else {})}
        for case in cases:
            log, seconds, study = LOGS[case](tmp)
            for command in ("identify", "diagnose"):
                extra = ["--method", "driving"] if command == "identify" else []
                for name, tree in trees.items():
                    out = tmp / f"{case}_{command}_{name.split()[0]}"
                    r = timed(tree, [command, str(log), "--study", str(ROOT / study), *extra, "--out", str(out),
                                     "--no-plots", "--no-progress"])
                    rows.append((case, seconds, command, name, r))
                    print(f"{case} {command} {name}: {r['wall']:.1f} s wall, {r['cpu']:.1f} s CPU, "
                          f"{r['peak_mb']:.0f} MB, exit {r['exit']} {r['verdict']}", file=sys.stderr, flush=True)
    return rows


def table(rows: list[tuple]) -> str:
    lines = ["| log | command | code | wall [s] | CPU [s] | wall / log duration | peak memory [MB] | target |",
             "|---|---|---|---:|---:|---:|---:|---|"]
    for case, seconds, command, name, r in rows:
        target = TARGETS.get((case, command))
        met = "" if target is None or not name.startswith("now") else \
            f"{target:g} s: {'met' if r['wall'] <= target else 'NOT met'}"
        failed = "" if r["exit"] == 0 else f" (exit {r['exit']})"
        lines.append(f"| {case} ({seconds:.0f} s) | {command}{failed} | {name} | {r['wall']:.1f} | {r['cpu']:.1f} | "
                     f"{r['wall'] / seconds:.3f} | {r['peak_mb']:.0f} | {met} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", choices=tuple(LOGS), default=list(LOGS))
    parser.add_argument("--before", default="1368bd1", help="the commit to compare with (default 1368bd1)")
    parser.add_argument("--no-before", action="store_true", help="only the code of this tree")
    args = parser.parse_args()
    load = os.getloadavg()[0]
    rows = measure(args.cases, None if args.no_before else args.before)
    print(table(rows))
    print(f"(load average {load:.1f} at the start, {os.getloadavg()[0]:.1f} at the end, on {os.cpu_count()} cores)")


if __name__ == "__main__":
    main()
