"""``identify``: the identification tool's sub-command and its study table ([identification])."""
from __future__ import annotations

import argparse
from pathlib import Path

from agrobot.api import identify
from agrobot.measurements.cli import add_mode_options, add_recording_options, recording_options
from agrobot.measurements.recording import describe
from agrobot.orchestrator.cli import add_output_options, add_set_option
from agrobot.orchestrator.observers import timed_progress


def add_arguments(p: argparse.ArgumentParser) -> None:
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
    p.add_argument("--course-speed", type=float, default=None, help="log without a gyro or heading: the speed "
                   "[m/s] above which the GNSS course measures the yaw rate (default: where 0.5 s chords keep the course's "
                   "noise within 0.05 rad for the positions' own noise, at most 1)")
    p.add_argument("--fit-seconds", type=float, default=None, help="log, driving: fit at most this many seconds "
                   "of the log's segments, evenly spread over it (default 300: a longer log's other segments are "
                   "passed over, and said; a larger value fits more at a cost growing with them)")
    p.add_argument("--steering-geometry", choices=("auto", "w", "tan"), default="auto", help="log, driving: how the "
                   "wheel angle w drives the single-track model: w (small angles), tan (an Ackermann machine's no-slip "
                   "turn r = v tan w / L), auto (the better fit of the two where w reaches 0.17 rad, else w)")
    p.add_argument("--input-hold", choices=("auto", "zoh", "linear"), default="auto", help="log, driving: how the "
                   "steering input is read between its rows: zoh (held: a set-point whose rows are its own update "
                   "stamps), linear, auto (linear: rows that resample a set-point quantize its updates)")
    p.add_argument("--resample", action="store_true",
                   help="log: interpolate a log whose clock jitters onto an even grid (its median step)")
    add_mode_options(p)
    add_recording_options(p)


def run(args: argparse.Namespace) -> int:
    """Parse, identify through agrobot.api, print."""
    is_study = args.source.suffix in (".toml", ".yaml", ".yml")
    found = identify(args.source, study=None if is_study else args.study, method=args.method, set=args.set,
                     period=args.period, speed=args.speed, band=args.band, models=args.models, delay=args.delay,
                     resample=args.resample, recording=None if is_study else recording_options(args),
                     out=args.out, plots=not args.no_plots, progress=timed_progress(), overwrite=args.overwrite,
                     course_speed=args.course_speed, fit_seconds=args.fit_seconds,
                     steering_geometry=args.steering_geometry, input_hold=args.input_hold)
    if found.method == "driving":
        figures = found.report.get("figures", [])
        print(found.summary())
        print(f"\nwritten to {args.out}/identification.json" + (f" and {', '.join(figures)}" if figures else ""))
        return 0
    if "recording" in found.report:
        print(describe(found.report["recording"]))
    print(found.summary())
    print(f"\nwritten to {args.out}/identification.json")
    return 0


def register(registry) -> None:
    registry.add_section("identification", "identification tool (python -m agrobot identify)")
    registry.add_command("identify", "identify the yaw dynamics from a study's experiment or a measured log",
                         add_arguments, run)
