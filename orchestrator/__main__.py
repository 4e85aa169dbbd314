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
    args = parser.parse_args(argv)
    if args.command == "sweep":
        return _sweep(args)
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


if __name__ == "__main__":
    sys.exit(main())
