"""The FMU export tool's sub-commands: ``export-controller``, ``export-ssp``, ``export-fmu``.

Imported where used: agrobot.fmu_export.controller (start-up: with the two next, fmpy and the controller's
components, 0.25 s on every command, ``--help`` included), agrobot.fmu_export.ssp_export (start-up: the
same), agrobot.fmu_export.loop_fmu (start-up: the same).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from agrobot.orchestrator.cli import add_output_options, add_set_option
from agrobot.orchestrator.observers import Stage
from agrobot.orchestrator.output import ResultFile, study_inputs
from agrobot.orchestrator.study import Study


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("study", type=Path, help="study holding the tracker, the yaw-rate MPC and the speed PID")
    add_output_options(p, "the .fmu to write, e.g. fmus/guidance_controller.fmu", file=True)
    p.add_argument("--fmi-version", type=int, default=2, choices=(2, 3), help="FMI version of the FMU (default 2)")
    add_set_option(p)


def run(args: argparse.Namespace) -> int:
    from .controller import export_controller

    study = Study.load(args.study, args.set)
    with ResultFile(args.out, args.overwrite, study_inputs(study), suffixes=(".fmu",)), \
            Stage(f"export-controller: generating the C code and compiling {args.out.name} (cmake and the C compiler)"):
        out = export_controller(study, args.out, args.fmi_version)
    print(f"controller of {args.study} exported to {out} (FMI {args.fmi_version}.0 co-simulation)")
    return 0


def add_ssp_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("study", type=Path, help="study whose components all have an FMU form (e.g. studies/figure8.toml)")
    add_output_options(p, "the .ssp to write, e.g. fmus/figure8.ssp", file=True)
    add_set_option(p)


def run_ssp(args: argparse.Namespace) -> int:
    from .ssp_export import export_ssp

    study = Study.load(args.study, args.set)
    with ResultFile(args.out, args.overwrite, study_inputs(study), suffixes=(".ssp",)), Stage(f"export-ssp: compiling {len(study.components)} FMUs, one per component (cmake and the C "
               f"compiler), and validating the SSD"):
        out = export_ssp(study, args.out)
    print(f"{args.study} exported to {out} (SSP 1.0: SystemStructure.ssd and one FMI 2.0 FMU per component)")
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
    from .loop_fmu import export_loop

    study = Study.load(args.study, args.set)
    names = [n.strip() for n in args.components.split(",") if n.strip()] if args.components is not None else None
    if study.sweep is not None:
        study = study.without("sweep")
        print(f"{args.study}: its [sweep] is left out: the FMU is the study's own point (--set the values to export "
              f"another)", file=sys.stderr)
    count = len(names) if names is not None else len(study.components)
    with ResultFile(args.out, args.overwrite, study_inputs(study), suffixes=(".fmu",)), \
            Stage(f"export-fmu: compiling the loop of {count} components into {args.out.name} "
                  f"(the compiled engine's C, cmake and the C compiler)"):
        out, note = export_loop(study, args.out, args.fmi_version, names)
    print(note, file=sys.stderr)
    what = f"the subsystem {', '.join(names)}" if names is not None else "the whole loop"
    print(f"{args.study} exported to {out} (FMI {args.fmi_version}.0 co-simulation, {what})")
    return 0


def register(registry) -> None:
    registry.add_command("export-controller",
                         "export the study's guidance controller (tracker + MPC + speed PID) as an FMU",
                         add_arguments, run)
    registry.add_command("export-fmu", "export the study's whole loop as one FMU (every component compiled from its "
                         "C core)", add_loop_arguments, run_loop)
    registry.add_command("export-ssp", "export the study as an SSP 1.0 archive (one FMU per component)",
                         add_ssp_arguments, run_ssp)
