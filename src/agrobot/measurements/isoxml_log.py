"""ISO 11783-10 time logs (TLGnnnnn.xml header + TLGnnnnn.bin records) as a recording.

The TaskData itself (TASKDATA.XML) is read with the ``isoxml`` package (its typed models and its
DDI dictionary: name, unit, bit resolution); the binary time logs it does not read, so this
module does, after ISO 11783-10's layout. The header's ``TIM`` names what each record holds: an
attribute written empty is logged per record, one with a value is fixed. A record is, little-endian:

- TIM A (start): uint32 ms since midnight, uint16 days since 1980-01-01;
- PTN A north, B east: int32 x 1e-7 deg; C up: int32 mm; D status: uint8; E PDOP, F HDOP: uint16 x
  0.1; G satellites: uint8; H GPS UTC time: uint32 ms; I GPS UTC date: uint16 days since 1980;
- uint8 N, then N x (uint8 DLV index in the header's order, int32 value).

Each DLV becomes a column named after its DDI (``ddi0074_total_area`` style) with the value
times the DDI's bit resolution, converted from the DDI's unit (ISO 11783-11: mm/s, mm, 0.001 deg,
r/min ...) to SI (m/s, m, rad, rad/s; a unit pint does not know is kept and named); the machine's
measured speed (DDI 397, Actual Speed) is the log's ``v``; ``--signal COLUMN=EXPR`` maps any
column (by its name or ``DDInnn``). The position goes to x/y about the first fix, the speed
between fixes to ``track_speed``. Where the records carry the GNSS time (PTN H, I), the
terminal's clock (TIM) is compared with it and the offset named. PTN D (status) is ISO's:
0 no GPS, 1 GNSS, 2 DGNSS, 3 precise GNSS, 4 RTK fixed, 5 RTK float, ... 15 not available; it is
kept as ``fix_quality`` with GGA's codes where they agree (0-5) and 15 -> NaN (unknown).

Imported where used: isoxml (the fields extra).
"""
from __future__ import annotations

import datetime
import re
import struct
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pandas as pd

from agrobot.orchestrator.source_files import regular_file
from agrobot.orchestrator.units import base_unit

from .log import LogError
from .quirks import ordered_in_time
from .signal_expressions import SignalSpec, evaluate, unknown_name
from .streams import Reader, Series, Streams, iso

EPOCH_1980 = datetime.datetime(1980, 1, 1, tzinfo=datetime.timezone.utc).timestamp()
PTN_LAYOUT = {"A": ("<i", 1e-7), "B": ("<i", 1e-7), "C": ("<i", 1e-3), "D": ("<B", 1.0), "E": ("<H", 0.1),
              "F": ("<H", 0.1), "G": ("<B", 1.0), "H": ("<I", 1e-3), "I": ("<H", 1.0)}
SPEED_DDI = 397                 # Actual Speed [mm/s]: the machine's measured speed
UNIT_ALIASES = {"r/min": "rpm", "/s": "1/s", "n.a.": "", "#": ""}
PTN_NAMES = {"A": "lat", "B": "lon", "C": "height", "D": "status", "E": "pdop", "F": "hdop", "G": "satellites",
             "H": "gps_time_ms", "I": "gps_date"}


def ddi_name(ddi: int) -> tuple[str, str, float]:
    """(column name, unit, bit resolution) of a DDI, from the isoxml package's dictionary."""
    from isoxml.models.ddi_entities import DDEntity

    try:
        e = DDEntity.from_id(ddi)
        name, unit, res = e.name, e.unit, float(e.bit_resolution)
    except KeyError:
        name, unit, res = "proprietary", "", 1.0
    words = re.sub(r"\s+as\s+\[.*?\]$", "", name)
    slug = re.sub(r"[^a-z0-9]+", "_", words.lower()).strip("_")[:48]
    return f"ddi{ddi:04d}_{slug}", unit, res


def read_header(path: Path) -> tuple[list[str], list[tuple[int, str]], dict]:
    """(PTN attributes logged per record, [(DDI, element)] of the DLVs, fixed values) of a
    TLG header; a LogError names the file and the element when it is not a time-log header."""
    regular_file(path, LogError)
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError, LookupError, ValueError) as exc:      # LookupError: an unknown encoding
        raise LogError(f"{path}: not a readable XML file: {exc}") from None
    if root.tag != "TIM":
        raise LogError(f"{path}: expected a time-log header (root element TIM), found <{root.tag}>")
    if root.get("A") != "":
        raise LogError(f"{path}: TIM A (the start time) is not logged per record (A=\"\"); found A={root.get('A')!r}")
    ptn = root.find("PTN")
    logged = [k for k in "ABCDEFGHI" if ptn is not None and ptn.get(k) == ""]
    fixed = {PTN_NAMES[k]: ptn.get(k) for k in "ABCDEFGHI" if ptn is not None and ptn.get(k) not in (None, "")}
    dlvs = []
    for i, dlv in enumerate(root.findall("DLV")):
        try:
            dlvs.append((int(dlv.get("A"), 16), dlv.get("C", "")))
        except (TypeError, ValueError):
            raise LogError(f"{path}: DLV {i}: attribute A must be a DDI in hex, got {dlv.get('A')!r}") from None
    return logged, dlvs, fixed


def read_binary(path: Path, logged: list[str], n_dlv: int) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]:
    """(POSIX times, PTN columns, DLV values (records x n_dlv, NaN where a record has none))."""
    data = regular_file(path, LogError).read_bytes()
    times, ptn_rows, dlv_rows = [], [], []
    i, n = 0, len(data)
    layout = [(k, PTN_LAYOUT[k]) for k in logged]
    size = 6 + sum(struct.calcsize(fmt) for _, (fmt, _) in layout) + 1
    record = 0
    while i < n:
        if i + size > n:
            raise LogError(f"{path}: record {record} at byte {i} is cut off ({n - i} bytes left, the header's TIM/PTN "
                           f"need {size}); the binary does not match its header")
        ms, days = struct.unpack_from("<IH", data, i)
        i += 6
        values = []
        for _, (fmt, scale) in layout:
            values.append(struct.unpack_from(fmt, data, i)[0] * scale)
            i += struct.calcsize(fmt)
        count = data[i]
        i += 1
        if i + 5 * count > n:
            raise LogError(f"{path}: record {record} at byte {i - 1} says {count} values but {n - i} bytes remain; "
                           f"the binary does not match its header")
        row = np.full(n_dlv, np.nan)
        for _ in range(count):
            index, value = struct.unpack_from("<Bi", data, i)
            i += 5
            if index >= n_dlv:
                raise LogError(f"{path}: record {record} refers to DLV {index}; the header lists {n_dlv} "
                               f"(0 to {n_dlv - 1}): the binary does not match its header")
            row[index] = value
        times.append(EPOCH_1980 + days * 86400.0 + ms * 1e-3)
        ptn_rows.append(values)
        dlv_rows.append(row)
        record += 1
    if not times:
        raise LogError(f"{path}: no record in it")
    ptn = np.array(ptn_rows, float).reshape(len(times), len(layout))
    return np.array(times), {PTN_NAMES[k]: ptn[:, j] for j, (k, _) in enumerate(layout)}, np.array(dlv_rows)


def read_timelog(xml: Path) -> tuple[pd.DataFrame, dict]:
    """One time log as a table (utc, lat, lon, height, status ..., a column per DLV) and its
    columns' units."""
    logged, dlvs, fixed = read_header(xml)
    binary = xml.with_suffix(".bin") if xml.with_suffix(".bin").exists() else xml.with_suffix(".BIN")
    if not binary.exists():
        raise LogError(f"{xml}: its binary {xml.with_suffix('.bin').name} is missing")
    t, ptn, values = read_binary(binary, logged, len(dlvs))
    table = pd.DataFrame({"utc": t, **ptn})
    units = {}
    names = [ddi_name(d) for d, _ in dlvs]
    count = {}
    si, ddis = {}, {}
    for (ddi, element), (name, unit, res), column in zip(dlvs, names, values.T):
        count[name] = count.get(name, 0) + 1
        label = name if sum(n == name for n, _, _ in names) == 1 else f"{name}_{element.lower().replace('-', '')}"
        factor, si_unit = ddi_to_si(unit)
        table[label] = column * res * factor
        si[label], ddis[label] = si_unit, ddi
        units[label] = (f"{unit or '-'} (DDI {ddi} 0x{ddi:04X}, element {element or '-'}, resolution {res:g})"
                        + (f" -> {si_unit}" if factor != 1.0 else "" if si_unit is not None else
                           ": a unit pint does not know, kept as the terminal wrote it"))
    return table, {"units": units, "fixed": fixed, "records": int(len(t)), "si": si, "ddi": ddis}


def ddi_to_si(unit: str) -> tuple[float, str | None]:
    """(factor, SI unit) of an ISO 11783-11 unit (mm/s -> 0.001 m/s, 0.001 deg -> rad ...);
    (1, None) for one pint does not know."""
    text = UNIT_ALIASES.get((unit or "").strip(), (unit or "").strip())
    try:
        b = base_unit(text)
    except Exception:                                # noqa: BLE001 - pint raises several kinds
        b = None
    if b is None or b.offset:
        return 1.0, None
    names = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")
    parts = [f"{n}^{e}" if e != 1 else n for n, e in zip(names, b.exponents) if e > 0]
    below = [f"{n}^{-e}" if e != -1 else n for n, e in zip(names, b.exponents) if e < 0]
    return b.factor, ("*".join(parts) or "1") + ("/" + "/".join(below) if below else "")


def timelog_files(paths: list[Path]) -> list[Path]:
    """The TLG headers among the files (a TASKDATA.XML names them; the headers are found beside it)."""
    heads = sorted({p for p in paths if p.name.upper().startswith("TLG") and p.suffix.lower() == ".xml"})
    if not heads:
        for p in paths:
            if p.name.upper().startswith("TLG") and p.suffix.lower() == ".bin":
                heads.append(p.with_suffix(".xml"))
        for task in [p for p in paths if p.name.upper() == "TASKDATA.XML"]:
            heads += sorted(task.parent.glob("TLG*.xml")) + sorted(task.parent.glob("TLG*.XML"))
    return sorted(set(heads))


def timelog_streams(paths: list[Path], options, source: Path):
    """The recording's streams from ISO 11783-10 time logs (one, or every one of a TaskData:
    the longest is used unless --run/--time-range says otherwise, each being one run)."""

    heads = timelog_files(paths)
    if not heads:
        raise LogError(f"{source}: a TaskData without time logs (no TLGnnnnn.xml/.bin beside it)")
    tables = [(h, *read_timelog(h)) for h in heads]
    notes = _task_notes(paths, heads) + _repeated_logs(tables)
    head, table, info = max(tables, key=lambda x: len(x[1])) if len(tables) > 1 else tables[0]
    table["line"] = np.arange(len(table))
    quirks = []
    padding = (table["utc"] == EPOCH_1980).to_numpy()
    if padding.any():
        i = np.flatnonzero(padding)
        quirks.append(f"{head.stem}: {len(i)} record(s) dated 1980-01-01 00:00:00.000 (time 0: zero padding or an unset "
                      f"clock), records {i[0]}-{i[-1]}: masked")
        table = table.loc[~padding].reset_index(drop=True)
    table, breaks = ordered_in_time(table, head.stem, notes, what="record")
    report: dict = {"source": str(source), "files": {"isoxml": [str(h) for h, _, _ in tables]}, "dbc": None,
                    "notes": notes, "quirks": quirks, "timelogs": {h.stem: {"records": i["records"], "start": iso(float(t["utc"].min())),
                                                        "end": iso(float(t["utc"].max()))} for h, t, i in tables},
                    "timelog_used": head.stem,
                    "clocks": {"reference": "the task controller's TIM start times (ms since midnight, days since 1980)"}}
    if len(tables) > 1:
        report["notes"].append(f"{len(tables)} time logs; the longest, {head.stem} ({len(table)} records), is used "
                               f"(convert one file to choose another)")
    gnss = None
    if "lat" in table and "lon" in table:
        ok = (table["lat"].abs() > 0) | (table["lon"].abs() > 0)
        status = table["status"].to_numpy(float) if "status" in table else np.full(len(table), 15.0)
        quality = np.where(status <= 5, status, np.nan)
        gnss = pd.DataFrame({"utc": table["utc"][ok], "lat": table["lat"][ok], "lon": table["lon"][ok],
                             "height": table["height"][ok] if "height" in table else 0.0,
                             "quality": quality[ok.to_numpy()],           # 15, not available: NaN
                             "speed": np.nan, "course": np.nan, "heading": np.nan, "position_std": np.nan}).reset_index(drop=True)
        if np.all(status[ok.to_numpy()] == 15):
            report["notes"].append("PositionStatus is 15 (not available) in every record: the receiver's fix quality "
                                   "was not logged")
    signals = {c: (table["utc"].to_numpy(float), table[c].to_numpy(float)) for c in info["units"]
               if np.isfinite(table[c]).sum() >= 2}
    signals = {c: (t[np.isfinite(v)], v[np.isfinite(v)]) for c, (t, v) in signals.items()}
    mapped = _mapped(signals, info, options, source, report)
    _terminal_clock(table, report)
    report["columns"] = {**{c: info["units"][c] for c in signals},
                         "x": "PTN north/east (1e-7 deg) -> east of the run's first fix (pymap3d)",
                         "y": "PTN north/east (1e-7 deg) -> north of the run's first fix (pymap3d)",
                         "t": "TIM start, s from the run's start"}
    report["fixed"] = info["fixed"]
    report["columns"].update({c: how for c, (_, _, how) in mapped.items()})
    signals.update({c: (t, v) for c, (t, v, _) in mapped.items()})
    held = set(signals) - {c for c in mapped if c != "delta_cmd"}
    return Streams(gnss, signals, report, held, {}, breaks, groups={c: "gnss" for c in signals})


def _mapped(signals: dict, info: dict, options, source: Path, report: dict) -> dict:
    """{column: (t, values, how)} of the ``--signal`` expressions over the time log's columns
    (named as listed, or DDInnn), and the machine's measured speed as ``v`` when not mapped."""
    series = {c: Series(t, v, info["si"].get(c), c) for c, (t, v) in signals.items()}
    for c, ddi in info["ddi"].items():
        if c in series:
            series.setdefault(f"DDI{ddi}", series[c])
    specs = list(options.signals)
    speed = next((c for c, d in info["ddi"].items() if d == SPEED_DDI and c in series), None)
    if speed and "v" not in {s.column for s in specs}:
        specs.append(SignalSpec("v", ((speed, 1.0),), 0.0, None, f"v={speed}"))
    out = {}
    for spec in specs:
        for name in spec.names:
            if name not in series:
                raise unknown_name(str(source), spec, name, sorted(series), "column")
        t, values, how = evaluate(spec, {n: series[n] for n in spec.names}, str(source), options.wheelbase or 1.4,
                                  report.setdefault("sums", {}))
        ok = np.isfinite(values)
        out[spec.column] = (t[ok], values[ok], how + ("; the machine's measured speed (DDI 397)"
                                                      if spec.text == f"v={speed}" else ""))
    return out


def _terminal_clock(table: pd.DataFrame, report: dict) -> None:
    """The terminal's clock (TIM) against the GNSS time the same records carry (PTN H, I)."""
    if "gps_time_ms" not in table or "gps_date" not in table:
        return
    gps = EPOCH_1980 + table["gps_date"].to_numpy(float) * 86400.0 + table["gps_time_ms"].to_numpy(float)   # s (PTN H read x 1e-3)
    ok = np.isfinite(gps) & (table["gps_date"].to_numpy(float) > 0)
    if ok.sum() < 2:
        return
    d = table["utc"].to_numpy(float)[ok] - gps[ok]
    offset = float(np.median(d))
    report["terminal_clock"] = {"offset_s": offset, "range_s": [float(d.min()), float(d.max())],
                                "terminal_start": iso(float(table["utc"].iloc[0])), "gnss_start": iso(float(gps[ok][0]))}
    report.setdefault("notes", []).append(
        f"the terminal's clock (TIM, labelled UTC) is {offset:+.3f} s from the GNSS time in the same records "
        f"(PTN H/I; {iso(float(table['utc'].iloc[0]))} vs {iso(float(gps[ok][0]))}); the log keeps the terminal's clock")


def _task_notes(paths: list[Path], heads: list[Path]) -> list[str]:
    """What the TaskData beside the time logs says of itself: a TASKDATA.XML that is not an ISO
    11783-10 document is named (the time logs are read without it: each header says its layout)."""
    tasks = {p for p in paths if p.name.upper() == "TASKDATA.XML"}
    tasks |= {p for h in heads for p in h.parent.iterdir() if p.name.upper() == "TASKDATA.XML"}
    notes = []
    for task in sorted(tasks):
        try:
            root = ET.parse(regular_file(task, LogError)).getroot()
            if not root.tag.endswith("ISO11783_TaskData"):
                notes.append(f"{task.name}: root element <{root.tag[:40]}>, not ISO11783_TaskData: not a TaskData "
                             f"(the time logs are read without it)")
        except (ET.ParseError, LookupError, ValueError) as exc:
            notes.append(f"{task.name}: not readable XML ({exc}): the TaskData is damaged; the time logs are read "
                         f"without it (each TLG header gives its own layout)")
    return notes


def _repeated_logs(tables: list) -> list[str]:
    """Time logs that repeat another one record for record (a TaskData copied twice into one folder)."""
    seen: dict = {}
    notes = []
    for head, table, _ in tables:
        key = (len(table), float(table["utc"].iloc[0]), float(table["utc"].iloc[-1]),
               float(np.nansum(table.select_dtypes("number").to_numpy(float))))
        if key in seen:
            notes.append(f"{head.stem} repeats {seen[key]} record for record ({len(table)} records, "
                         f"{iso(key[1])} to {iso(key[2])}): a duplicated TaskData; read once")
        else:
            seen[key] = head.stem
    return notes


def list_timelogs(paths: list[Path], source: Path) -> list[str]:
    """``--list``: each time log, its records and span, and its columns (DDIs) with their ranges."""
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


class TimeLogReader(Reader):
    """ISO 11783-10 TaskData: TASKDATA.XML and its time logs (TLGnnnnn.xml headers, .bin records)."""

    kind, name, listed = "isoxml", "ISO 11783-10 TaskData", "time logs with their DDIs"
    files = "ISOXML: TASKDATA.XML with TLGnnnnn.xml/.bin"
    suffixes = (".xml", ".bin")

    def claims(self, path: Path) -> bool:
        name = path.name.upper()
        return super().claims(path) and (name == "TASKDATA.XML" or name.startswith("TLG"))

    def streams(self, files: dict[str, list[Path]], options, source: Path) -> Streams:
        return timelog_streams(files[self.kind], options, source)

    def listing(self, paths: list[Path], options, source: Path) -> list[str]:
        return list_timelogs(paths, source)


READER = TimeLogReader()
