"""``identify``: the identification tool's sub-command and its study table ([identification])."""
from __future__ import annotations

import argparse
from pathlib import Path


def add_arguments(p: argparse.ArgumentParser) -> None:
    from agrobot.orchestrator.cli import add_set_option

    p.add_argument("source", type=Path, help="study file (.toml/.yaml), log (.csv/.parquet), or a raw recording "
                   "(a folder of *.nmea files and CAN logs)")
    p.add_argument("--out", type=Path, required=True, help="output folder")
    add_set_option(p, "study only: override a parameter (or study.FIELD=VALUE); repeatable")
    p.add_argument("--period", type=float, help="log: multisine period [s] (detected if not given)")
    p.add_argument("--speed", type=float, help="log: speed [m/s] (median of v if not given)")
    p.add_argument("--band", type=float, nargs=2, metavar=("F_MIN", "F_MAX"), help="log: lines to fit [Hz]")
    p.add_argument("--models", nargs="+", help="log: structures to fit")
    p.add_argument("--delay", action="store_true", help="log: fit a pure delay too (multisine)")
    p.add_argument("--method", choices=("auto", "multisine", "driving"), default="auto",
                   help="log: 'multisine' (a designed periodic experiment: FRF and frequency-domain fits), 'driving' "
                   "(ordinary driving: a time-domain fit held out on segments), 'auto' (multisine when delta_cmd repeats "
                   "with a period, else driving)")
    p.add_argument("--study", type=Path, default=None, help="log: the vehicle's study (its yaw plant's mass and axle "
                   "distances for the physical parameters; its [vehicle] table for a recording); default the tractor")
    p.add_argument("--resample", action="store_true",
                   help="log: interpolate a log whose clock jitters onto an even grid (its median step)")
    p.add_argument("--no-plots", action="store_true", help="skip the figures")
    from agrobot.measurements.cli import add_recording_options

    add_recording_options(p)


def run(args: argparse.Namespace) -> int:
    from agrobot.orchestrator.errors import InputError
    from agrobot.orchestrator.study import Study, StudyError

    from .pipeline import identify_log, identify_study, summary

    if args.band is not None and not 0 < args.band[0] < args.band[1]:
        raise StudyError(f"--band {args.band[0]:g} {args.band[1]:g}: expected 0 < F_MIN < F_MAX [Hz]")
    for option, value in (("--speed", args.speed), ("--period", args.period)):
        if value is not None and not value > 0:
            raise StudyError(f"{option} {value:g}: expected a positive number")
    from agrobot.orchestrator.output import check_output

    check_output(args.out, overwrite=True)
    try:
        if args.source.suffix in (".toml", ".yaml", ".yml"):
            report = identify_study(Study.load(args.source, args.set), args.out, plots=not args.no_plots)
        else:
            from agrobot.measurements.cli import recording_options
            from agrobot.measurements.recording import describe

            from .from_log import choose_method, identify_driving_log

            study = Study.load(args.study) if args.study else None
            if choose_method(args.source, args.method, args.resample, recording_options(args), study) == "driving":
                return identify_driving_log(args.source, args.out, study, plots=not args.no_plots,
                                            resample=args.resample, recording=recording_options(args))
            report = identify_log(args.source, args.out, args.period, args.speed,
                                  tuple(args.band) if args.band else None, args.models, args.delay,
                                  plots=not args.no_plots, resample=args.resample,
                                  recording=recording_options(args),
                                  study=study)
            if "recording" in report:
                print(describe(report["recording"]))
    except ValueError as exc:      # e.g. an unknown model structure
        if isinstance(exc, InputError):       # a LogError is both
            raise
        raise StudyError(f"{args.source}: {exc}") from None
    print(summary(report))
    print(f"\nwritten to {args.out}/identification.json")
    return 0


def register(registry) -> None:
    registry.add_section("identification", "identification tool (python -m agrobot identify)")
    registry.add_command("identify", "identify the yaw dynamics from a study's experiment or a measured log",
                         add_arguments, run)
