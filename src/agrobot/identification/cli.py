"""``identify``: the identification tool's sub-command and its study table ([identification])."""
from __future__ import annotations

import argparse
from pathlib import Path


def add_arguments(p: argparse.ArgumentParser) -> None:
    from agrobot.orchestrator.cli import add_output_options, add_set_option

    p.add_argument("source", type=Path, help="study file (.toml/.yaml), log (.csv/.parquet), or a raw recording "
                   "(a folder of *.nmea files and CAN logs)")
    add_output_options(p, "output folder (identification.json, figures)", plots=True)
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
    from agrobot.measurements.cli import add_recording_options

    add_recording_options(p)


def run(args: argparse.Namespace) -> int:
    from agrobot.orchestrator.study import Study, StudyError

    from .pipeline import summary

    if args.band is not None and not 0 < args.band[0] < args.band[1]:
        raise StudyError(f"--band {args.band[0]:g} {args.band[1]:g}: expected 0 < F_MIN < F_MAX [Hz]")
    for option, value in (("--speed", args.speed), ("--period", args.period)):
        if value is not None and not value > 0:
            raise StudyError(f"{option} {value:g}: expected a positive number")
    from agrobot.orchestrator.output import ResultFolder, study_inputs

    is_study = args.source.suffix in (".toml", ".yaml", ".yml")
    study = Study.load(args.source, args.set) if is_study else Study.load(args.study) if args.study else None
    folder = ResultFolder(args.out, args.overwrite, ("identification.json",), "identification",
                          [args.source, args.study, args.dbc, *study_inputs(study)])
    with folder:
        report = _identify(args, study, is_study, folder.tmp)
        folder.commit()
    if report is None:          # ordinary driving: its summary is printed
        return 0
    print(summary(report))
    print(f"\nwritten to {args.out}/identification.json")
    return 0


def _identify(args: argparse.Namespace, study, is_study: bool, out: Path):
    """The report of a multisine identification written into ``out``; None for ordinary driving
    (written and summed up by identify_driving_log)."""
    from agrobot.orchestrator.errors import InputError
    from agrobot.orchestrator.study import StudyError

    from .pipeline import identify_log, identify_study

    try:
        if is_study:
            return identify_study(study, out, plots=not args.no_plots)
        else:
            from agrobot.measurements.cli import recording_options
            from agrobot.measurements.recording import describe

            from .from_log import choose_method, identify_driving_log

            if choose_method(args.source, args.method, args.resample, recording_options(args), study) == "driving":
                identify_driving_log(args.source, out, study, plots=not args.no_plots,
                                     resample=args.resample, recording=recording_options(args), shown_as=args.out)
                return None
            report = identify_log(args.source, out, args.period, args.speed,
                                  tuple(args.band) if args.band else None, args.models, args.delay,
                                  plots=not args.no_plots, resample=args.resample,
                                  recording=recording_options(args),
                                  study=study)
            if "recording" in report:
                print(describe(report["recording"]))
            return report
    except ValueError as exc:      # e.g. an unknown model structure
        if isinstance(exc, InputError):       # a LogError is both
            raise
        raise StudyError(f"{args.source}: {exc}") from None


def register(registry) -> None:
    registry.add_section("identification", "identification tool (python -m agrobot identify)")
    registry.add_command("identify", "identify the yaw dynamics from a study's experiment or a measured log",
                         add_arguments, run)
