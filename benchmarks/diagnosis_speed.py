"""How long ``identify`` and ``diagnose`` take against the log's duration, now and on the code before,
in one run (the machine is shared: both sides see the same load).

    python benchmarks/diagnosis_speed.py [--cases tractor f1tenth hour] [--before 1368bd1] [--no-before]
                                         [--cap 900]

Logs:

- ``tractor``: a 240 s log of the truth tractor (harness/truth_tractor.py, seed 1000, one hidden
  actuator delay, 20 Hz), against studies/figure8.toml;
- ``f1tenth``: the 39 s F1TENTH excerpt the documentation diagnoses (tests/data/f1tenth_frictionmaps DS5,
  converted as docs/hooks/quoted.py does), against studies/f1tenth.toml (no known truth);
- ``hour``: the truth tractor driven for an hour and logged at 100 Hz (seed 1000, one hidden actuator
  delay: 360,000 rows), against studies/figure8.toml.

Each command runs in a fresh process (``python -m agrobot``, PYTHONPATH the tree's ``src``) under
/usr/bin/time: wall seconds, CPU seconds of the process and its worker processes (sampled from /proc
every 0.1 s: on a shared machine the wall time follows the load, the CPU time the code), the peak
resident memory of its largest process, and the peak of the sum over the process and its workers. A command that
runs past ``--cap`` seconds is stopped and shown as ``> cap``. The code before is the commit
``--before`` unpacked by ``git archive`` into a temporary folder; the logs are generated into a
temporary folder and removed with it. For a log with a hidden effect the row says whether the
verdict names it (harness.hidden_effects.expected_ids); a second table gives each diagnosis's verdict
and fitted values with their 95 % intervals on each code, and whether the code before concluded the
same (the same effects, each value inside the other's interval). Targets (on two idle cores): the tractor log
diagnosed in 10 s, the excerpt in 15 s, the hour identified and diagnosed in 120 s together, peak
memory under 2 GB.
"""
from __future__ import annotations

import argparse
import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))                      # harness/ (the truth tractor)
TARGETS = {("tractor", "diagnose"): 10.0, ("f1tenth", "diagnose"): 15.0, ("hour", "identify + diagnose"): 120.0}
MEMORY_TARGET_MB = 2048.0
DS5 = ["--signal", "delta_cmd=commandData.delta[rad]", "--signal", "yaw_rate=imuData.wz[deg/s]",
       "--signal", "v=pfOdomData.vx[m/s]", "--signal", "x=pfOdomData.x[m]", "--signal", "y=pfOdomData.y[m]"]


def truth_log(folder: Path, name: str, duration: float, rate: float) -> tuple[Path, float, str, set]:
    """The truth tractor with one hidden actuator delay (seed 1000) for ``duration`` s at ``rate`` Hz."""
    from harness.hidden_effects import expected_ids
    from harness.truth_tractor import make_log

    frame, truth = make_log(1000, "actuator_delay", duration=duration, rate=rate)
    path = folder / f"{name}.parquet"
    frame.to_parquet(path)
    return path, float(frame["t"].iloc[-1] - frame["t"].iloc[0]), "studies/figure8.toml", expected_ids(truth)


def tractor_log(folder: Path) -> tuple[Path, float, str, set]:
    return truth_log(folder, "tractor_240s", 240.0, 20.0)


def f1tenth_log(folder: Path) -> tuple[Path, float, str, None]:
    import pandas as pd

    path = folder / "ds5.csv"
    subprocess.run([sys.executable, "-m", "agrobot", "convert", "tests/data/f1tenth_frictionmaps/DataSets/DS5",
                    *DS5, "--out", str(path), "--overwrite"], cwd=ROOT, check=True, capture_output=True,
                   env={**os.environ, "PYTHONPATH": str(ROOT / "src")})
    t = pd.read_csv(path)["t"]
    return path, float(t.iloc[-1] - t.iloc[0]), "studies/f1tenth.toml", None


def hour_log(folder: Path) -> tuple[Path, float, str, set]:
    return truth_log(folder, "tractor_hour_100hz", 3600.0, 100.0)


LOGS = {"tractor": tractor_log, "f1tenth": f1tenth_log, "hour": hour_log}


def tree_sample(pid: int) -> tuple[float, dict[int, float]]:
    """(the resident memory [MB] of ``pid`` and every process descending from it, the CPU seconds
    each of them has used so far), from /proc."""
    children: dict[int, list[int]] = {}
    rss: dict[int, float] = {}
    cpu: dict[int, float] = {}
    tick = os.sysconf("SC_CLK_TCK")
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        children.setdefault(int(fields[1]), []).append(int(entry))
        rss[int(entry)] = int(fields[21]) * os.sysconf("SC_PAGE_SIZE") / 2**20
        cpu[int(entry)] = (int(fields[11]) + int(fields[12])) / tick
    total, seen, todo = 0.0, {}, [pid]
    while todo:
        p = todo.pop()
        total += rss.get(p, 0.0)
        seen[p] = cpu.get(p, 0.0)
        todo += children.get(p, [])
    return total, seen


def timed(tree: Path, argv: list[str], cap: float) -> dict:
    """Wall and CPU seconds (the worker processes' too: their last sample) and peak memory (MB: the
    largest process, and the sum over the process tree) of ``python -m agrobot ARGV`` with ``tree``'s
    code; stopped after ``cap`` seconds."""
    start = time.perf_counter()
    proc = subprocess.Popen(["/usr/bin/time", "-f", "TIME %e %U %S %M", sys.executable, "-m", "agrobot", *argv],
                            cwd=tree, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "PYTHONPATH": str(tree / "src")}, start_new_session=True)
    peak, used, done = [0.0], {}, threading.Event()

    def sample() -> None:
        while not done.wait(0.1):
            mb, cpu = tree_sample(proc.pid)
            peak[0] = max(peak[0], mb)
            used.update(cpu)

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    try:
        out, err = proc.communicate(timeout=cap)
        capped = False
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)            # the command's own session: it and its workers
        out, err = proc.communicate()
        capped = True
    done.set()
    sampler.join()
    wall = time.perf_counter() - start
    last = [line for line in err.splitlines() if line.startswith("TIME ")]
    cpu, largest = (float(last[-1].split()[2]) + float(last[-1].split()[3]), float(last[-1].split()[4]) / 1024) \
        if last else (float("nan"), float("nan"))
    verdict = next((line for line in out.splitlines() if line.lower().startswith("verdict")), "")
    return {"wall": wall, "cpu": max(cpu, sum(used.values())), "peak_mb": largest, "tree_mb": peak[0], "capped": capped,
            "exit": proc.returncode, "verdict": verdict.strip()}


def named(out: Path, expected: set | None) -> str:
    """Whether the diagnosis at ``out`` names the hidden effects: 'yes', 'no (found ...)', or '-'."""
    if expected is None:
        return "-"
    try:
        result = json.loads((out / "diagnosis.json").read_text())
    except (OSError, ValueError):
        return "no result"
    found = {e["id"] for e in result.get("effects", [])}
    return "yes" if expected <= found and result.get("verdict") in expected else \
        f"no ({result.get('verdict')}; {'+'.join(sorted(found)) or 'none'})"


def concluded(out: Path) -> str:
    """What the diagnosis at ``out`` concluded: its verdict, and each effect's fitted values with their
    95 % intervals ('id: name value [lo, hi]'), for comparing two codes' results."""
    try:
        result = json.loads((out / "diagnosis.json").read_text())
    except (OSError, ValueError):
        return "no result"
    effects = [f"{e['id']}: " + ", ".join(f"{k} {q['value']:.4g} [{q['interval'][0]:.4g}, {q['interval'][1]:.4g}]"
                                          for k, q in (e.get("fitted") or {}).items())
               for e in result.get("effects", [])]
    return "; ".join([str(result.get("verdict"))] + effects)


def same_within_intervals(now: str, before: str) -> str:
    """'yes' when the two codes name the same verdict and effects, each value of one inside the
    other's 95 % interval; else 'no'."""
    def parsed(text: str):
        head, *effects = text.split("; ")
        values = {}
        for e in effects:
            eid, _, rest = e.partition(": ")
            for name, value, lo, hi in re.findall(r"(\S+) (\S+) \[(\S+), (\S+)\]", rest):
                values[(eid, name)] = (float(value), float(lo), float(hi))
        return head, values
    (v1, a), (v2, b) = parsed(now), parsed(before)
    inside = all(b[k][1] <= a[k][0] <= b[k][2] and a[k][1] <= b[k][0] <= a[k][2] for k in a if k in b)
    return "yes" if v1 == v2 and set(a) == set(b) and inside else "no"


def unpack(commit: str, folder: Path) -> Path:
    """The tree at ``commit`` (git archive), with its package's links to the top-level folders."""
    folder.mkdir(parents=True)
    archive = subprocess.run(["git", "archive", commit], cwd=ROOT, check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(folder)], input=archive, check=True)
    return folder


def measure(cases: list[str], before: str | None, cap: float) -> list[tuple]:
    """(case, log seconds, command, code, result) of identify, then diagnose, on each case's log, on
    this tree's code and on ``before``'s, and the two together for the hour."""
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        trees = {"now": ROOT, **({f"before ({before})": unpack(before, tmp / "before")} if before else {})}
        for case in cases:
            log, seconds, study, expected = LOGS[case](tmp)
            for name, tree in trees.items():
                both = []
                for command in ("identify", "diagnose"):
                    extra = ["--method", "driving"] if command == "identify" else []
                    out = tmp / f"{case}_{command}_{name.split()[0]}"
                    r = timed(tree, [command, str(log), "--study", str(ROOT / study), *extra, "--out", str(out),
                                     "--no-plots", "--no-progress"], cap)
                    r["named"] = named(out, expected) if command == "diagnose" else ""
                    r["concluded"] = concluded(out) if command == "diagnose" else ""
                    rows.append((case, seconds, command, name, r))
                    both.append(r)
                    print(f"{case} {command} {name}: {r['wall']:.1f} s wall{' (> cap)' if r['capped'] else ''}, "
                          f"{r['cpu']:.1f} s CPU, {r['peak_mb']:.0f} MB ({r['tree_mb']:.0f} MB with workers), "
                          f"exit {r['exit']} {r['verdict']}", file=sys.stderr, flush=True)
                if case == "hour":
                    rows.append((case, seconds, "identify + diagnose", name, {
                        "wall": sum(r["wall"] for r in both), "cpu": sum(r["cpu"] for r in both),
                        "peak_mb": max(r["peak_mb"] for r in both), "tree_mb": max(r["tree_mb"] for r in both),
                        "capped": any(r["capped"] for r in both), "exit": max(r["exit"] for r in both),
                        "named": both[1]["named"]}))
    return rows


def table(rows: list[tuple], cap: float) -> str:
    lines = ["| log | command | code | wall [s] | CPU with workers [s] | wall / log duration | peak memory [MB] (with workers) "
             "| names the hidden effect | target |",
             "|---|---|---|---:|---:|---:|---:|---|---|"]
    for case, seconds, command, name, r in rows:
        target = TARGETS.get((case, command))
        met = "" if target is None or not name.startswith("now") else \
            f"{target:g} s: {'met' if r['wall'] <= target and not r['capped'] else 'NOT met'}"
        if name.startswith("now") and (case, command) == ("hour", "identify + diagnose"):
            met += f"; {MEMORY_TARGET_MB:.0f} MB: {'met' if r['tree_mb'] <= MEMORY_TARGET_MB else 'NOT met'}"
        failed = "" if r["exit"] == 0 or r["capped"] else f" (exit {r['exit']})"
        wall = f"> {cap:.0f} (cap)" if r["capped"] else f"{r['wall']:.1f}"
        ratio = f"> {cap / seconds:.3f}" if r["capped"] else f"{r['wall'] / seconds:.3f}"
        lines.append(f"| {case} ({seconds:.0f} s) | {command}{failed} | {name} | {wall} | {r['cpu']:.1f} | {ratio} | "
                     f"{r['peak_mb']:.0f} ({r['tree_mb']:.0f}) | {r.get('named', '')} | {met} |")
    return "\n".join(lines)


def conclusions(rows: list[tuple]) -> str:
    """Each diagnosis's verdict and values with their intervals, on each code, and whether the other
    codes' agree with this tree's (the same effects, each value inside the other's interval)."""
    lines = ["| log | code | verdict; effect: value [95 % interval] | same as now |", "|---|---|---|---|"]
    now = {case: r["concluded"] for case, _, command, name, r in rows if command == "diagnose" and name == "now"}
    for case, _, command, name, r in rows:
        if command == "diagnose":
            same = "-" if name == "now" else same_within_intervals(now.get(case, ""), r["concluded"])
            lines.append(f"| {case} | {name} | {r['concluded'].replace('|', '/')} | {same} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", choices=tuple(LOGS), default=list(LOGS))
    parser.add_argument("--before", default="1368bd1", help="the commit to compare with (default 1368bd1)")
    parser.add_argument("--no-before", action="store_true", help="only the code of this tree")
    parser.add_argument("--cap", type=float, default=900.0,
                        help="seconds after which a command is stopped and shown as '> cap' (default 900)")
    args = parser.parse_args()
    load = os.getloadavg()[0]
    rows = measure(args.cases, None if args.no_before else args.before, args.cap)
    print(table(rows, args.cap))
    print(conclusions(rows))
    print(f"(load average {load:.1f} at the start, {os.getloadavg()[0]:.1f} at the end, on {os.cpu_count()} cores)")


if __name__ == "__main__":
    main()
