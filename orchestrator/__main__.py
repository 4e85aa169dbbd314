"""Command line: ``python -m orchestrator run STUDY --out DIR [--set comp.param=value ...]``."""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from .engine import RunError
from .runner import AnalysisError, run_study
from .study import StudyError, load_study


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m orchestrator", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run a study file and write metrics, signals and plots")
    run.add_argument("study", type=Path)
    run.add_argument("--out", type=Path, required=True, help="output folder")
    run.add_argument("--set", action="append", default=[], metavar="COMP.PARAM=VALUE",
                     help="override a parameter (or study.FIELD=VALUE); repeatable")
    run.add_argument("--no-plots", action="store_true")
    sw = sub.add_parser("sweep", help="run every point of a study's [sweep] section")
    sw.add_argument("study", type=Path)
    sw.add_argument("--out", type=Path, required=True, help="output folder (rerun it to resume)")
    sw.add_argument("--workers", type=int, default=os.cpu_count() or 1, help="worker processes (default: all cores)")
    sw.add_argument("--scheduler", default=None, metavar="ADDRESS",
                    help="a Dask scheduler address, or 'local' to start a local Dask cluster")
    sw.add_argument("--set", action="append", default=[], metavar="COMP.PARAM=VALUE")
    sw.add_argument("--retry-failed", action="store_true", help="run failed points again")
    sw.add_argument("--no-progress", action="store_true")
    sw.add_argument("--no-plots", action="store_true")
    ident = sub.add_parser("identify", help="identify the yaw dynamics from a study's experiment or a measured log")
    ident.add_argument("source", type=Path, help="study file (.toml/.yaml) or log (.csv/.parquet)")
    ident.add_argument("--out", type=Path, required=True)
    ident.add_argument("--set", action="append", default=[], metavar="COMP.PARAM=VALUE", help="study only")
    ident.add_argument("--period", type=float, help="log: multisine period [s] (detected if not given)")
    ident.add_argument("--speed", type=float, help="log: speed [m/s] (median of v if not given)")
    ident.add_argument("--band", type=float, nargs=2, metavar=("F_MIN", "F_MAX"), help="log: lines to fit [Hz]")
    ident.add_argument("--models", nargs="+", help="log: structures to fit")
    ident.add_argument("--delay", action="store_true", help="log: fit a pure delay too")
    ident.add_argument("--no-plots", action="store_true")
    exp = sub.add_parser("export-controller",
                         help="export the study's guidance controller (tracker + MPC + speed PID) as an FMU")
    exp.add_argument("study", type=Path)
    exp.add_argument("--out", type=Path, required=True, help="the .fmu to write, e.g. fmus/guidance_controller.fmu")
    exp.add_argument("--set", action="append", default=[], metavar="COMP.PARAM=VALUE")
    diag = sub.add_parser("diagnose", help="name what the simulation gets wrong about a measured log")
    diag.add_argument("log", type=Path, help="measured log (.csv/.parquet): t, delta_cmd, delta, v, yaw_rate, x, y")
    diag.add_argument("--study", type=Path, default=None, help="baseline study (default: studies/figure8.toml)")
    diag.add_argument("--out", type=Path, required=True)
    diag.add_argument("--fit-fraction", type=float, default=0.6, help="share of the log used to fit; the rest is held out")
    diag.add_argument("--min-gain", type=float, default=0.05, help="least held-out RMS reduction to accept an extension")
    diag.add_argument("--no-plots", action="store_true")
    emu = sub.add_parser("emulate", help="serve a simulated tractor in real time over NMEA/TCP and CAN")
    emu.add_argument("study", type=Path, help="a study with an nmea_server, e.g. studies/tractor_emulator.toml")
    emu.add_argument("--nmea-port", type=int, required=True, help="TCP port on 127.0.0.1 for NMEA clients")
    emu.add_argument("--out", type=Path, default=None, help="write the emulated tractor's signals here")
    emu.add_argument("--duration", type=float, default=None, help="stop after this many seconds")
    emu.add_argument("--set", action="append", default=[], metavar="COMP.PARAM=VALUE")
    args = parser.parse_args(argv)
    if args.command == "emulate":
        from components.hardware.emulate import emulate

        return emulate(args.study, args.nmea_port, args.out, args.set, args.duration)
    if args.command == "diagnose":
        return _diagnose(args)
    if args.command == "export-controller":
        return _export_controller(args)
    if args.command == "sweep":
        return _sweep(args)
    if args.command == "identify":
        return _identify(args)
    try:
        study = load_study(args.study, args.set)
        result = run_study(study, args.out, plots=not args.no_plots)
    except StudyError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except AnalysisError as exc:
        print(f"error: {exc}; the signals are in {args.out}", file=sys.stderr)
        return 1
    except RunError as exc:
        print(f"error: run failed {exc}; results recorded so far are in {args.out}", file=sys.stderr)
        return 1
    print(result.summary)
    print(f"\nresults written to {args.out}/ ({', '.join(p.name for p in result.files)})")
    return 0


def _sweep(args) -> int:
    from .study import load_raw, parse_study
    from .sweep import SweepRun, sweep_plots

    if args.workers < 1:
        print("error: --workers must be >= 1", file=sys.stderr)
        return 2
    try:
        raw = load_raw(args.study, args.set)
        study = parse_study(raw, args.study)
        runner = SweepRun(study, raw, args.out)
        table = runner.run(args.workers, args.scheduler, args.retry_failed, progress=not args.no_progress)
    except StudyError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"\ninterrupted: finished points are kept in {args.out}; run the same command to resume",
              file=sys.stderr)
        return 130
    failed = int((table["status"] != "completed").sum())
    files = [] if args.no_plots else sweep_plots(study, table, args.out / "plots")
    print(f"{len(table)} points ({failed} failed) in {args.out}/results.{study.study.signals_format}"
          + (f"; plots: {', '.join(p.name for p in files)}" if files else ""))
    return 0 if failed == 0 else 1


def _export_controller(args) -> int:
    from fmu_export.controller import ExportError, export_controller

    try:
        out = export_controller(load_study(args.study, args.set), args.out)
    except (StudyError, ExportError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"controller of {args.study} exported to {out}")
    return 0


def _identify(args) -> int:
    from identification.experiment import LogError
    from identification.pipeline import identify_log, identify_study, summary
    from .study import load_raw, parse_study

    try:
        if args.source.suffix in (".toml", ".yaml", ".yml"):
            raw = load_raw(args.source, args.set)
            report = identify_study(parse_study(raw, args.source), raw, args.out, plots=not args.no_plots)
        else:
            report = identify_log(args.source, args.out, args.period, args.speed,
                                  tuple(args.band) if args.band else None, args.models, args.delay,
                                  plots=not args.no_plots)
    except (StudyError, LogError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except ValueError as exc:      # e.g. an unknown model structure
        print(f"error: {args.source}: {exc}", file=sys.stderr)
        return 2
    print(summary(report))
    print(f"\nwritten to {args.out}/identification.json")
    return 0


def _diagnose(args) -> int:
    """Exit 0 with a verdict (an effect or 'none'); 2 when the log or study cannot be used (the
    verdict 'cannot decide' and the reason are still written)."""
    from diagnosis.pipeline import CANNOT_DECIDE, diagnose

    if not 0.2 <= args.fit_fraction <= 0.8:
        print("error: --fit-fraction must be in [0.2, 0.8]", file=sys.stderr)
        return 2
    try:
        result = diagnose(args.log, args.out, args.study, args.fit_fraction, args.min_gain, plots=not args.no_plots)
    except StudyError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if result["verdict"] == CANNOT_DECIDE:
        print(f"error: {result['reason']}\nverdict: {CANNOT_DECIDE} (written to {args.out}/diagnosis.json)", file=sys.stderr)
        return 2
    print(f"verdict: {result['verdict']}")
    for f in result["findings"][:3]:
        print(f"  {f['effect']:26s} dBIC {f['evidence']['delta_bic']:9.1f}  held-out gain {100 * f['gain']:5.1f}%  "
              + ", ".join(f"{k} = {v:.4g}" for k, v in f["params_display"].items()))
    print(f"report: {args.out}/report.md" + (f", extended study: {args.out}/{result['extended_study']}"
                                             if "extended_study" in result else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
