"""A raw field recording as one measured log, and a report of how: the readers' dispatcher.

The readers (measurements.recording_readers: ROS bags, ISO 11783-10 time logs, NMEA with CAN on one clock,
tables) each turn their files into Streams (measurements.streams); this module gives each file to
the first reader that claims it, has the first reader that holds files make the streams, finds
the quirks (measurements.quirks: spikes, position quantisation) and puts everything on one grid.
No reader imports it.

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

from agrobot.orchestrator.source_files import checked_path, regular_file, regular_files

from . import recording_readers as readers
from .audit import audit_frame, audit_streams
from .import_report import describe
from .log import LogError, check_log, read_log
from .modes import judged
from .options import ImportOptions
from .quirks import find_quirks, fixes_from_columns
from .runs import assemble
from .steering_scale import road_wheel_or_handwheel, turn_slope
from .streams import Streams

__all__ = ["ImportOptions", "describe", "import_recording", "import_runs", "is_recording", "load_log", "positions",
           "recording_files"]


def is_recording(source: Path) -> bool:
    """A folder, or a file that is a raw recording rather than a table (CSV/Parquet): its suffix
    is one a raw format's reader may claim (measurements.recording_readers)."""
    source = Path(source)
    return source.is_dir() or source.suffix.lower() in readers.raw_suffixes()


def recording_files(source: Path) -> dict[str, list[Path]]:
    """The files of a folder or the one file, by kind (every reader's, measurements.recording_readers): each
    file goes to the first reader that claims it, as does each folder inside (a rosbag2 folder); a
    folder that a reader claims whole (a rosbag2 folder) is that reader's alone."""
    source = checked_path(source, LogError)
    kinds: dict[str, list[Path]] = {k: [] for k in readers.kinds()}
    whole = readers.claimant(source) if source.is_dir() else None
    if whole is not None:
        kinds[whole.kind].append(source)
        return kinds
    files = regular_files(source) if source.is_dir() else [source]
    for p in files:
        if not source.is_dir():
            regular_file(p, LogError, None)        # before a byte is read; the size limit by kind below
        reader = readers.claimant(p)
        if reader is not None:
            kinds[reader.kind].append(p)
    for reader in readers.READERS:
        for p in kinds[reader.kind]:
            regular_file(p, LogError, "streamed" if reader.streamed else "whole")
    if source.is_dir():
        for d in sorted(source.iterdir()):
            reader = readers.claimant(d) if d.is_dir() else None
            if reader is not None:
                kinds[reader.kind].append(d)
    return kinds


def _streams(source: Path, options: ImportOptions) -> Streams:
    kinds = recording_files(source)
    reader = readers.first_held(kinds)
    if reader is None:
        raise LogError(readers.no_recording(source))
    streams = reader.streams(kinds, options, source)
    ignored = [p.name for k in ("table",) for p in kinds[k] if streams.report.get("files", {}).get(k) is None]
    if ignored and kinds["table"] and streams.report.get("files", {}).get("table") is None:
        streams.report.setdefault("notes", []).append(f"tables beside the recording not read: {', '.join(ignored[:6])}")
    streams = _steered(find_quirks(fixes_from_columns(streams, source), options), options, source)
    streams.report["audit"] = audit_streams(streams, options, source)     # spikes already masked
    return streams


def _steered(streams: Streams, options: ImportOptions, source: Path) -> Streams:
    """Handwheel angles to road-wheel angles: delta and delta_cmd divided by the steering ratio,
    the study's only where the log's turns say delta is the handwheel's (measurements.steering_scale);
    the choice is in the report's ``steering_ratio``; an angle the turns read in degrees is refused
    (LogError naming ``source`` and the column)."""
    ratio = options.steering_ratio or 1.0
    if options.steering_ratio_from == "study" and ratio != 1.0:
        column = streams.report.get("columns", {}).get("delta", "delta")
        handwheel, why = road_wheel_or_handwheel(turn_slope(streams.signals, streams.gnss, options.wheelbase), ratio,
                                                 f"{source}: delta ({column})")
        if handwheel is False:
            ratio = 1.0
        streams.report["steering_ratio"] = {
            "applied": ratio, "study": options.steering_ratio, "decided_from_turns": handwheel is not None,
            "text": (f"steering ratio {ratio:g}: " + ("delta taken as recorded; " if ratio == 1.0 else "delta divided by "
                     "it (handwheel -> road wheel); ") + f"the study's {options.steering_ratio:g} "
                     + ("passed over" if ratio == 1.0 else "applied" if handwheel else "applied (the turns cannot tell)")
                     + f": {why}; --steering-ratio R sets it (1: the angle as recorded)")}
    elif ratio != 1.0:
        streams.report["steering_ratio"] = {"applied": ratio, "decided_from_turns": False,
                                            "text": f"steering ratio {ratio:g} (given): delta divided by it "
                                                    f"(handwheel -> road wheel)"}
    if ratio == 1.0:
        return streams
    for column in ("delta_cmd", "delta"):
        if column in streams.signals:
            t, v = streams.signals[column]
            streams.signals[column] = (t, v / ratio)
            streams.resolution[column] = streams.resolution.get(column, 0.0) / ratio
            streams.report.setdefault("columns", {})[column] = (streams.report.get("columns", {}).get(column, column)
                                                                 + f"; / steering ratio {ratio:g} "
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
    if frame.attrs["declared"]:              # written beside the log: read back, the word still stands
        report["declared"] = dict(frame.attrs["declared"])
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
            frame.attrs["audit"] = audit_frame(frame)
        return judged(frame, source, recording), None
    frame, report = import_recording(source, recording)
    where = f"{source} ({report['used']['how']}, {report['used']['start']:.1f}-{report['used']['end']:.1f} s)"
    frame = check_log(frame, where, required, resample_jitter)
    report.setdefault("notes", []).extend(n for n in frame.attrs.get("notes", []) if n.startswith("warning:"))
    frame.attrs["resolution"] = dict(report.get("resolution", {}))
    frame.attrs["audit"] = list(report.get("audit", {}).get("findings", []))
    frame = judged(frame, source, recording)
    if frame.attrs.get("selection"):
        report["selection"] = list(frame.attrs["selection"])
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
