"""The yaw replay's cost per call under three discretisations, measured in one run, and whether this
tree's replays equal those of the code before (``python3 benchmarks/replay_hold_speed.py [--calls 40]
[--rounds 3] [--expm 93fb6f5] [--zoh 46e386f]``).

- ``zoh``: the zero-order hold (the step's mean input held; 46e386f, the commit before the first-order
  hold): the exponential of [[A, B], [0, 0]] h restricted to its top rows;
- ``expm``: the exact first-order hold as the full exponential of the augmented generator
  [[A, B, 0], [0, 0, I/h], [0, 0, 0]] h at each speed of the log (93fb6f5), in C (expm_stack) and in
  Python (expm_batched);
- ``now``: this tree, the same hold from the n x n block alone (identification/phi_step.h and its twin
  identification.driving.phi_steps: Pade for e^{hA}, Horner for h phi2(hA) B).

Logs (generated, read as the diagnosis reads them: identification.from_log.read_uneven with
resampling, then diagnosis.candidates.Replay; the line printed per log says what was judged): the
truth tractor (harness/truth_tractor.py, seed 1000, one hidden actuator delay, 240 s at 20 Hz; the
stretches its command does not explain are left out and the rest joined on one clock), and the same
log with its clock jittered (+-20 % of a row, uniform) and 2 % of its rows dropped in bursts of one
to five (read onto an even clock). On each: the yaw models bicycle, rlf and rlfr (diagnosis.replay.YawReplay on the replay's
wheel angle, speed and heading), each called ``--calls`` times with distinct values of the
parameters that enter the model nonlinearly (so every call discretises and recurses; the cache
never answers), in C and in Python. Each code runs in its own process (``git archive`` of the commit
into a temporary folder; PYTHONPATH that tree's ``src``) on the same arrays; the table gives CPU
milliseconds (user + sys of the process, over the calls) per call, the least of ``--rounds`` runs of
each code taken in turn (a shared machine's load falls on all three alike), and the largest relative difference
of this tree's yaw rates from ``expm``'s (max |now - expm| / max |expm| over each call's series).
"""
from __future__ import annotations

import argparse
import json
import os
import pickle
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MODELS, KERNELS = ("bicycle", "rlf", "rlfr"), ("c", "python")


def draws(calls: int, seed: int = 5) -> list[dict[str, float]]:
    """``calls`` sets of the yaw model's nonlinear values (seeded)."""
    rng = np.random.default_rng(seed)
    return [{"cornering_front_scale": float(rng.uniform(0.7, 1.3)), "cornering_rear_scale": float(rng.uniform(0.7, 1.3)),
             "cornering_speed_slope": float(rng.uniform(-0.1, 0.1)), "cornering_reference_speed": 2.0,
             "relaxation_scale": float(rng.uniform(0.6, 1.6))} for _ in range(calls)]


def child(job: Path) -> None:
    """Run in a tree's process: time every (log, model, kernel) and store the yaw rates."""
    import time

    from agrobot.diagnosis.pipeline import baseline_from_study, load_study
    from agrobot.diagnosis.replay import YawReplay, nonlinear, yaw_plant

    spec = pickle.loads(job.read_bytes())
    baseline = baseline_from_study(load_study(ROOT / "studies" / "figure8.toml"))
    times, rates = {}, {}
    for name, log in spec["logs"].items():
        for model in MODELS:
            for kernel in KERNELS:
                replay = YawReplay(model, baseline.tractor, log["h"], log["delta"], log["speed"], log["heading"],
                                   min_speed=log["min_speed"], kernel=kernel)
                sets = [{**baseline.values, **d} for d in spec["sets"]]
                replay.yaw_rate({**baseline.values})                 # compiles, and the parts of A and B
                start = time.process_time()
                out = [replay.yaw_rate(v) for v in sets]
                whole = (time.process_time() - start) / len(sets)
                start = time.process_time()
                for v in sets:
                    replay._discrete(*nonlinear(yaw_plant(v)))
                hold = (time.process_time() - start) / len(sets)
                key = f"{name}|{model}|{kernel}"
                times[key], rates[key] = (whole, hold), np.array(out)
    np.savez(job.with_suffix(".npz"), **rates)
    job.with_suffix(".json").write_text(json.dumps(times))


def logs(folder: Path) -> dict[str, dict]:
    """The two generated logs as the yaw replay sees them (arrays of candidates.Replay)."""
    from agrobot.diagnosis.candidates import Replay
    from agrobot.diagnosis.pipeline import baseline_from_study, load_study
    from agrobot.identification.from_log import read_uneven
    from harness.truth_tractor import make_log

    baseline = baseline_from_study(load_study(ROOT / "studies" / "figure8.toml"))
    frame, _ = make_log(1000, "actuator_delay", duration=240.0, rate=20.0)
    rng = np.random.default_rng(8)
    uneven = frame.copy()
    h = float(np.median(np.diff(frame["t"])))
    uneven["t"] = frame["t"] + rng.uniform(-0.2, 0.2, len(frame)) * h
    drop = np.zeros(len(frame), bool)
    for start in rng.choice(len(frame) - 5, int(0.02 * len(frame) / 3), replace=False):
        drop[start:start + rng.integers(1, 6)] = True
    drop[[0, -1]] = False
    out = {}
    for name, f in (("even", frame), ("uneven+dropouts", uneven[~drop].reset_index(drop=True))):
        path = folder / f"{name}.parquet"
        f.to_parquet(path)
        read, _, note = read_uneven(path, resample=True, causal=False)
        replay = Replay(read, baseline)
        out[name] = {"h": replay.h, "delta": replay.delta, "speed": replay.speed, "heading": replay.heading,
                     "min_speed": replay.min_speed, "rows": len(read), "note": note or ""}
    return out


def unpack(commit: str, folder: Path) -> Path:
    """The tree at ``commit`` (git archive)."""
    folder.mkdir(parents=True)
    archive = subprocess.run(["git", "archive", commit], cwd=ROOT, check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(folder)], input=archive, check=True)
    return folder


def relative(a: np.ndarray, b: np.ndarray) -> float:
    """max over calls of max |a - b| / max |b|."""
    return float(np.max(np.max(np.abs(a - b), axis=1) / np.max(np.abs(b), axis=1)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=40)
    parser.add_argument("--rounds", type=int, default=3, help="runs of each code, in turn; the least CPU is shown")
    parser.add_argument("--expm", default="93fb6f5", help="the full augmented exponential's commit (default 93fb6f5)")
    parser.add_argument("--zoh", default="46e386f", help="the zero-order hold's commit (default 46e386f)")
    parser.add_argument("--child", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        return child(args.child)
    sys.path[:0] = [str(ROOT / "src"), str(ROOT)]     # this tree's code and harness/ for the logs
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        spec = {"logs": logs(tmp), "sets": draws(args.calls)}
        trees = {"zoh": unpack(args.zoh, tmp / "zoh"), "expm": unpack(args.expm, tmp / "expm"), "now": ROOT}
        result: dict[str, tuple[dict, dict]] = {}
        for _ in range(args.rounds):                 # the codes in turn, each round: the least CPU of the rounds
            for code, tree in trees.items():
                job = tmp / f"{code}.pkl"
                job.write_bytes(pickle.dumps(spec))
                subprocess.run([sys.executable, str(Path(__file__).resolve()), "--child", str(job)], check=True,
                               env={**os.environ, "PYTHONPATH": f"{tree / 'src'}{os.pathsep}{ROOT}"})
                times = json.loads(job.with_suffix(".json").read_text())
                if code in result:
                    times = {k: [min(a, b) for a, b in zip(v, result[code][0][k])] for k, v in times.items()}
                result[code] = (times, dict(np.load(job.with_suffix(".npz"))))
    for name, log in spec["logs"].items():
        print(f"{name}: {log['rows']} rows at h = {log['h']:.4f} s{'; ' + log['note'] if log['note'] else ''}")
    print(f"\n{args.calls} calls each, least of {args.rounds} rounds; CPU ms per call (the discretisation alone "
          f"in brackets)\n")
    print("| log | model | kernel | zoh | expm (before) | now | now / expm | now / zoh | max rel. diff now vs expm |")
    print("|---|---|---|---:|---:|---:|---:|---:|---:|")
    for key in result["now"][0]:
        (z, zh), (e, eh), (n, nh) = (result[c][0][key] for c in ("zoh", "expm", "now"))
        diff = relative(result["now"][1][key], result["expm"][1][key])
        print(f"| {' | '.join(key.split('|'))} | {1e3 * z:.2f} ({1e3 * zh:.2f}) | {1e3 * e:.2f} ({1e3 * eh:.2f}) | "
              f"{1e3 * n:.2f} ({1e3 * nh:.2f}) | {n / e:.2f} | {n / z:.2f} | {diff:.1e} |")
    print(f"\n(load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)")


if __name__ == "__main__":
    main()
