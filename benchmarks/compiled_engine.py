"""The compiled engine against the Python engine, for every shipped study the compiled engine takes:
the time of one run each (after the compiled shape is cached), the agreement of the signals with
noise off (the steering potentiometer's quantisation off, then on), the agreement of the metrics'
distributions with noise on (two-sample Kolmogorov-Smirnov over seeded draws, 1 %), and the
robustness Monte Carlo of many draws: wall time and peak memory of the sweep command.

    python benchmarks/compiled_engine.py [--ks-draws 1000] [--ks-stop-time 160] [--draws 10000]
                                         [--skip-sweep] [--skip-ks]
"""
from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.compiled import CompiledSimulation, cores_of
from agrobot.orchestrator.compiled.simulation import refusal
from agrobot.orchestrator.engine import Simulation
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study
from agrobot.studies import shipped

QUIET = ["gps.position_noise_std=0", "gps.velocity_noise_std=0"]
NO_QUANTISATION = ["steering.potentiometer_resolution=0"]


def base(name: str, overrides=()) -> Study:
    study = Study.load(shipped(name), list(overrides))
    return study.without("sweep") if study.sweep is not None else study


def taken() -> list[str]:
    names = []
    for path in sorted(Path(shipped("figure8.toml")).parent.glob("*.toml")):
        try:
            system = build_system(resolve(base(path.name)))
        except Exception:      # noqa: BLE001 - a study this machine cannot build (a device) is not taken
            continue
        if not refusal(system, cores_of(system)[1]):
            names.append(path.name)
    return names


def timed(factory, study: Study):
    system = build_system(resolve(study))
    began = time.perf_counter()
    rec = factory(system).run()
    return rec, time.perf_counter() - began


def worst(a, b) -> float:
    scale = np.maximum(np.abs(b.data).max(axis=0), 1e-12)
    return float((np.abs(a.data - b.data).max(axis=0) / scale).max())


def metrics_of(study: Study, rec) -> dict:
    from agrobot.orchestrator.runner import _analysis, _metrics

    return _metrics(_analysis(study), rec.to_frame(), study)


def ks_rows(name: str, draws: int, stop_time: float) -> list[tuple[str, float, float]]:
    """(metric, KS statistic, p-value) over ``draws`` seeds per engine (noise on)."""
    from scipy.stats import ks_2samp

    per = {"python": [], "compiled": []}
    for seed in range(draws):
        study = base(name, [f"study.seed={seed}", f"study.stop_time={stop_time}"])
        for engine, factory in (("python", Simulation), ("compiled", CompiledSimulation)):
            per[engine].append(metrics_of(study, timed(factory, study)[0]))
    keys = [k for k in per["python"][0] if isinstance(per["python"][0][k], float)]
    rows = []
    for k in keys:
        a = np.array([m[k] for m in per["python"]])
        b = np.array([m[k] for m in per["compiled"]])
        res = ks_2samp(a, b)
        rows.append((k, float(res.statistic), float(res.pvalue)))
    return rows


def sweep(draws: int) -> tuple[float, float, float, str]:
    """(wall s, CPU s of every process of the command, peak RSS of the largest process MiB, the
    summary's first line) of the robustness sweep."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    with tempfile.TemporaryDirectory() as tmp:
        began = time.perf_counter()
        done = subprocess.run([sys.executable, "-m", "agrobot", "sweep", str(shipped("robustness.toml")), "--set",
                               f"sweep.samples={draws}", "--out", f"{tmp}/mc", "--engine", "compiled", "--no-plots",
                               "--no-progress"], capture_output=True, text=True)
        wall = time.perf_counter() - began
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    line = next((ln for ln in done.stdout.splitlines() if "points," in ln), done.stderr.strip()[-200:])
    return wall, cpu, after.ru_maxrss / 1024, line


def main() -> None:
    warnings.simplefilter("ignore")
    parser = argparse.ArgumentParser()
    parser.add_argument("--ks-draws", type=int, default=1000)
    parser.add_argument("--ks-stop-time", type=float, default=160.0)
    parser.add_argument("--draws", type=int, default=10000)
    parser.add_argument("--skip-sweep", action="store_true")
    parser.add_argument("--skip-ks", action="store_true")
    args = parser.parse_args()
    names = taken()
    print(f"shipped studies the compiled engine takes: {', '.join(names)}")
    print(f"{'study':<20}{'python [s]':>11}{'compiled [s]':>13}{'ratio':>8}{'compile [s]':>12}"
          f"{'noise off: signals':>22}{'tracking metrics':>22}")
    for name in names:
        study = base(name, QUIET + NO_QUANTISATION)
        began = time.perf_counter()
        CompiledSimulation(build_system(resolve(study)))          # the shape compiled (or found) once
        compile_s = time.perf_counter() - began
        py, t_py = timed(Simulation, study)
        cc, t_cc = timed(CompiledSimulation, study)
        quantised = base(name, QUIET)
        mq = metrics_of(quantised, timed(CompiledSimulation, quantised)[0])
        mp = metrics_of(quantised, timed(Simulation, quantised)[0])
        tracking = [k for k in mp if k.startswith("euclid") and np.isfinite(mp[k])]
        diff_q = max(abs(mq[k] - mp[k]) / abs(mp[k]) for k in tracking)
        print(f"{name:<20}{t_py:>11.3f}{t_cc:>13.4f}{t_py / t_cc:>8.0f}{compile_s:>12.2f}{worst(cc, py):>22.2e}"
              f"{diff_q:>22.2e}")
    print("(signals: the largest difference of any signal at any instant over that signal's largest magnitude, the "
          "potentiometer's quantisation off; tracking metrics: the largest relative difference of the euclid_* "
          "metrics with the 1-degree quantisation on, as shipped, where a flip of one level parts the loops)")
    if not args.skip_ks:
        print(f"\nnoise on, figure8.toml, {args.ks_draws} seeds per engine, {args.ks_stop_time:g} s each: "
              f"two-sample KS of every metric (the same distribution unless p < 0.01)")
        print(f"{'metric':<30}{'KS D':>8}{'p':>10}  verdict")
        for k, d, p in ks_rows("figure8.toml", args.ks_draws, args.ks_stop_time):
            print(f"{k:<30}{d:>8.3f}{p:>10.3f}  {'agree' if p >= 0.01 else 'DIFFER'}")
    if not args.skip_sweep:
        wall, cpu, peak, line = sweep(args.draws)
        load = os.getloadavg()[0]
        print(f"\nrobustness Monte Carlo, {args.draws} draws, --engine compiled, 2 workers: {wall:.0f} s wall "
              f"({wall / args.draws * 1e3:.0f} ms a draw) at load {load:.1f} on {os.cpu_count()} cores; CPU of all its "
              f"processes {cpu:.0f} s ({cpu / args.draws * 1e3:.0f} ms a draw): 10,000 draws on 2 idle cores "
              f"~ {cpu / args.draws * 10000 / 2:.0f} s ({'within' if cpu / args.draws * 10000 / 2 <= 600 else 'over'} "
              f"10 min); peak memory of the largest process {peak:.0f} MiB")
        print(f"  {line}")


if __name__ == "__main__":
    main()
