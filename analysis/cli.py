"""``margins``: the analysis tools' sub-command."""
from __future__ import annotations

import argparse
from pathlib import Path


def add_arguments(p: argparse.ArgumentParser) -> None:
    from orchestrator.cli import add_set_option

    p.add_argument("study", type=Path, help="a figure-8 study (tracker, yaw-rate MPC, steering, yaw plant, reference)")
    add_set_option(p)
    p.add_argument("--no-simulation", action="store_true", help="skip the simulated delay limit (bisection)")


def run(args: argparse.Namespace) -> int:
    from orchestrator.study import Study

    from .margins import report

    print(report(Study.load(args.study, args.set), simulate=not args.no_simulation))
    return 0


def register(registry) -> None:
    registry.add_command("margins", "gain, phase and delay margins of the linearised yaw-rate and path loops, "
                         "and the delay at which the simulated figure-8 leaves the bounds", add_arguments, run)
