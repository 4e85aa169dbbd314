"""How fast the figure-8 (studies/figure8.toml, 160 s simulated) runs: the Python engine on this tree
and on the code of another commit, and the compiled engine, in one run (the machine is shared:
every side sees the same load, the rounds interleave them).

    python benchmarks/engine_speed.py [--tree 295871d] [--repeat 5] [--no-tree] [--profile 12]

Two measures of the Python engine, each in a fresh process with PYTHONPATH the tree's ``src``:

- **CPU** (the target's figure): ``time.process_time`` of the engine from ``start`` to ``finish``
  (initialise, every base step, the signal table built; no interpreter start-up, no analysis, no
  writing), beside the wall time of the same span. CPU time is what the run costs: on a machine
  shared with other work the wall time also holds the time the process waited for a core. The
  figure is the process's first run, as a ``run`` command makes it; "run again" is the least CPU
  time of two more runs in that process (restarted: the same work without the first call's costs),
  the steadier figure on a busy machine.
- **command**: ``python -m agrobot run studies/figure8.toml --engine ENGINE --no-plots``, its run
  as metrics.json's ``wall_time_s`` (the same span, wall clock) and the whole command's wall time;
  the compiled engine is measured this way only.

Every figure is the median of ``--repeat`` rounds (the best beside it); the real-time factor is
160 s over the run's time. Start-up is the wall time of ``python -m agrobot --version``. The other
commit is unpacked by ``git archive`` into a temporary folder. Target: the Python engine at >= 500x
real time in CPU time (the median), on this tree. The output also says whether every Python run of
both trees recorded the same signal table, to the bit (a digest of its names and values).
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STUDY = "studies/figure8.toml"
TARGET = 500.0
SIM_TIME = 160.0
RUNS_IN_PROCESS = 3         # the first run is the figure; the others (restarted) give "again"

# the engine's span, timed inside a fresh process (the Simulation API of every tree since 24154ae)
IN_PROCESS = f"""
import hashlib, json, time
from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.engine import Simulation
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import load_study
sim = Simulation(build_system(resolve(load_study({STUDY!r}))))
runs = []
for _ in range({RUNS_IN_PROCESS}):
    cpu, wall = time.process_time(), time.perf_counter()
    sim.start()
    sim.advance(sim.n_steps)
    rec = sim.finish()
    runs.append((time.process_time() - cpu, time.perf_counter() - wall))
    sim.terminate()
digest = hashlib.sha256(repr(rec.columns).encode() + rec.data.tobytes()).hexdigest()
print(json.dumps({{"cpu": runs[0][0], "wall": runs[0][1], "again": min(c for c, _ in runs[1:]), "digest": digest}}))
"""


# the same span under cProfile: the functions that take the most time of their own
PROFILED = f"""
import cProfile, io, pstats, sys
from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.engine import Simulation
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import load_study
sim = Simulation(build_system(resolve(load_study({STUDY!r}))))
profile = cProfile.Profile()
profile.enable()
sim.start()
sim.advance(sim.n_steps)
sim.finish()
profile.disable()
sim.terminate()
text = io.StringIO()
pstats.Stats(profile, stream=text).sort_stats("tottime").print_stats(int(sys.argv[1]))
print(text.getvalue()[text.getvalue().index("   ncalls"):].replace(sys.path[0] if sys.path[0] else "", ""))
"""


def profile(tree: Path, lines: int) -> str:
    """The top ``lines`` of the Python engine's run under cProfile (own time), paths from the package."""
    done, _ = _python(tree, ["-c", PROFILED, str(lines)])
    if done.returncode != 0:
        raise SystemExit(f"{tree}: the profiled run exited {done.returncode}:\n{done.stderr[-2000:]}")
    return done.stdout.replace(str(tree / "src") + "/", "").rstrip()


def unpack(commit: str, folder: Path) -> Path:
    """The tree at ``commit`` (git archive), with its package's links to the top-level folders."""
    folder.mkdir(parents=True)
    archive = subprocess.run(["git", "archive", commit], cwd=ROOT, check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(folder)], input=archive, check=True)
    return folder


def _python(tree: Path, argv: list[str]) -> tuple[subprocess.CompletedProcess, float]:
    start = time.perf_counter()
    done = subprocess.run([sys.executable, *argv], cwd=tree, capture_output=True, text=True,
                          env={**os.environ, "PYTHONPATH": str(tree / "src")})
    return done, time.perf_counter() - start


def run_command(tree: Path, engine: str, out: Path) -> tuple[float, float]:
    """(the run's wall time from metrics.json, the command's wall time) of one figure-8 run."""
    done, wall = _python(tree, ["-m", "agrobot", "run", STUDY, "--engine", engine, "--no-plots", "--no-progress",
                                "--out", str(out), "--overwrite"])
    if done.returncode != 0:
        raise SystemExit(f"{tree}: run --engine {engine} exited {done.returncode}:\n{done.stderr[-2000:]}")
    metrics = json.loads((out / "metrics.json").read_text())
    if metrics.get("engine", "python") != engine:
        raise SystemExit(f"{tree}: --engine {engine} ran the {metrics.get('engine')} engine")
    return float(metrics["wall_time_s"]), wall


def run_in_process(tree: Path) -> tuple[float, float, float, str]:
    """(CPU time, wall time) of the Python engine's first run, timed inside its process, the least
    CPU time of the runs after it in that process, and a digest of its signal table (names and
    every bit of every value)."""
    done, _ = _python(tree, ["-c", IN_PROCESS])
    if done.returncode != 0:
        raise SystemExit(f"{tree}: the in-process run exited {done.returncode}:\n{done.stderr[-2000:]}")
    facts = json.loads(done.stdout.strip().splitlines()[-1])
    return float(facts["cpu"]), float(facts["wall"]), float(facts["again"]), facts["digest"]


def start_up(tree: Path) -> float:
    """Wall time of ``python -m agrobot --version`` with ``tree``'s code."""
    done, wall = _python(tree, ["-m", "agrobot", "--version"])
    if done.returncode != 0:
        raise SystemExit(f"{tree}: --version exited {done.returncode}: {done.stderr[-500:]}")
    return wall


def measure(trees: dict[str, Path], repeat: int, folder: Path) -> list[dict]:
    """One row per (tree, engine) with every round's figures; the rounds interleave the rows, so a
    change of load falls on all of them alike."""
    cases = [(name, tree, "python") for name, tree in trees.items()] + [("now", trees["now"], "compiled")]
    run_command(trees["now"], "compiled", folder / "warm")        # the loop compiled (or found in the cache)
    rows = {(name, engine): {"code": name, "engine": engine, "cpu": [], "wall": [], "again": [], "run": [],
                             "command": [], "start": [], "digests": set()} for name, _, engine in cases}
    for _ in range(repeat):
        for name, tree, engine in cases:
            row = rows[(name, engine)]
            if engine == "python":
                cpu, wall, again, digest = run_in_process(tree)
                row["digests"].add(digest)
                row["cpu"].append(cpu)
                row["wall"].append(wall)
                row["again"].append(again)
            run, command = run_command(tree, engine, folder / f"{name.split()[0]}_{engine}")
            row["run"].append(run)
            row["command"].append(command)
            row["start"].append(start_up(tree))
    return list(rows.values())


def _factor(times: list[float]) -> str:
    """The real-time factor of the median time, the best beside it."""
    if not times:
        return "-"
    return f"{SIM_TIME / statistics.median(times):.0f} ({SIM_TIME / min(times):.0f})"


def _seconds(times: list[float]) -> str:
    return f"{statistics.median(times):.3f}" if times else "-"


def table(rows: list[dict]) -> str:
    """Medians (best in brackets for the factors); the target judged on the median CPU factor."""
    lines = ["| code | engine | CPU [s] | x real time, CPU | wall [s] | x real time, wall | CPU, run again [s] | "
             "command's run [s] | x real time, command | start-up [s] | whole command [s] | target (CPU) |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        target = ""
        if r["engine"] == "python" and r["code"] == "now":
            factor = SIM_TIME / statistics.median(r["cpu"])
            target = f">= {TARGET:g}x: {'met' if factor >= TARGET else 'NOT met'} ({factor:.0f}x)"
        lines.append(f"| {r['code']} | {r['engine']} | {_seconds(r['cpu'])} | {_factor(r['cpu'])} | "
                     f"{_seconds(r['wall'])} | {_factor(r['wall'])} | {_seconds(r['again'])} | "
                     f"{_seconds(r['run'])} | {_factor(r['run'])} | "
                     f"{_seconds(r['start'])} | {_seconds(r['command'])} | {target} |")
    return "\n".join(lines)


def same_signals(rows: list[dict]) -> str:
    """Whether every Python run of every tree recorded the same signal table, to the bit."""
    digests = {name: r["digests"] for r in rows if r["engine"] == "python" for name in [r["code"]]}
    every = set().union(*digests.values())
    if len(every) == 1:
        return (f"signals: the same to the bit in every Python run of {' and '.join(digests)} "
                f"(sha256 {next(iter(every))[:16]})")
    return "signals: NOT the same: " + "; ".join(f"{name}: {', '.join(d[:16] for d in sorted(ds))}"
                                                  for name, ds in digests.items())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tree", default="295871d", help="the commit to compare with (default 295871d)")
    parser.add_argument("--no-tree", action="store_true", help="only the code of this tree")
    parser.add_argument("--repeat", type=int, default=5, help="rounds; each figure is their median (default 5)")
    parser.add_argument("--profile", type=int, default=0, metavar="LINES",
                        help="also print each tree's top LINES functions by own time under cProfile (default 0: none)")
    args = parser.parse_args()
    if args.repeat < 1:
        parser.error(f"--repeat {args.repeat}: expected at least 1")
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        before = {} if args.no_tree else {f"before ({args.tree})": unpack(args.tree, tmp / "before")}
        trees = {"now": ROOT, **before}
        rows = measure(trees, args.repeat, tmp)
        profiles = {name: profile(tree, args.profile) for name, tree in trees.items()} if args.profile > 0 else {}
    print(f"figure-8, {SIM_TIME:g} s simulated; the median of {args.repeat} rounds each, the best in brackets")
    print(table(rows))
    print(same_signals(rows))
    print("target: the Python engine on this tree at >= 500x real time in CPU time (the median; the engine from "
          "start to its table built, timed in its process); wall-clock figures move with the machine's load")
    print(f"(load average {load:.1f} at the start, {os.getloadavg()[0]:.1f} at the end, on {os.cpu_count()} cores)")
    for name, text in profiles.items():
        print(f"\nPython engine, {name}: the top {args.profile} functions by own time under cProfile "
              f"(the profiler slows each call: compare the lines, not with the table)\n{text}")


if __name__ == "__main__":
    main()
