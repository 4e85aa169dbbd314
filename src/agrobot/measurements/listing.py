"""``convert SOURCE --list``: what a recording holds, so that a user can choose its signals: NMEA
sentences and fixes, CAN messages and signals (units, declared ranges, the values seen, rates,
buses) with the DBC's load report, ROS topics with their types and numeric fields, ISO 11783-10
time logs with their DDIs, table columns with their ranges and the time found."""
from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np

from .log import LogError
from .streams import iso


def list_source(source: Path, options) -> list[str]:
    from .recording import recording_files

    kinds = recording_files(Path(source))
    lines: list[str] = []
    if kinds["bag"]:
        from .rosbag import list_bag

        lines += list_bag(kinds["bag"])
    if kinds["nmea"]:
        lines += _nmea(kinds["nmea"])
    if kinds["can"]:
        lines += _can(kinds["can"], options)
    if kinds["isoxml"]:
        lines += _isoxml(kinds["isoxml"], source)
    if kinds["table"]:
        lines += _tables(kinds["table"], options)
    if not lines:
        raise LogError(f"{source}: no recording in it (NMEA, CAN logs, ROS bags, ISO 11783-10 TaskData or tables)")
    return lines


def _nmea(paths: list[Path]) -> list[str]:
    from .raw_nmea import read_nmea_file

    out = []
    for p in paths:
        try:
            rec = read_nmea_file(p)
        except LogError as exc:
            out.append(f"NMEA {p.name}: not read: {exc}")
            continue
        e = rec.epochs
        fix = e[e["quality"] > 0]
        rate = 1.0 / float(np.median(np.diff(e["utc"]))) if len(e) > 1 else float("nan")
        out.append(f"NMEA {p.name}: {len(e)} epochs ({len(fix)} with a fix) at {rate:.3g} Hz from {iso(float(e['utc'].iloc[0]))}, "
                   f"{e['utc'].iloc[-1] - e['utc'].iloc[0]:.1f} s; fix qualities "
                   + ", ".join(f"{int(k)}: {int(v)}" for k, v in e["quality"].value_counts().sort_index().items()))
        out.append("  sentences: " + ", ".join(f"{k} {v}" for k, v in rec.counts.most_common() if k not in ("lines",)))
        for c in ("speed", "heading", "position_std"):
            if e[c].notna().any():
                out.append(f"  {c}: {e[c].min():.4g} .. {e[c].max():.4g}")
        out += [f"  note: {n}" for n in rec.notes]
    return out


def _can(paths: list[Path], options) -> list[str]:
    from .raw_can import load_dbc, read_can_file

    db, report = load_dbc(options.dbc)
    out = report.lines() if report is not None else ["DBC: the project's agrobot_tractor.dbc"]
    out[0] += f": {len(db.messages)} messages"
    for p in paths:
        try:
            rec = read_can_file(p, db, options.bus)
        except LogError as exc:
            if "choose one with --bus" not in str(exc):
                raise
            rec = None
            out.append(f"CAN log {p.name}: {exc}")
            for bus in _buses(p):
                out += _can_one(read_can_file(p, db, bus), db, f" on bus {bus}")
            continue
        out += _can_one(rec, db, "")
    return out


def _buses(path: Path) -> list[str]:
    import can

    seen: Counter = Counter()
    for frame in can.LogReader(str(path)):
        seen[str(frame.channel)] += 1
    return [b for b, _ in seen.most_common()]


def _can_one(rec, db, where: str) -> list[str]:
    out = [f"CAN log {rec.path.name}{where}: {rec.counts['frames']} frames, {rec.counts['decoded']} decoded; buses "
           + ", ".join(f"{b} ({n})" for b, n in rec.buses.most_common())
           + (f"; identifiers the DBC does not hold: {', '.join(f'{k} ({v})' for k, v in rec.unknown_ids.most_common(8))}"
              if rec.unknown_ids else "")]
    by_name = {m.name: m for m in db.messages}
    for name, table in sorted(rec.messages.items()):
        m = by_name[name]
        t = table["t"].to_numpy(float)
        rate = 1.0 / float(np.median(np.diff(t))) if len(t) > 1 else float("nan")
        out.append(f"  {name} ({m.frame_id:#x}{', 29-bit' if m.is_extended_frame else ''}): {len(t)} frames at {rate:.3g} Hz"
                   + (", multiplexed" if m.is_multiplexed() else ""))
        for s in m.signals:
            if s.name not in table:
                continue
            x = table[s.name].to_numpy(float)
            seen = f"{np.nanmin(x):.6g} .. {np.nanmax(x):.6g}" if np.isfinite(x).any() else "no value"
            declared = f"declared [{s.minimum:g}|{s.maximum:g}]" if s.minimum is not None and s.maximum is not None else ""
            flag = rec.outside_range.get(f"{name}.{s.name}")
            out.append(f"    {name}.{s.name} [{(s.unit or '').strip() or 'no unit'}]: {seen} {declared}"
                       + (f"; {flag['outside']} of {flag['of']} values outside it (kept)" if flag else ""))
    return out


def _isoxml(paths: list[Path], source: Path) -> list[str]:
    from .isoxml_log import read_timelog, timelog_files

    out = []
    for head in timelog_files(paths):
        try:
            table, info = read_timelog(head)
        except LogError as exc:
            out.append(f"time log {head.name}: not read: {exc}")
            continue
        out.append(f"time log {head.name}: {info['records']} records from {iso(float(table['utc'].min()))}, "
                   f"{table['utc'].max() - table['utc'].min():.0f} s")
        for c, unit in info["units"].items():
            x = table[c].to_numpy(float)
            seen = f"{np.nanmin(x):.6g} .. {np.nanmax(x):.6g}" if np.isfinite(x).any() else "no value"
            out.append(f"  {c}: {seen} [{unit}]")
    if not out:
        out.append(f"{source}: a TaskData without time logs")
    return out


def _tables(paths: list[Path], options) -> list[str]:
    from .tables import describe_table, read_table, read_tables

    try:
        tables = read_tables(paths, options.time, options.rate, paths[0].parent,
                             tuple(n for s in options.signals for n in s.names))
    except LogError as exc:                   # each table alone, saying why the set has no clock
        out = [f"tables: {exc}"]
        for p in paths:
            try:
                out += describe_table(read_table(p))
            except LogError as why:
                out.append(f"table {p.name}: not read: {why}")
        return out
    return [line for t in tables for line in describe_table(t)]
