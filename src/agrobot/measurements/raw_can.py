"""A recorded CAN log decoded with a DBC, and the map from its signals to the log's columns.

Any format python-can reads (candump ``.log``, Vector ``.asc``, ``.blf``, ``.trc``) goes through
``can.LogReader``; the DBC is loaded by measurements.dbc (cantools, repaired where a maker's file
needs it) and frames are decoded by cantools to raw values, scaled here (value = raw x scale +
offset). Multiplexed messages give, per frame, the signals of the multiplexer value sent. A
29-bit frame that matches no identifier exactly is matched by its J1939 parameter group number
(priority and source address free, and the destination of a PDU1 group), so one DBC decodes any
sender; in 29-bit messages a byte-aligned unsigned field above J1939's valid range (0xFA.. for
8 bits, 0xFAFF for 16 ...: 'error' and 'not available') is NaN, counted. A DBC's declared
[min|max] is a plausibility note (values outside are counted and named, kept), except a sentinel:
a value exactly on a declared bound that is also the field's raw extreme (raw 0 or all ones) and
beyond what a ground vehicle can measure (SENTINEL_LIMITS: an acceleration of -64 m/s^2 from raw
0) is a sender's "no value", NaN, counted and named.

Frames carry their bus (candump's ``can0``, a Vector channel ``1``): ``--bus`` chooses; a log of
several buses without it is refused with the buses named. Columns come from ``--signal``
expressions (measurements.signal_expressions), else from SOURCES (the project's messages, then ISO 11783-7
guidance), else from a signal matched by name and unit (GUESSES). ISO 11783-7 curvature is
positive to the driver's right, the log's angles to the left: those sources carry the sign -1.

Imported where used: can (python-can, the hardware extra).
"""
from __future__ import annotations

import math
import re
from array import array
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from agrobot.components.hardware.can_frames import DEFAULT_DBC, load_dbc as project_dbc
from agrobot.orchestrator.units import base_unit

from .dbc import load_dbc_file
from .log import LogError
from .quirks import ordered_in_time
from .signal_expressions import SignalSpec
from .streams import Series

CAN_SUFFIXES = (".log", ".asc", ".blf", ".trc")


def _spec(column: str, message: str, signal: str, sign: float = 1.0) -> SignalSpec:
    return SignalSpec(column, ((f"{message}.{signal}", sign),), 0.0, None,
                      f"{column}={'-' if sign < 0 else ''}{message}.{signal}")


# per column, the first source whose message the DBC holds is used
SOURCES: dict[str, tuple[SignalSpec, ...]] = {
    "delta_cmd": (_spec("delta_cmd", "GuidanceCommand", "SteerAngleCmd"),
                  _spec("delta_cmd", "GuidanceSystemCommand", "CurvatureCommand", -1.0)),
    "delta": (_spec("delta", "TractorFeedback", "SteerAngle"),
              _spec("delta", "GuidanceMachineInfo", "EstimatedCurvature", -1.0)),
    "v": (_spec("v", "TractorFeedback", "Speed"),
          _spec("v", "WheelBasedSpeedAndDistance", "WheelBasedMachineSpeed")),
    "yaw_rate": (_spec("yaw_rate", "TractorFeedback", "YawRate"),
                 _spec("yaw_rate", "AgrobotYawRate", "YawRate")),
}
CAN_COLUMNS = tuple(SOURCES)

# |value| in SI that no ground vehicle's sensor measures: a declared bound beyond it is a sentinel
# (an angular rate only in deg or rad units: an engine's rpm shares its dimension)
SENTINEL_LIMITS = (("m/s^2", 50.0, ""), ("m/s", 100.0, ""), ("rad/s", 10.0, "deg|rad"))


def _key(frame_id: int, extended: bool) -> tuple:
    """The J1939 parameter group of a 29-bit identifier: data page and PDU format, and the PDU
    specific byte when it is a group extension (PDU2, PF >= 240) rather than a destination."""
    pf = (frame_id >> 16) & 0xFF
    return ("pgn", (frame_id >> 8) & (0x3FF00 if pf < 240 else 0x3FFFF)) if extended else ("std", frame_id)


@dataclass
class CANRecording:
    """Decoded frames per DBC message (a table with ``t``, ``source_address`` and the signals
    scaled), and what the reader counted: frames, unknown identifiers, buses, values outside the
    DBC's declared ranges, J1939 'not available' values."""

    path: Path
    messages: dict[str, pd.DataFrame]
    counts: Counter = field(default_factory=Counter)
    unknown_ids: Counter = field(default_factory=Counter)
    buses: Counter = field(default_factory=Counter)
    outside_range: dict = field(default_factory=dict)
    not_available: dict = field(default_factory=dict)
    sentinels: dict = field(default_factory=dict)         # Message.Signal -> {values, count, of}: a declared bound as "no value"
    bad_lines: list = field(default_factory=list)        # (line number, text) of the first lines that are not frames
    notes: list = field(default_factory=list)
    breaks: list = field(default_factory=list)           # on the logger's clock (measurements.quirks.ordered_in_time)

    @property
    def span(self) -> tuple[float, float]:
        t = [m["t"].to_numpy() for m in self.messages.values() if len(m)]
        return (min(float(x[0]) for x in t), max(float(x[-1]) for x in t)) if t else (math.nan, math.nan)


def load_dbc(path: str | Path | None):
    """(database, DBCReport or None): the DBC (None: the project's own agrobot_tractor.dbc); a
    LogError names the file when nothing in it can be read."""
    if path is None:
        try:
            return project_dbc(None), None
        except Exception as exc:             # noqa: BLE001 - cantools raises many kinds
            raise LogError(f"{DEFAULT_DBC}: cannot read as a DBC: {exc}") from None
    if not Path(path).is_file():
        raise LogError(f"--dbc {path}: no such file")
    return load_dbc_file(path)


def _bus_name(channel) -> str:
    if channel is None or channel == "":
        return "-"
    return str(channel)


def _bus_matches(channel: str, wanted: str) -> bool:
    wanted = wanted.strip()
    return channel == wanted or channel == wanted.removeprefix("can") or f"can{channel}" == wanted


# candump -L: '(1436509052.249713) can0 18FEF100#00FA0000000000FF', CAN FD '##<flags><data>', remote 'R[dlc]'
CANDUMP_LINE = re.compile(r"^\(\d+(?:\.\d*)?\)\s+\S+\s+[0-9A-Fa-f]{1,8}#(?:#[0-9A-Fa-f])?"
                          r"(?:(?:[0-9A-Fa-f]{2})*|[Rr]\d*)(?:\s+[RrTt])?$")
CANDUMP_FORMAT = "'(SECONDS) BUS ID#HEXDATA' (candump -L, e.g. '(1436509052.249713) can0 18FEF100#00FA0000000000FF')"


class _CheckedLines:
    """A candump log's lines for python-can's reader, each checked against CANDUMP_LINE first: a
    line that is not a frame is skipped, counted and its number kept (python-can would stop the
    whole log at it)."""

    def __init__(self, path: Path) -> None:
        self.path, self.bad, self.good, self.examples = path, 0, 0, []

    def __iter__(self):
        with open(self.path, "rb") as f:
            for number, raw in enumerate(f, 1):
                line = raw.strip()
                if not line or line.startswith(b"#"):
                    continue
                text = line.decode("ascii", "replace")
                if CANDUMP_LINE.match(text):
                    self.good += 1
                    yield text
                else:
                    self.bad += 1
                    if len(self.examples) < 3:
                        self.examples.append((number, text[:60]))
                    if self.bad > 1000 and self.bad > 10 * self.good:
                        return          # not a candump log: the error below names the first lines

    def close(self) -> None:
        pass


class _Columns:
    """One message's decoded frames, column by column in compact arrays (8 bytes a value)."""

    def __init__(self, msg) -> None:
        self.names = [s.name for s in msg.signals]
        self.t, self.source, self.values = array("d"), array("d"), {n: array("d") for n in self.names}

    def add(self, t: float, source: int, values: dict) -> None:
        self.t.append(t)
        self.source.append(source)
        for n in self.names:
            v = values.get(n, math.nan)
            self.values[n].append(float(v) if isinstance(v, (int, float)) else math.nan)

    def table(self) -> pd.DataFrame:
        return pd.DataFrame({"t": np.frombuffer(self.t, float), "source_address": np.frombuffer(self.source, float),
                             **{n: np.frombuffer(v, float) for n, v in self.values.items()}})


def read_can_file(path: str | Path, db, bus: str | None = None, wanted: set[str] | None = None) -> CANRecording:
    """Every frame of a CAN log that a message of ``db`` describes, decoded (on ``bus`` only,
    when given; of the ``wanted`` messages only, when given: the others are counted), read a
    frame at a time into compact columns. A candump line that is not a frame is skipped and
    counted with its line number; a log with no frame is refused naming its first lines."""
    import can

    path = Path(path)
    exact = {(m.is_extended_frame, m.frame_id): m for m in db.messages}
    by_group = {_key(m.frame_id, True): m for m in db.messages if m.is_extended_frame}
    columns: dict[str, _Columns] = {}
    counts: Counter = Counter()
    unknown: Counter = Counter()
    buses: Counter = Counter()
    lines = _CheckedLines(path) if path.suffix.lower() == ".log" else None
    try:
        # Vector ASC: absolute times from the file's trigger-block date (python-can's default is from 0)
        reader = can.ASCReader(str(path), relative_timestamp=False) if path.suffix.lower() == ".asc" \
            else can.CanutilsLogReader(lines) if lines is not None else can.LogReader(str(path))
        for frame in reader:
            counts["frames"] += 1
            channel = _bus_name(frame.channel)
            buses[channel] += 1
            if bus is not None and not _bus_matches(channel, bus):
                counts["frames on other buses"] += 1
                continue
            if frame.is_error_frame or frame.is_remote_frame:
                counts["error or remote frames"] += 1
                continue
            msg = exact.get((frame.is_extended_id, frame.arbitration_id))
            if msg is None and frame.is_extended_id:
                msg = by_group.get(_key(frame.arbitration_id, True))
            if msg is None:
                unknown[f"0x{frame.arbitration_id:X}"] += 1
                continue
            if wanted is not None and msg.name not in wanted:
                counts["frames of messages not used"] += 1
                continue
            try:
                values = msg.decode(bytes(frame.data), decode_choices=False, scaling=False, allow_truncated=True)
            except Exception:            # noqa: BLE001 - a frame that does not decode is counted
                counts["frames that do not decode"] += 1
                continue
            if msg.name not in columns:
                columns[msg.name] = _Columns(msg)
            columns[msg.name].add(float(frame.timestamp), frame.arbitration_id & 0xFF if frame.is_extended_id else -1,
                                  values)
            counts["decoded"] += 1
    except LogError:
        raise
    except Exception as exc:              # noqa: BLE001 - a reader choking on a foreign format or damaged bytes
        where = f"frame {counts['frames'] + 1} (after {counts['frames']} read)" if counts["frames"] else "its first frame"
        named = str(exc) if isinstance(exc, (OSError, ValueError, EOFError, can.CanError)) and str(exc) \
            else f"{type(exc).__name__}: {exc}"
        raise LogError(f"{path}: cannot read as a CAN log ({path.suffix}) at {where}: {named}") from None
    bad = [] if lines is None else lines.examples
    if lines is not None and lines.bad:
        counts["lines that are not frames"] = lines.bad
    if counts["frames"] == 0 or (lines is not None and lines.bad > lines.good):
        raise LogError((f"{path}: no CAN frame in it" if counts["frames"] == 0 else
                        f"{path}: {lines.bad} of {lines.bad + lines.good} lines are not CAN frames")
                       + ("; " + "; ".join(f"line {n}: {t!r}" for n, t in bad) + f"; expected {CANDUMP_FORMAT}" if bad
                          else " (python-can reads .log candump, .asc, .blf, .trc)"))
    if bus is not None and counts["frames on other buses"] == counts["frames"]:
        raise LogError(f"{path}: --bus {bus}: no frame on that bus; buses in the log: "
                       + ", ".join(f"{b} ({n} frames)" for b, n in buses.most_common()))
    if bus is None and len(buses) > 1:
        raise LogError(f"{path}: frames from {len(buses)} buses ("
                       + ", ".join(f"{b}: {n} frames" for b, n in buses.most_common())
                       + "); choose one with --bus NAME")
    rec = CANRecording(path, {}, counts, unknown, buses)
    rec.bad_lines = bad
    by_name = {m.name: m for m in db.messages}
    for name, c in columns.items():
        table = c.table().rename(columns={"t": "utc"})          # in file order: damaged or backward stamps named
        table, breaks = ordered_in_time(table, f"{path.name} {name}", rec.notes, tuple(c.names), stream=f"CAN {name}",
                                        what="frame")
        rec.breaks += breaks
        rec.messages[name] = _scaled(by_name[name], table.rename(columns={"utc": "t"}), rec)
    return rec


def _scaled(msg, raw: pd.DataFrame, rec: CANRecording) -> pd.DataFrame:
    """The message's raw values scaled; J1939 'error'/'not available' fields NaN, and the fields of
    a frame whose own validity flag is 0; values outside the DBC's declared range counted (kept)."""
    table = raw.sort_values("t", kind="stable").reset_index(drop=True)
    for sig in msg.signals:
        if sig.name not in table:
            continue
        x = pd.to_numeric(table[sig.name], errors="coerce").to_numpy(float)
        if msg.is_extended_frame and not sig.is_signed and not sig.is_float and sig.length in (8, 16, 24, 32):
            limit = (0xFB << (sig.length - 8))          # J1939-71: above 0xFA.. is error / not available
            na = np.isfinite(x) & (x >= limit)
            if na.any():
                rec.not_available[f"{msg.name}.{sig.name}"] = int(na.sum())
                x = np.where(na, np.nan, x)
        conv = getattr(sig, "conversion", None)
        scale = float(getattr(conv, "scale", getattr(sig, "scale", 1.0)) or 1.0)
        offset = float(getattr(conv, "offset", getattr(sig, "offset", 0.0)) or 0.0)
        x = x * scale + offset
        lo, hi = sig.minimum, sig.maximum
        bounds = sentinel_bounds(sig, scale, offset)
        hit = np.isfinite(x) & np.isin(x, bounds)
        if hit.any():
            rec.sentinels[f"{msg.name}.{sig.name}"] = {"values": [float(b) for b in bounds], "count": int(hit.sum()),
                                                       "of": int(np.isfinite(x).sum())}
            x = np.where(hit, np.nan, x)
        if lo is not None and hi is not None and not (lo == 0 and hi == 0) and hi > lo:
            out = np.isfinite(x) & ((x < lo - 1e-9 * max(1.0, abs(lo))) | (x > hi + 1e-9 * max(1.0, abs(hi))))
            if out.any():
                rec.outside_range[f"{msg.name}.{sig.name}"] = {
                    "outside": int(out.sum()), "of": int(np.isfinite(x).sum()), "declared": [lo, hi],
                    "seen": [float(np.nanmin(x)), float(np.nanmax(x))]}
        table[sig.name] = x
    return _flagged_invalid(msg, table, rec)


def sentinel_bounds(sig, scale: float, offset: float) -> list[float]:
    """The declared bounds of ``sig`` that are sentinels (module docstring): on the raw field's
    extreme and beyond SENTINEL_LIMITS for the signal's unit."""
    unit = (sig.unit or "").strip()
    own = base_unit(unit) if unit else None
    if own is None or sig.is_float or not scale:
        return []
    limit = next((lim for u, lim, words in SENTINEL_LIMITS if base_unit(u).exponents == own.exponents
                  and (not words or re.search(words, unit, re.I))), None)
    if limit is None:
        return []
    n = sig.length
    extremes = (-(2 ** (n - 1)), 2 ** (n - 1) - 1) if sig.is_signed else (0, 2 ** n - 1)
    decoded = [r * scale + offset for r in extremes]
    return [b for b in (sig.minimum, sig.maximum) if b is not None and abs(b * own.factor) > limit
            and any(math.isclose(b, d, rel_tol=1e-9, abs_tol=1e-9) for d in decoded)]


VALID_FLAG = re.compile(r"(?<!in)(?<!not)(?<!not_)valid$", re.I)
INVALID_FLAG = re.compile(r"(in|not_?)valid$", re.I)


def _flagged_invalid(msg, table: pd.DataFrame, rec: CANRecording) -> pd.DataFrame:
    """A message that carries its own validity (one one-bit signal named ...Valid, as a GNSS/IMU
    module's PositionValid, or ...Invalid / ...NotValid with the opposite sense): its other signals
    NaN in the frames the flag marks invalid (the sender says they are not measurements), named in a
    note. Several flags in one message are named and none applied (which signals each covers is not
    declared)."""
    bits = [s.name for s in msg.signals if s.length == 1 and s.name in table]
    flags = [(n, 0.0) for n in bits if VALID_FLAG.search(n)] + [(n, 1.0) for n in bits if INVALID_FLAG.search(n)]
    if len(flags) > 1:
        rec.notes.append(f"{msg.name}: {len(flags)} validity flags ({', '.join(n for n, _ in flags)}): none applied, "
                         f"the DBC does not say which signals each covers; every frame is kept")
    if len(flags) != 1:
        return table
    (flag, invalid_when), = flags
    bad = table[flag].to_numpy(float) == invalid_when
    others = [s.name for s in msg.signals if s.name in table and s.name != flag]
    if bad.any() and others:
        table.loc[bad, others] = np.nan
        span = table["t"].to_numpy(float)[bad]
        rec.notes.append(f"{msg.name}: {int(bad.sum())} of {len(bad)} frames say {flag} = {invalid_when:g} "
                         f"(from {span[0] - table['t'].iloc[0]:.1f} to {span[-1] - table['t'].iloc[0]:.1f} s of the "
                         f"message): their {', '.join(others)} are left out, not measurements")
    return table


def merge(cans: list[CANRecording]) -> dict[str, pd.DataFrame]:
    """Each message's frames from every log, in time order."""
    frames: dict[str, list] = {}
    for c in cans:
        for name, table in c.messages.items():
            frames.setdefault(name, []).append(table)
    return {k: pd.concat(v).sort_values("t", kind="stable").drop_duplicates("t").reset_index(drop=True)
            for k, v in frames.items()}


def messages_of(db, specs) -> set[str]:
    """The DBC messages that the expressions ``specs`` read (the longest message name that
    prefixes each ``Message.Signal``)."""
    names = {m.name for m in db.messages}
    out = set()
    for spec in specs:
        for name in spec.names:
            cuts = [i for i, ch in enumerate(name) if ch == "."][::-1]
            out.update(next(([name[:k]] for k in cuts if name[:k] in names), []))
    return out


def signal_names(db) -> list[str]:
    return [f"{m.name}.{s.name}" for m in db.messages for s in m.signals]


def series(db, frames: dict[str, pd.DataFrame], name: str) -> Series | None:
    """The named ``Message.Signal`` as recorded (None: the DBC has no such signal). A message
    name may hold dots: the longest message name that prefixes ``name`` is taken."""
    messages = {m.name: m for m in db.messages}
    for k in [i for i, ch in enumerate(name) if ch == "."][::-1]:
        message, signal = name[:k], name[k + 1:]
        if message in messages and signal in [s.name for s in messages[message].signals]:
            sig = messages[message].get_signal_by_name(signal)
            table = frames.get(message)
            if table is None or signal not in table:
                return Series(np.array([]), np.array([]), (sig.unit or "").strip() or None, name)
            ok = table[signal].notna().to_numpy()
            return Series(table["t"].to_numpy(float)[ok], table[signal].to_numpy(float)[ok],
                          (sig.unit or "").strip() or None, f"{name} (CAN {messages[message].frame_id:#x})",
                          _width(sig))
    return None


def _width(sig) -> float | None:
    """The modulus a DBC integer signal rolls over at, in its physical unit: 2^length x scale (a
    counter's rate() is unwrapped by it: signal_expressions.counter_rate); None for a float signal."""
    return None if sig.is_float else float(2 ** sig.length) * abs(float(sig.scale))


# a maker's DBC names its signals its own way: by name and unit (pint), the first match in
# message order is used and the report says so (--signal chooses another)
GUESSES = {
    "yaw_rate": (re.compile(r"yaw.?rate", re.I), "rad/s"),
    "v": (re.compile(r"(veh(icle)?|ground|wheel.?based|machine|xmission|transmission|wheel|road).?speed|^speed$|"
                     r"speed.?(kph|mps|veh)|^v(eh)?_?speed", re.I), "m/s"),
    "delta": (re.compile(r"(steer(ing)?|road.?wheel|wheel).?(wheel.?)?angle(?!.*(cmd|command|req|target|set))", re.I), "rad"),
    "delta_cmd": (re.compile(r"steer.*(cmd|command|req(uest)?|target|set.?point|desired)", re.I), "rad"),
}


def _guess(db, column: str, taken: set) -> SignalSpec | None:
    pattern, unit = GUESSES[column]
    want = base_unit(unit).exponents
    for m in db.messages:
        for sig in m.signals:
            name = f"{m.name}.{sig.name}"
            if name in taken or not (pattern.search(sig.name) or pattern.search(name.replace(".", "_"))):
                continue
            try:
                have = base_unit(sig.unit.strip()) if (sig.unit or "").strip() else None
            except Exception:                    # noqa: BLE001 - a unit pint does not know: not a match
                have = None
            if have is not None and have.exponents == want:
                return _spec(column, m.name, sig.name)
    return None


def choose_sources(db, dbc_name: str, given: list[SignalSpec] = ()) -> tuple[dict[str, SignalSpec], dict[str, str], set]:
    """(column -> expression, column -> why it has none, columns matched by name): the user's,
    else the first of SOURCES the DBC holds, else a signal matched by name and unit (GUESSES)."""
    names = {m.name for m in db.messages}
    chosen = {s.column: s for s in given}
    how: set = set()
    for column, candidates in SOURCES.items():
        if column not in chosen:
            found = [s for s in candidates if s.names[0].split(".")[0] in names]
            if found:
                chosen[column] = found[0]
    taken = {n for s in chosen.values() for n in s.names}
    for column in CAN_COLUMNS:
        if column not in chosen:
            guess = _guess(db, column, taken)
            if guess is not None:
                chosen[column] = guess
                taken.update(guess.names)
                how.add(column)
    unmapped = {c: (f"no signal for it in {dbc_name} (messages: {', '.join(sorted(names)[:12])}"
                    f"{' ...' if len(names) > 12 else ''}); map one with --signal {c}=Message.Signal")
                for c in CAN_COLUMNS if c not in chosen}
    return chosen, unmapped, how


def list_can(paths: list[Path], options) -> list[str]:
    """``--list``: the DBC's load report, then each CAN log's buses, messages and signals (units,
    declared ranges, the values seen, rates); a log of several buses without --bus, bus by bus."""
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
