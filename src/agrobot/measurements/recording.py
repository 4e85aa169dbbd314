"""A raw field recording as one measured log, and a report of how: the readers' dispatcher.

The readers (measurements.raw_nmea, raw_can, rosbag, isoxml_log, tables) each turn their files
into Streams (measurements.streams); this module chooses them by the files it finds, merges NMEA
with CAN on one clock, finds the quirks (measurements.quirks: spikes, position quantisation) and
puts everything on one grid. No reader imports it.

Time base: the receiver's UTC where there is one (a fix is valid at its epoch's time), else the
source's own clock (a logger's boot-time clock is reported as such, never as a 1970 date); the
clocks are aligned by measurements.clocks, the streams put on one grid and cut into runs by
measurements.runs, and the report printed by measurements.import_report.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

from .import_report import describe
from .log import LogError, check_log, read_log
from .mdf4 import is_bus_logging
from .nmea_can import nmea_can_streams
from .options import ImportOptions
from .quirks import find_quirks, fixes_from_columns
from .raw_can import CAN_SUFFIXES
from .raw_nmea import looks_like_nmea
from .runs import assemble
from agrobot.orchestrator.source_files import checked_path, regular_file, regular_files
from .streams import Streams
from .tables import MDF_SUFFIXES, TABLE_SUFFIXES, TEXT_SUFFIXES, looks_like_table

__all__ = ["ImportOptions", "describe", "import_recording", "import_runs", "is_recording", "load_log", "positions",
           "recording_files"]

NMEA_SUFFIXES = (".nmea", ".gps", ".nma")


BAG_SUFFIXES = (".bag", ".db3", ".mcap")
KINDS = ("nmea", "can", "bag", "isoxml", "table")


def is_recording(source: Path) -> bool:
    """A folder, or a file that is a raw recording rather than a table (CSV/Parquet)."""
    source = Path(source)
    suffix = source.suffix.lower()
    return source.is_dir() or suffix in NMEA_SUFFIXES + CAN_SUFFIXES + BAG_SUFFIXES + MDF_SUFFIXES + (".txt", ".xml", ".bin")


def recording_files(source: Path) -> dict[str, list[Path]]:
    """The files of a folder or the one file, by kind (KINDS): NMEA (a ``.log``/``.txt`` holding
    sentences counts), CAN logs, ROS bags (ROS 1 ``.bag``, ROS 2 ``.db3``/``.mcap`` or a rosbag2
    folder with metadata.yaml), ISO 11783-10 TaskData (TASKDATA.XML, or TLGnnnnn.xml/.bin) and
    tables (CSV, TSV, Parquet)."""
    source = checked_path(source, LogError)
    kinds: dict[str, list[Path]] = {k: [] for k in KINDS}
    if source.is_dir() and (source / "metadata.yaml").is_file():
        kinds["bag"].append(source)                   # a rosbag2 folder is one bag
        return kinds
    files = regular_files(source) if source.is_dir() else [source]
    for p in files:
        if not source.is_dir():
            regular_file(p, LogError, None)        # before a byte is read; the size limit by kind below
        suffix, name = p.suffix.lower(), p.name.upper()
        if suffix in NMEA_SUFFIXES or (suffix in (".log", ".txt") and looks_like_nmea(p)):
            kinds["nmea"].append(p)
        elif suffix in CAN_SUFFIXES:
            kinds["can"].append(p)
        elif suffix in MDF_SUFFIXES:                  # bus logging is a CAN log, signals are tables
            kinds["can" if is_bus_logging(p) else "table"].append(p)
        elif suffix in BAG_SUFFIXES:
            kinds["bag"].append(p)
        elif name == "TASKDATA.XML" or (name.startswith("TLG") and suffix in (".xml", ".bin")):
            kinds["isoxml"].append(p)
        elif suffix in TABLE_SUFFIXES or (suffix in TEXT_SUFFIXES and looks_like_table(p)):
            kinds["table"].append(p)          # a table by its content: a .txt dump of one topic field
    for kind, paths in kinds.items():
        for p in paths:
            regular_file(p, LogError, "streamed" if kind in ("nmea", "can", "bag") else "whole")
    if source.is_dir():
        kinds["bag"] += [d for d in sorted(source.iterdir()) if d.is_dir() and (d / "metadata.yaml").is_file()]
    return kinds


def _streams(source: Path, options: ImportOptions) -> Streams:
    kinds = recording_files(source)
    if kinds["bag"]:
        from .rosbag import bag_streams

        streams = bag_streams(kinds["bag"], options, source)
    elif kinds["isoxml"]:
        from .isoxml_log import timelog_streams

        streams = timelog_streams(kinds["isoxml"], options, source)
    elif kinds["nmea"] or kinds["can"]:
        streams = nmea_can_streams(source, options, kinds)
        if not kinds["can"] and options.signals:
            _receiver_signals(streams, options, source)
    elif kinds["table"]:
        from .tables import table_streams

        streams = table_streams(kinds["table"], options, source)
    else:
        raise LogError(f"{source}: no recording in it: expected NMEA files (*.nmea, *.gps, or a .log/.txt holding "
                       f"sentences), CAN logs (*.log candump, *.asc, *.blf, *.trc), a ROS bag (*.bag, *.db3, *.mcap, "
                       f"or a rosbag2 folder), an ISO 11783-10 TaskData (TASKDATA.XML with TLG files) or tables "
                       f"(*.csv, *.tsv, *.parquet)")
    ignored = [p.name for k in ("table",) for p in kinds[k] if streams.report.get("files", {}).get(k) is None]
    if ignored and kinds["table"] and streams.report.get("files", {}).get("table") is None:
        streams.report.setdefault("notes", []).append(f"tables beside the recording not read: {', '.join(ignored[:6])}")
    streams = _steered(find_quirks(fixes_from_columns(streams, source), options), options)
    from .audit import audit_streams

    streams.report["audit"] = audit_streams(streams, options, source)     # spikes already masked
    return streams


RECEIVER_FIELDS = {"speed": "m/s", "course": "rad", "heading": "rad", "height": "m", "quality": "", "position_std": "m"}


def _receiver_signals(streams: Streams, options: ImportOptions, source: Path) -> None:
    """``--signal`` over an NMEA recording: the receiver's fields (gnss.speed, gnss.course,
    gnss.heading, gnss.height, gnss.quality, gnss.position_std; SI); a name it does not hold is
    refused with the near names."""
    from .signal_expressions import evaluate, unknown_name
    from .streams import Series

    g = streams.gnss
    if g is None:
        raise LogError(f"{source}: --signal {options.signals[0]}: the NMEA holds no fix to take a signal from")
    utc = g["utc"].to_numpy(float)
    series = {}
    for name, unit in RECEIVER_FIELDS.items():
        x = g[name].to_numpy(float)
        ok = np.isfinite(x)
        if ok.sum() >= 2:
            series[f"gnss.{name}"] = Series(utc[ok], x[ok], unit or None, f"gnss.{name}")
    for spec in options.signals:
        for name in spec.names:
            if name not in series:
                raise unknown_name(str(source), spec, name, sorted(series), "receiver field")
        t, values, how = evaluate(spec, {n: series[n] for n in spec.names}, str(source), options.wheelbase or 1.4)
        streams.signals[spec.column] = (t, values)
        streams.groups[spec.column] = "gnss"
        streams.report.setdefault("columns", {})[spec.column] = how


def _steered(streams: Streams, options: ImportOptions) -> Streams:
    """Handwheel angles to road-wheel angles: delta and delta_cmd divided by the steering ratio."""
    if not options.steering_ratio or options.steering_ratio == 1.0:
        return streams
    for column in ("delta_cmd", "delta"):
        if column in streams.signals:
            t, v = streams.signals[column]
            streams.signals[column] = (t, v / options.steering_ratio)
            streams.resolution[column] = streams.resolution.get(column, 0.0) / options.steering_ratio
            streams.report.setdefault("columns", {})[column] = (streams.report.get("columns", {}).get(column, column)
                                                                 + f"; / steering ratio {options.steering_ratio:g} "
                                                                   f"(handwheel -> road wheel)")
    return streams


def import_recording(source: str | Path, options: ImportOptions | None = None) -> tuple[pd.DataFrame, dict]:
    """(canonical log t, delta_cmd, delta, v, yaw_rate, x, y; the import report)."""
    options = (options or ImportOptions()).for_vehicle()
    frame, report = assemble(Path(source), _checked(Path(source), options), options)
    return _with_audit(frame, report, options), report


def import_runs(source: str | Path, options: ImportOptions | None = None) -> list[tuple[pd.DataFrame, dict]]:
    """Every run of a recording as (log, report), the files read once."""
    source, options = Path(source), (options or ImportOptions()).for_vehicle()
    streams = _checked(source, options)
    first = assemble(source, streams, options)
    runs = [first if r["run"] == first[1]["used"].get("run") else assemble(source, streams, replace(options, run=r["run"]))
            for r in first[1]["runs"]]
    return [(_with_audit(f, rep, options), rep) for f, rep in runs]


def _with_audit(frame: pd.DataFrame, report: dict, options: ImportOptions) -> pd.DataFrame:
    """The audit's findings on the log (frame.attrs["audit"], measurements.audit), and the units
    the user declared (frame.attrs["declared"]: a unit heuristic warns on them, never refuses)."""
    frame.attrs["audit"] = list(report.get("audit", {}).get("findings", []))
    frame.attrs["declared"] = {s.column: s.unit for s in options.signals if s.unit}
    return frame


def _checked(source: Path, options: ImportOptions) -> Streams:
    if options.rate is not None and not 1.0 <= options.rate <= 200.0:
        raise LogError(f"--rate {options.rate:g}: expected 1 to 200 Hz")
    if not 0.0 <= options.max_gap <= 60.0:
        raise LogError(f"--max-gap {options.max_gap:g}: expected 0 to 60 s (a channel's gap bridged up to this)")
    return _streams(source, options)


def load_log(source: str | Path, required: tuple[str, ...] = ("t",), resample_jitter: bool = False,
             recording=None) -> tuple[pd.DataFrame, dict | None]:
    """(log, import report): a table (CSV/Parquet) through read_log, or a raw field recording
    (a folder of NMEA files and CAN logs, or one such file) through
    measurements.recording.import_recording with ``recording`` (ImportOptions), then the same
    checks. The report is None for a table. The log carries its audit (frame.attrs["audit"],
    measurements.audit): the import's, the one written beside it, or that of its own columns."""
    source = Path(source)
    if not is_recording(source) and not (recording is not None and recording.maps_a_table):
        frame = read_log(source, required, resample_jitter)
        if "audit" not in frame.attrs:        # a table as it is: the audit of its own columns
            from .audit import audit_frame

            frame.attrs["audit"] = audit_frame(frame)
        return frame, None
    frame, report = import_recording(source, recording)
    where = f"{source} ({report['used']['how']}, {report['used']['start']:.1f}-{report['used']['end']:.1f} s)"
    frame = check_log(frame, where, required, resample_jitter)
    report.setdefault("notes", []).extend(n for n in frame.attrs.get("notes", []) if n.startswith("warning:"))
    frame.attrs["resolution"] = dict(report.get("resolution", {}))
    frame.attrs["audit"] = list(report.get("audit", {}).get("findings", []))
    return frame, report


def positions(source: str | Path, options: ImportOptions | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
    """(times [s], latitude, longitude [deg], report) of every fix of a recording, whole (no run
    chosen): the track a field is made of."""
    source = Path(source)
    options = (options or ImportOptions()).for_vehicle()
    streams = _checked(source, options)
    if streams.gnss is None:
        raise LogError(f"{source}: no positions in it (NMEA with a fix, a NavSatFix topic, a TLG position, or "
                       f"lat/lon columns: --signal lat=TABLE.COLUMN --signal lon=TABLE.COLUMN)")
    g = streams.gnss
    report = streams.report
    width = [v for c, (_, v) in streams.signals.items() if c.startswith("ddi0067")]   # ISO 11783 actual working width, m (SI)
    if width and np.isfinite(width[0]).any():
        report["working_width_m"] = float(np.nanmedian(width[0]))
    return g["utc"].to_numpy(float), g["lat"].to_numpy(float), g["lon"].to_numpy(float), report
