"""Command line: ``python -m orchestrator run STUDY --out DIR [--set comp.param=value ...]``."""
from __future__ import annotations

import argparse
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
    args = parser.parse_args(argv)
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


if __name__ == "__main__":
    sys.exit(main())
