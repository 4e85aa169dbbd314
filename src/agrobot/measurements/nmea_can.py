"""NMEA files and CAN logs as one recording's streams: the receiver's epochs merged from every
NMEA file, the CAN columns decoded with the DBC (or --signal expressions), and the CAN clock put
on the receiver's UTC (measurements.clocks). Their two readers (NMEA, CAN) read their files
together, whichever of them makes the recording."""
from __future__ import annotations

import math
from collections import Counter
from pathlib import Path

import numpy as np
import pandas as pd

from .clocks import align_clocks
from .imu_axes import GRAVITY, axis_check, axis_siblings
from .log import LogError
from .options import ImportOptions
from .mdf4 import is_bus_logging
from .raw_can import (
    CAN_SUFFIXES,
    CANDUMP_FORMAT,
    CANRecording,
    choose_sources,
    list_can,
    load_dbc,
    merge,
    messages_of,
    read_can_file,
    series,
    signal_names,
)
from .raw_nmea import NMEA_SUFFIXES, NMEA_TEXT_SUFFIXES, list_nmea, looks_like_nmea, read_nmea_file
from .signal_expressions import evaluate, unknown_name
from .streams import HELD, Reader, Series, Streams, iso
from .tables import MDF_SUFFIXES, fixes_as_given


def nmea_can_recording(files: dict[str, list[Path]], options: ImportOptions, source: Path) -> Streams:
    """The streams of the NMEA files and CAN logs; ``--signal`` over NMEA alone takes receiver fields."""
    streams = nmea_can_streams(source, options, files)
    if not files["can"] and options.signals:
        _receiver_signals(streams, options, source)
    return streams


def nmea_can_streams(source: Path, options: ImportOptions, kinds: dict[str, list[Path]]) -> Streams:
    nmea_files, can_files = kinds["nmea"], kinds["can"]
    dbc_name = str(options.dbc) if options.dbc else "the project's agrobot_tractor.dbc"
    db, dbc_report = load_dbc(options.dbc) if can_files else (None, None)
    nmea = [read_nmea_file(p) for p in nmea_files]
    wanted = messages_of(db, choose_sources(db, dbc_name, list(options.signals))[0].values()) if can_files else None
    cans = [read_can_file(p, db, options.bus, wanted) for p in can_files]
    report: dict = {"source": str(source), "files": {"nmea": [str(n.path) for n in nmea], "can": [str(c.path) for c in cans]},
                    "dbc": dbc_name if cans else None, "notes": [x for n in nmea for x in n.notes],
                    "time_base": [x for n in nmea for x in n.time_base]}
    for c in cans:
        report["notes"] += c.notes
        if c.bad_lines:
            report["notes"].append(f"{c.path.name}: {c.counts['lines that are not frames']} line(s) that are not CAN "
                                   f"frames skipped (" + "; ".join(f"line {n}: {t!r}" for n, t in c.bad_lines)
                                   + f"); expected {CANDUMP_FORMAT}")
    if dbc_report is not None:
        report["dbc_load"] = dbc_report.as_dict()
    gnss, epochs, u0 = None, None, None
    if nmea:
        epochs = pd.concat([n.epochs for n in nmea]).sort_values("utc").drop_duplicates("utc").reset_index(drop=True)
        fix = epochs["quality"].to_numpy() > 0
        if fix.sum() < 2 and not cans:
            raise LogError(f"{source}: {int(fix.sum())} GNSS epochs with a fix ({len(epochs)} epochs); a recording of "
                           f"NMEA alone needs positions")
        counts: Counter = Counter()
        for n in nmea:
            counts.update(n.counts)
        quality = epochs["quality"].value_counts().sort_index()
        report["nmea"] = {"epochs": int(len(epochs)), "with_fix": int(fix.sum()),
                          "by_quality": {str(int(k)): int(v) for k, v in quality.items()},
                          "rate_hz": float(1.0 / np.median(np.diff(epochs["utc"]))) if len(epochs) > 1 else math.nan,
                          "sentences": dict(counts)}
        if fix.sum() >= 2:
            gnss = epochs.loc[fix].reset_index(drop=True)
            u0 = float(gnss["utc"].iloc[0])
            report["first_fix_utc"] = iso(u0)
        else:
            report["notes"].append(f"the NMEA holds {int(fix.sum())} epochs with a fix: no positions")
    raw: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    units: dict[str, str] = {}
    if cans:
        raw, units = _can_signals(source, cans, db, dbc_name, options, report)
    report["columns"] = dict(units)
    if gnss is not None:
        report["columns"].update({"x": "NMEA GGA latitude/longitude -> east of the run's first fix (pymap3d)",
                                  "y": "NMEA GGA latitude/longitude -> north of the run's first fix (pymap3d)",
                                  "t": "receiver UTC (GGA), s from the run's start"})
    can_breaks = [b for c in cans for b in c.breaks]
    if raw and gnss is not None:
        report["clocks"], to_utc = align_clocks(epochs, raw, u0, gnss)
        raw = {c: (to_utc(t), v) for c, (t, v) in raw.items()}
        for b in can_breaks:
            b["start"], b["end"] = float(to_utc(b["start"])), float(to_utc(b["end"]))
    elif raw:
        lo = min(float(t[0]) for t, _ in raw.values())
        report["clocks"] = {"reference": "the CAN logger's clock (no NMEA with a fix: not GPS time)"
                                         + ("" if lo > 1e8 else "; it counts from the logger's start, not a date"),
                            "can_clock": {"method": "the time base itself", "offset_s": 0.0, "drift_ppm": 0.0,
                                          "posix": lo > 1e8}}
        report["columns"]["t"] = "the CAN logger's timestamps, s from the run's start"
    else:
        report["clocks"] = {"reference": "receiver UTC (NMEA GGA time and RMC/ZDA date)"}
    return fixes_as_given(Streams(gnss, raw, report, set(HELD) & set(raw), {},
                                  [b for n in nmea for b in n.breaks] + can_breaks, groups={c: "can" for c in raw}), source)


def _can_signals(source: Path, cans: list[CANRecording], db, dbc_name: str, options: ImportOptions, report: dict):
    """Column -> (logger time, values in the column's unit) of every column the DBC (or --signal) gives, and how."""
    sources, unmapped, guessed = choose_sources(db, dbc_name, list(options.signals))
    report["can"] = {"frames": int(sum(c.counts["frames"] for c in cans)),
                     "decoded": int(sum(c.counts["decoded"] for c in cans)),
                     "unknown_ids": dict(sum((c.unknown_ids for c in cans), Counter()).most_common(8)),
                     "not_decoded": int(sum(c.counts["frames that do not decode"] for c in cans)),
                     "buses": dict(sum((c.buses for c in cans), Counter())),
                     "messages": {}, "columns_without_a_signal": unmapped}
    for c in cans:
        report["can"].setdefault("outside_declared_range", {}).update(c.outside_range)
        report["can"].setdefault("j1939_not_available", {}).update(c.not_available)
        report["can"].setdefault("sentinels", {}).update(c.sentinels)
        report["notes"] += [f"{name}: {d['count']} of {d['of']} values sit on the DBC's declared bound "
                            f"{', '.join(f'{v:g}' for v in d['values'])} (the field's raw extreme, beyond what a ground "
                            f"vehicle measures): the sender's 'no value', left out" for name, d in c.sentinels.items()]
    if options.bus is not None:
        report["can"]["bus"] = options.bus
    frames = merge(cans)
    known = signal_names(db)
    raw, units = {}, {}
    given_columns = {g.column for g in options.signals}
    for column, spec in sources.items():
        found = {}
        for name in spec.names:
            s = series(db, frames, name)
            if s is None:
                raise unknown_name(f"{source} (DBC {dbc_name})", spec, name, known)
            found[name] = s
        short = [n for n, s in found.items() if len(s.t) < 10]
        if short:
            what = (f"the CAN logs hold {len(found[short[0]].t)} frames with {short[0]} (column {column!r}, DBC "
                    f"{dbc_name}); messages found: {', '.join(sorted(frames)[:12]) or 'none'}"
                    + (f"; unknown identifiers: {', '.join(report['can']['unknown_ids'])}" if report['can']['unknown_ids'] else ""))
            if column in given_columns:
                raise LogError(f"{source}: {what}")
            report["can"]["columns_without_a_signal"][column] = what
            continue
        t, values, text = evaluate(spec, found, f"{source} (DBC {dbc_name})", options.wheelbase or 1.4,
                                   report.setdefault("sums", {}))
        raw[column] = (t, values)
        _yaw_axis(db, frames, spec, report)
        units[column] = text + ("; matched by name and unit (--signal to choose another)" if column in guessed else "")
        for name in spec.names:
            message = name.rsplit(".", 1)[0]
            tm = frames[message]["t"].to_numpy(float)
            report["can"]["messages"][message] = {"frames": int(len(tm)),
                                                  "rate_hz": float(1.0 / np.median(np.diff(tm))) if len(tm) > 1 else math.nan}
    if not raw:
        unknown = report["can"]["unknown_ids"]
        raise LogError(f"{source}: no CAN frame decodes to a column of the log with {dbc_name} "
                       f"({report['can']['decoded']} of {report['can']['frames']} frames decoded"
                       + (f"; unknown identifiers: {', '.join(unknown)}" if unknown else "")
                       + "); give the vehicle's DBC with --dbc, and map signals with --signal COLUMN=Message.Signal")
    return raw, units


def _yaw_axis(db, frames: dict, spec, report: dict) -> None:
    """A yaw rate read from one axis of a CAN IMU whose message (or another) carries its
    accelerometer: the vertical axis by gravity checked against it (measurements.imu_axes); a
    mismatch goes to report["imu_axes"] for the audit to name."""
    if spec.column != "yaw_rate" or len(spec.names) != 1:
        return
    name = spec.names[0]
    names = [f"{m}.{c}" for m, table in frames.items() for c in table.columns if c != "t"]
    found = axis_siblings(name, [n for n in names if n.rsplit(".", 1)[0] == name.rsplit(".", 1)[0]] or names)
    if found is None:
        return
    axis, accel = found
    readings = {a: series(db, frames, n) for a, n in accel.items()}
    if any(r is None or len(r.values) < 20 for r in readings.values()):
        return
    scale = {a: GRAVITY if (r.unit or "").strip().lower() in ("g", "gn") else 1.0 for a, r in readings.items()}
    check = axis_check(spec.column, name, axis, accel, {a: r.values * scale[a] for a, r in readings.items()})
    if check is not None:
        report.setdefault("imu_axes", []).append(check)


RECEIVER_FIELDS = {"speed": "m/s", "course": "rad", "heading": "rad", "height": "m", "quality": "", "position_std": "m"}


def _receiver_signals(streams: Streams, options: ImportOptions, source: Path) -> None:
    """``--signal`` over an NMEA recording: the receiver's fields (gnss.speed, gnss.course,
    gnss.heading, gnss.height, gnss.quality, gnss.position_std; SI); a name it does not hold is
    refused with the near names."""
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
        t, values, how = evaluate(spec, {n: series[n] for n in spec.names}, str(source), options.wheelbase or 1.4,
                                  streams.report.setdefault("sums", {}))
        streams.signals[spec.column] = (t, values)
        streams.groups[spec.column] = "gnss"
        streams.report.setdefault("columns", {})[spec.column] = how


class _Together(Reader):
    """A reader whose files are read with the other's: NMEA and CAN make one recording."""

    streamed = True

    def streams(self, files: dict[str, list[Path]], options, source: Path) -> Streams:
        return nmea_can_recording(files, options, source)


class NMEAReader(_Together):
    """NMEA 0183 files: by their suffix, or a .log/.txt whose first lines are sentences."""

    kind, name, listed = "nmea", "NMEA", "NMEA sentences and fixes"
    files = "*.nmea, *.gps, *.nma, a .log/.txt of sentences"
    suffixes = NMEA_SUFFIXES + NMEA_TEXT_SUFFIXES

    def claims(self, path: Path) -> bool:
        suffix = path.suffix.lower()
        return ((suffix in NMEA_SUFFIXES and not path.is_dir())
                or (suffix in NMEA_TEXT_SUFFIXES and looks_like_nmea(path)))

    def listing(self, paths: list[Path], options, source: Path) -> list[str]:
        return list_nmea(paths)


class CANReader(_Together):
    """CAN logs python-can reads (candump, Vector, PEAK), and MDF4 files of bus logging."""

    kind, name, listed = "can", "CAN logs", "CAN messages and signals with units and rates"
    files = "*.log candump, *.asc, *.blf, *.trc, MDF4 bus logging *.mf4/*.mdf"
    suffixes = CAN_SUFFIXES + MDF_SUFFIXES

    def claims(self, path: Path) -> bool:
        return super().claims(path) and (path.suffix.lower() in CAN_SUFFIXES or is_bus_logging(path))

    def listing(self, paths: list[Path], options, source: Path) -> list[str]:
        return list_can(paths, options)


NMEA, CAN = NMEAReader(), CANReader()
