"""The FMU export tool's sub-commands: ``export-controller``, ``export-ssp``, ``export-fmu``: each
parses, calls its function of agrobot.api (which builds the archive and writes it under the output
rule) and prints.

Imported where used: agrobot.api (start-up: with the exporters it imports where used, fmpy and the
controller's components, 0.25 s on every command, ``--help`` included).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from agrobot.orchestrator.cli import add_output_options, add_set_option


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("study", type=Path, help="study holding the tracker, the yaw-rate MPC and the speed PID")
    add_output_options(p, "the .fmu to write, e.g. fmus/guidance_controller.fmu", file=True)
    p.add_argument("--fmi-version", type=int, default=2, choices=(2, 3), help="FMI version of the FMU (default 2)")
    add_set_option(p)


def run(args: argparse.Namespace) -> int:
    from agrobot.api import export_controller

    made = export_controller(args.study, args.set, args.out, fmi_version=args.fmi_version, overwrite=args.overwrite)
    print(f"controller of {args.study} exported to {made.path} (FMI {args.fmi_version}.0 co-simulation)")
    return 0


def add_ssp_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("study", type=Path, help="study whose components all have an FMU form (e.g. studies/figure8.toml)")
    add_output_options(p, "the .ssp to write, e.g. fmus/figure8.ssp", file=True)
    add_set_option(p)


def run_ssp(args: argparse.Namespace) -> int:
    from agrobot.api import export_ssp

    made = export_ssp(args.study, args.set, args.out, overwrite=args.overwrite)
    print(f"{args.study} exported to {made.path} (SSP 1.0: SystemStructure.ssd and one FMI 2.0 FMU per component)")
    return 0


def add_loop_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("study", type=Path, help="study whose every component has a C core (e.g. studies/figure8.toml)")
    add_output_options(p, "the .fmu to write, e.g. fmus/figure8_loop.fmu", file=True)
    p.add_argument("--fmi-version", type=int, default=2, choices=(2, 3), help="FMI version of the FMU (default 2)")
    p.add_argument("--components", default=None, metavar="NAME,NAME",
                   help="export only these components (a subsystem, e.g. tractor,steering,gps): the inputs they do "
                        "not feed each other become the FMU's inputs, all their outputs its outputs (default: the "
                        "whole study)")
    add_set_option(p)


def run_loop(args: argparse.Namespace) -> int:
    from agrobot.api import export_fmu

    names = [n.strip() for n in args.components.split(",") if n.strip()] if args.components is not None else None
    made = export_fmu(args.study, args.set, args.out, fmi_version=args.fmi_version, components=names,
                      overwrite=args.overwrite)
    print(made.note, file=sys.stderr)
    what = f"the subsystem {', '.join(names)}" if names is not None else "the whole loop"
    print(f"{args.study} exported to {made.path} (FMI {args.fmi_version}.0 co-simulation, {what})")
    return 0


def register(registry) -> None:
    registry.add_command("export-controller",
                         "export the study's guidance controller (tracker + MPC + speed PID) as an FMU",
                         add_arguments, run)
    registry.add_command("export-fmu", "export the study's whole loop as one FMU (every component compiled from its "
                         "C core)", add_loop_arguments, run_loop)
    registry.add_command("export-ssp", "export the study as an SSP 1.0 archive (one FMU per component)",
                         add_ssp_arguments, run_ssp)
