"""How fast the figure-8 (studies/figure8.toml, 160 s simulated) runs: the Python engine on this tree
and on the code of another commit, and the compiled engine, in one run (the machine is shared:
every side sees the same load).

    python benchmarks/engine_speed.py [--tree 24154ae] [--repeat 5] [--no-tree]

Each run is ``python -m agrobot run studies/figure8.toml --engine ENGINE --no-plots`` in a fresh
process (PYTHONPATH the tree's ``src``); the run itself is metrics.json's ``wall_time_s`` (the
engine from its start to its last instant: no interpreter start-up, no analysis, no writing), the
best of ``--repeat`` runs, and the real-time factor is 160 s over it. Start-up is the wall time of
``python -m agrobot --version`` (the interpreter and the command line's imports), the best of
``--repeat``. The other commit is unpacked by ``git archive`` into a temporary folder. Target: the
Python engine at >= 500x real time on a quiet machine.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STUDY = "studies/figure8.toml"
TARGET = 500.0


def unpack(commit: str, folder: Path) -> Path:
    """The tree at ``commit`` (git archive), with its package's links to the top-level folders."""
    folder.mkdir(parents=True)
    archive = subprocess.run(["git", "archive", commit], cwd=ROOT, check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(folder)], input=archive, check=True)
    return folder


def _agrobot(tree: Path, argv: list[str]) -> tuple[subprocess.CompletedProcess, float]:
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "agrobot", *argv], cwd=tree, capture_output=True, text=True,
                          env={**os.environ, "PYTHONPATH": str(tree / "src")})
    return done, time.perf_counter() - start


def run_once(tree: Path, engine: str, out: Path) -> tuple[float, float]:
    """(the run's wall time from metrics.json, the command's wall time) of one figure-8 run."""
    done, wall = _agrobot(tree, ["run", STUDY, "--engine", engine, "--no-plots", "--no-progress", "--out", str(out),
                                 "--overwrite"])
    if done.returncode != 0:
        raise SystemExit(f"{tree}: run --engine {engine} exited {done.returncode}:\n{done.stderr[-2000:]}")
    metrics = json.loads((out / "metrics.json").read_text())
    if metrics.get("engine", "python") != engine:
        raise SystemExit(f"{tree}: --engine {engine} ran the {metrics.get('engine')} engine")
    return float(metrics["wall_time_s"]), wall


def start_up(tree: Path) -> float:
    """Wall time of ``python -m agrobot --version`` with ``tree``'s code."""
    done, wall = _agrobot(tree, ["--version"])
    if done.returncode != 0:
        raise SystemExit(f"{tree}: --version exited {done.returncode}: {done.stderr[-500:]}")
    return wall


def measure(trees: dict[str, Path], repeat: int, folder: Path) -> list[dict]:
    """One row per (tree, engine): best run, best command, best start-up over ``repeat`` rounds; the
    rounds interleave the rows, so a change of load falls on all of them alike."""
    cases = [(name, tree, "python") for name, tree in trees.items()] + [("now", trees["now"], "compiled")]
    run_once(trees["now"], "compiled", folder / "warm")           # the loop compiled (or found in the cache)
    best = {case[:1] + case[2:]: {"run": float("inf"), "command": float("inf"), "start": float("inf")} for case in cases}
    for _ in range(repeat):
        for name, tree, engine in cases:
            run, command = run_once(tree, engine, folder / f"{name.split()[0]}_{engine}")
            b = best[(name, engine)]
            b["run"], b["command"] = min(b["run"], run), min(b["command"], command)
            b["start"] = min(b["start"], start_up(tree))
    return [{"code": name, "engine": engine, **best[(name, engine)]} for name, _, engine in cases]


def table(rows: list[dict], sim_time: float = 160.0) -> str:
    lines = ["| code | engine | run [s] | x real time | start-up [s] | whole command [s] | target |",
             "|---|---|---:|---:|---:|---:|---|"]
    for r in rows:
        factor = sim_time / r["run"]
        target = f">= {TARGET:g}x: {'met' if factor >= TARGET else 'NOT met'}" \
            if r["engine"] == "python" and r["code"] == "now" else ""
        lines.append(f"| {r['code']} | {r['engine']} | {r['run']:.3f} | {factor:.0f} | {r['start']:.2f} | "
                     f"{r['command']:.2f} | {target} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tree", default="24154ae", help="the commit to compare with (default 24154ae)")
    parser.add_argument("--no-tree", action="store_true", help="only the code of this tree")
    parser.add_argument("--repeat", type=int, default=5, help="rounds; each row keeps its best (default 5)")
    args = parser.parse_args()
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        trees = {"now": ROOT, **({f"before ({args.tree})": unpack(args.tree, tmp / "before")} if not args.no_tree else {})}
        rows = measure(trees, args.repeat, tmp)
    print(f"figure-8, 160 s simulated; best of {args.repeat} runs each")
    print(table(rows))
    print(f"(load average {load:.1f} at the start, {os.getloadavg()[0]:.1f} at the end, on {os.cpu_count()} cores)")


if __name__ == "__main__":
    main()
