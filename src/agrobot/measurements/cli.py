"""``convert``: a raw recording (NMEA, CAN with any maker's DBC, ROS bags, ISO 11783-10 time logs,
other tools' tables) to the measured log (CSV or Parquet), with its import report beside it, or
``--list`` of what it holds; and the recording options ``identify`` and ``diagnose`` share. The
formats the help names are the readers' (measurements.recording_readers), in their order of precedence."""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from agrobot.orchestrator.atomic_files import atomic_write, write_frame
from agrobot.orchestrator.cli import add_output_options
from agrobot.orchestrator.output import ResultFile, check_output_file
from agrobot.orchestrator.source_files import set_limit

from . import recording_readers as readers
from .audit import parse_align, with_findings
from .listing import list_source
from .log import SECONDS_STEP_MAX, LogError, check_log, log_units
from .log_mcap import write_log_mcap
from .modes import parse_where
from .recording import ImportOptions, describe, import_recording, import_runs
from .signal_expressions import parse_signal
from .tables import parse_time


def add_recording_options(p: argparse.ArgumentParser) -> None:
    """Options for reading a raw recording (ignored for a CSV/Parquet log)."""
    g = p.add_argument_group(f"raw recordings (a folder or one file: {readers.names()})")
    g.add_argument("--dbc", type=Path, default=None, help="DBC decoding the CAN logs (any maker's: what cannot be "
                   "decoded is left out and named; default: the project's agrobot_tractor.dbc; "
                   "components/hardware/isobus_guidance.dbc for ISO 11783-7 guidance)")
    g.add_argument("--signal", action="append", default=[], metavar="COLUMN=EXPR[unit]",
                   help="a log column from an expression of signals: Message.Signal (CAN), /topic.field (ROS), "
                        "TABLE.COLUMN or COLUMN (tables); sums, differences and numbers (A+B, -0.5*(A+B), A*3.6); "
                        "[unit] any unit pint knows (deg, deg/s, km/h, g), else the source's own; an angle, rate or "
                        "speed without any unit must be declared; lat/lon in degrees become x/y; repeatable")
    g.add_argument("--bus", default=None, help="the CAN bus to read when a log holds several (can0, can1, or a "
                   "Vector channel number)")
    g.add_argument("--time", default=None, metavar="COLUMN[unit|datetime]",
                   help="a table's time: COLUMN[s|ms|us|ns], COLUMN[datetime], SECONDS+NANOSECONDS, DATE+TIME[datetime], "
                        "or TABLE.COLUMN for tables without their own (default: found by name, e.g. t, time, s+ns); "
                        "a ROS bag's: /topic.field[s|ms|us|ns], a topic holding the data's own clock (a bag recorded "
                        "while a log was replayed; default: the bag's clock)")
    g.add_argument("--keep-spikes", action="store_true", help="keep the samples found to be spikes (they are "
                   "named in the report either way)")
    g.add_argument("--steering-ratio", type=float, default=None, metavar="R",
                   help="the recording's steering angles are handwheel angles: divide delta and delta_cmd by R "
                        "(default: the study's steering_ratio for identify/diagnose, else 1)")
    g.add_argument("--wheelbase", type=float, default=None, help="m: curvature <-> wheel angle, and the wheelbase identify (and "
                   "diagnose's identify step) fits on (default: the study's [vehicle] wheelbase, else its yaw "
                   "plant's l_f + l_r, else 1.4, the paper tractor)")
    g.add_argument("--max-file-size", default=None, metavar="SIZE", help="the largest file read (500M, 4G ...; "
                   "default 1G for a file read whole into memory, 16G for one read as a stream: NMEA, CAN, bags)")
    g.add_argument("--rate", type=float, default=None, help="Hz of the log (default: the GNSS epoch rate, else the fastest "
                   "channel's, at most 50 Hz; a channel thinned by it is said)")
    g.add_argument("--run", type=int, default=None, help="use the K-th run found (default: the longest)")
    g.add_argument("--max-gap", type=float, default=0.5, metavar="SECONDS",
                   help="a channel's gap up to this is bridged (linear; a command held) and named; a longer one, or "
                        "a silence of every channel, splits the log (default 0.5 s; 0 bridges nothing)")
    g.add_argument("--align", default="auto", metavar="auto|none|GROUP=SECONDS",
                   help="clock offsets between channel groups (a file, topic or bus): auto corrects those the audit "
                        "finds on strong evidence (two speeds, gyro vs GNSS course, v r vs lateral acceleration); none "
                        "keeps the stamps; GROUP=SECONDS moves GROUP earlier by SECONDS (default auto)")
    g.add_argument("--sign-speed", action="store_true",
                   help="the speed is unsigned (a receiver's speed over ground, an encoder without direction): make "
                        "it negative where the audit finds the machine reversing (the course against a direction "
                        "channel, the heading or the steering); without it such a recording is refused")
    g.add_argument("--trim-standstill", action="store_true",
                   help="leave out the standstill before and after the run used (kept by default: a gyro's bias "
                        "and a steering offset are measured standing still)")
    g.add_argument("--time-range", type=float, nargs=2, default=None, metavar=("START", "END"),
                   help="use this span, s after the recording's first fix, instead of a run")


def add_mode_options(p: argparse.ArgumentParser) -> None:
    """The stretches judged (measurements.modes): --where and --keep-unexplained."""
    p.add_argument("--where", default=None, metavar="'COLUMN OP VALUE'",
                   help="judge only the stretches where a mode or engagement channel says so: COLUMN OP VALUE with OP "
                        "== != < <= > >=, joined by and/or (e.g. 'mode == auto', 'engaged == 1 and v > 0.5'); the "
                        "stretches are printed; a raw recording's channel is mapped with --signal")
    p.add_argument("--min-stretch", type=float, default=15.0, metavar="SECONDS",
                   help="a stretch that --where selects (or that is left between unexplained ones) shorter than this "
                        "is left out; every longer one is judged (default 15 s: the replays' 3 s burn-in and a 10 s "
                        "window, with margin)")
    p.add_argument("--keep-unexplained", action="store_true",
                   help="keep the stretches where the steering command does not explain the steering (driven by hand "
                        "or remote; found and left out by default, printed either way)")


def recording_options(args: argparse.Namespace):
    """ImportOptions from the parsed options; a LogError names the bad one."""
    set_limit(getattr(args, "max_file_size", None))

    if args.wheelbase is not None and not 0.1 <= args.wheelbase <= 10.0:
        raise LogError(f"--wheelbase {args.wheelbase:g}: expected metres, 0.1 (a 1:10 model car) to 10")
    if args.run is not None and args.run < 1:
        raise LogError(f"--run {args.run}: runs are numbered from 1")
    if args.time_range is not None and not 0 <= args.time_range[0] < args.time_range[1]:
        raise LogError(f"--time-range {args.time_range[0]:g} {args.time_range[1]:g}: expected 0 <= START < END (s)")
    if args.run is not None and args.time_range is not None:
        raise LogError("--run and --time-range: give one of them")
    if args.dbc is not None and not args.dbc.is_file():
        raise LogError(f"--dbc {args.dbc}: no such file")
    if args.steering_ratio is not None and not 0.05 <= args.steering_ratio <= 50.0:
        raise LogError(f"--steering-ratio {args.steering_ratio:g}: expected the handwheel-to-road-wheel ratio, "
                       f"0.05 to 50 (a car: 12-20)")
    signals = [parse_signal(s) for s in args.signal]
    columns = [s.column for s in signals]
    twice = sorted({c for c in columns if columns.count(c) > 1})
    if twice:
        raise LogError(f"--signal: column {twice[0]!r} is given {columns.count(twice[0])} times; give each column once")
    parse_time(getattr(args, "time", None))
    options = ImportOptions(dbc=args.dbc, signals=signals, rate=args.rate,
                            run=args.run, time_range=tuple(args.time_range) if args.time_range else None,
                            bus=getattr(args, "bus", None), time=getattr(args, "time", None),
                            keep_spikes=getattr(args, "keep_spikes", False),
                            trim_standstill=getattr(args, "trim_standstill", False),
                            max_gap=getattr(args, "max_gap", 0.5), align=getattr(args, "align", "auto"),
                            sign_speed=getattr(args, "sign_speed", False),
                            where=getattr(args, "where", None),
                            keep_unexplained=getattr(args, "keep_unexplained", False),
                            min_stretch=getattr(args, "min_stretch", 15.0))
    if not 0.0 <= options.min_stretch <= 3600.0:
        raise LogError(f"--min-stretch {options.min_stretch:g}: expected seconds, 0 to 3600")
    parse_align(options.align)
    if options.where is not None:
        parse_where(options.where)
    if args.steering_ratio is not None:
        options.steering_ratio = args.steering_ratio
    if args.wheelbase is not None:
        options.wheelbase = args.wheelbase
    return options


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("source", type=Path, help=f"a folder or one file: {readers.described()}; in this order of "
                   "precedence: a file is read as the first of these formats that claims it, and the first format "
                   "a folder holds makes the recording (NMEA files and CAN logs are read together)")
    add_output_options(p, "the log to write (.csv or .parquet); the import report goes beside it as "
                          "<name>.import.json", required=False, file=True)
    p.add_argument("--list", action="store_true", help=f"print what the recording holds ({readers.listed()}) and "
                   "write nothing")
    p.add_argument("--all-runs", action="store_true", help="write every run, as <name>_run01.csv ...")
    p.add_argument("--mcap", action="store_true", help="also write each log as <name>.mcap for Foxglove/PlotJuggler")
    add_recording_options(p)


def run(args: argparse.Namespace) -> int:
    if args.list:
        options = recording_options(args)
        print("\n".join(list_source(args.source, options)))
        return 0
    if args.out is None:
        raise LogError("convert: give --out LOG.csv (or .parquet), or --list to see what the recording holds")
    inputs = [args.source, args.dbc]
    target = ResultFile(args.out, args.overwrite, inputs, suffixes=(".csv", ".parquet"))
    options = recording_options(args)
    if args.all_runs:
        if options.run is not None or options.time_range is not None:
            raise LogError("--all-runs: not with --run or --time-range")
        jobs = [(args.out.with_name(f"{args.out.stem}_run{rep['used']['run']:02d}{args.out.suffix}"), f, rep)
                for f, rep in import_runs(args.source, options)]
    else:
        jobs = [(args.out, *import_recording(args.source, options))]
    if args.wheelbase is not None:          # read back by identify on the converted log
        for _, _, rep in jobs:
            rep["wheelbase"] = {"value": float(args.wheelbase), "unit": "m", "from": "convert --wheelbase"}
    for path, f, rep in jobs:             # every log checked before the first is written
        checked_log(args.source, f, rep)
        for written in (path, path.with_name(path.stem + ".import.json")) + ((path.with_suffix(".mcap"),) if args.mcap else ()):
            check_output_file(written, args.overwrite, inputs)
    with target:
        _write(jobs)
    if args.mcap:          # after every log is in place: an MCAP that fails loses none of them
        for path, f, _ in jobs:
            print(f"written: {write_log_mcap(f, path.with_suffix('.mcap'), str(args.source))}")
    return 0


def checked_log(source, f, rep: dict):
    """``f`` checked as a measured log (a LogError names ``source``); its warnings go into ``rep``."""
    try:
        checked = check_log(f, f"{source} ({rep['used']['how']})", ("t",))
    except LogError as exc:              # the refusal lists what the audit found besides
        raise with_findings(LogError(f"{exc}{_undeclared_clocks(f, rep)}"),
                            rep.get("audit", {}).get("findings", [])) from None
    rep.setdefault("notes", []).extend(n for n in checked.attrs.get("notes", []) if n.startswith("warning:"))
    return checked


def _undeclared_clocks(f, rep: dict) -> str:
    """'; ...' naming the tables whose time column had no unit and was taken as seconds, with the
    --time that declares it, when the log steps too slowly for seconds (check_log); '' else."""
    t = f["t"].to_numpy(float) if "t" in f and len(f) > 1 else None
    if t is None or not float(np.median(np.diff(t))) >= SECONDS_STEP_MAX:
        return ""
    said = [(name, str(table.get("time", "")).split(" [")[0]) for name, table in rep.get("tables", {}).items()
            if "no unit stated" in str(table.get("time", ""))]
    return "".join(f"; {name}'s time column {column!r} states no unit and was taken as seconds: "
                   f"--time '{name}.{column}[ms]' declares milliseconds" for name, column in said)


def write_converted(path: Path, f, rep: dict) -> None:
    """The log ``f`` as ``path`` (its units in the metadata) and its import report beside it."""
    path.parent.mkdir(parents=True, exist_ok=True)
    f.attrs["units"] = log_units(f)
    write_frame(path, f, float_format="%.9g")           # the units in its metadata (orchestrator.atomic_files)
    atomic_write(path.with_name(path.stem + ".import.json"),
                 lambda p: p.write_text(json.dumps(rep, indent=2, default=float)))


def _write(jobs) -> None:
    for path, f, rep in jobs:
        write_converted(path, f, rep)
        print(describe(rep))
        print(f"written: {path} ({len(f)} rows) and {path.with_name(path.stem + '.import.json').name}", file=sys.stdout)


def register(registry) -> None:
    registry.add_command("convert", f"a raw recording ({readers.names()}) as a measured log, or --list what it holds",
                         add_arguments, run)
    registry.add_section("vehicle", "measurements: steering_ratio (handwheel / road wheel) and wheelbase [m] for reading "
                                    "the vehicle's recordings")
