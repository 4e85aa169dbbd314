"""A recorded CAN log decoded with a DBC, and the map from its signals to the log's columns.

Any format python-can reads (candump ``.log``, Vector ``.asc``, ``.blf``, ``.trc``, ``.csv``)
goes through ``can.LogReader``; frames are decoded by cantools. A 29-bit frame that matches no
identifier exactly is matched by its J1939 parameter group number (priority and source address
free, and the destination of a PDU1 group), so one DBC decodes any sender. A decoded value outside
the DBC's range (J1939's 'not available' patterns) is NaN.

Columns come from signals (``SOURCES``: the project's messages, then ISO 11783-7 guidance), or
from ``COLUMN=[-]Message.Signal`` given by the user. Units are converted from the DBC's unit
(pint: deg, km/h, deg/s ...); a curvature feeds a wheel angle through the wheelbase,
delta = atan(L kappa) (kinematic bicycle). ISO 11783-7 curvature is positive to the driver's
right, the log's angles to the left: those sources carry the sign -1.
"""
from __future__ import annotations

import math
import re
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .log import COLUMNS, LogError

CAN_SUFFIXES = (".log", ".asc", ".blf", ".trc")


@dataclass(frozen=True)
class SignalSource:
    column: str
    message: str
    signal: str
    sign: float = 1.0

    def __str__(self) -> str:
        return f"{self.column}={'-' if self.sign < 0 else ''}{self.message}.{self.signal}"


# per column, the first source whose message the DBC holds is used
SOURCES: dict[str, tuple[SignalSource, ...]] = {
    "delta_cmd": (SignalSource("delta_cmd", "GuidanceCommand", "SteerAngleCmd"),
                  SignalSource("delta_cmd", "GuidanceSystemCommand", "CurvatureCommand", -1.0)),
    "delta": (SignalSource("delta", "TractorFeedback", "SteerAngle"),
              SignalSource("delta", "GuidanceMachineInfo", "EstimatedCurvature", -1.0)),
    "v": (SignalSource("v", "TractorFeedback", "Speed"),
          SignalSource("v", "WheelBasedSpeedAndDistance", "WheelBasedMachineSpeed")),
    "yaw_rate": (SignalSource("yaw_rate", "TractorFeedback", "YawRate"),
                 SignalSource("yaw_rate", "AgrobotYawRate", "YawRate")),
}
CAN_COLUMNS = tuple(SOURCES)


_COLUMN_NAME = re.compile(r"^[a-z_][a-z0-9_]*$")


def parse_source(text: str) -> SignalSource:
    """``COLUMN=[-]Message.Signal`` (the ``--signal`` option for CAN). COLUMN is a log column
    (delta_cmd, delta, v, yaw_rate) or any other lower-case name, kept as an extra column."""
    column, eq, rest = text.partition("=")
    sign = -1.0 if rest.strip().startswith("-") else 1.0
    message, dot, signal = rest.strip().lstrip("-").partition(".")
    if not eq or not dot or not message or not signal or not _COLUMN_NAME.match(column.strip()) \
            or column.strip() in ("t", "x", "y"):
        raise LogError(f"--signal {text!r}: expected COLUMN=[-]Message.Signal with COLUMN one of "
                       f"{', '.join(CAN_COLUMNS)} or another lower-case name for an extra column (a leading '-' "
                       f"flips the sign); a ROS topic is COLUMN=/topic.field")
    return SignalSource(column.strip(), message.strip(), signal.strip(), sign)


def _key(frame_id: int, extended: bool) -> tuple:
    """The J1939 parameter group of a 29-bit identifier: data page and PDU format, and the PDU
    specific byte when it is a group extension (PDU2, PF >= 240) rather than a destination."""
    pf = (frame_id >> 16) & 0xFF
    return ("pgn", (frame_id >> 8) & (0x3FF00 if pf < 240 else 0x3FFFF)) if extended else ("std", frame_id)


@dataclass
class CANRecording:
    """Decoded frames per DBC message (a table with ``t``, ``source_address`` and the signals)."""

    path: Path
    messages: dict[str, pd.DataFrame]
    counts: Counter = field(default_factory=Counter)
    unknown_ids: Counter = field(default_factory=Counter)

    @property
    def span(self) -> tuple[float, float]:
        t = [m["t"].to_numpy() for m in self.messages.values() if len(m)]
        return (min(float(x[0]) for x in t), max(float(x[-1]) for x in t)) if t else (math.nan, math.nan)


def load_dbc(path: str | Path | None):
    """A DBC (None: the project's own); a LogError names the file when it cannot be read."""
    from components.hardware.can_frames import DEFAULT_DBC, load_dbc as load

    try:
        return load(path)
    except Exception as exc:             # noqa: BLE001 - cantools raises many kinds
        raise LogError(f"{path or DEFAULT_DBC}: cannot read as a DBC: {exc}") from None


def read_can_file(path: str | Path, db) -> CANRecording:
    """Every frame of a CAN log that a message of ``db`` describes, decoded."""
    import can

    path = Path(path)
    exact = {(m.is_extended_frame, m.frame_id): m for m in db.messages}
    by_group = {_key(m.frame_id, True): m for m in db.messages if m.is_extended_frame}
    rows: dict[str, list] = {m.name: [] for m in db.messages}
    ranges = {m.name: {s.name: (s.minimum, s.maximum) for s in m.signals} for m in db.messages}
    counts: Counter = Counter()
    unknown: Counter = Counter()
    try:
        # Vector ASC: absolute times from the file's trigger-block date (python-can's default is from 0)
        reader = can.ASCReader(str(path), relative_timestamp=False) if path.suffix.lower() == ".asc" \
            else can.LogReader(str(path))
        for frame in reader:
            counts["frames"] += 1
            if frame.is_error_frame or frame.is_remote_frame:
                counts["error or remote frames"] += 1
                continue
            msg = exact.get((frame.is_extended_id, frame.arbitration_id))
            if msg is None and frame.is_extended_id:
                msg = by_group.get(_key(frame.arbitration_id, True))
            if msg is None:
                unknown[f"0x{frame.arbitration_id:X}"] += 1
                continue
            try:
                values = msg.decode(bytes(frame.data), decode_choices=False)
            except Exception:            # noqa: BLE001 - a frame that does not decode is counted
                counts["frames that do not decode"] += 1
                continue
            for name, (lo, hi) in ranges[msg.name].items():
                v = values.get(name)
                if v is not None and ((lo is not None and v < lo - 1e-9) or (hi is not None and v > hi + 1e-9)):
                    values[name] = math.nan              # a J1939 'not available' / 'error' pattern
            rows[msg.name].append({"t": float(frame.timestamp),
                                   "source_address": frame.arbitration_id & 0xFF if frame.is_extended_id else -1,
                                   **{k: float(v) for k, v in values.items()}})
            counts["decoded"] += 1
    except (OSError, ValueError, EOFError, can.CanError) as exc:
        raise LogError(f"{path}: cannot read as a CAN log ({path.suffix}): {exc}") from None
    except Exception as exc:              # noqa: BLE001 - a reader choking on a foreign format
        raise LogError(f"{path}: cannot read as a CAN log ({path.suffix}): {type(exc).__name__}: {exc}") from None
    if counts["frames"] == 0:
        raise LogError(f"{path}: no CAN frame in it (python-can reads .log candump, .asc, .blf, .trc, .csv)")
    messages = {k: pd.DataFrame(v).sort_values("t", kind="stable").reset_index(drop=True) for k, v in rows.items() if v}
    return CANRecording(path, messages, counts, unknown)


# a maker's DBC names its signals its own way: by name and unit (pint), the first match in
# message order is used and the report says so (--signal chooses another)
GUESSES = {
    "yaw_rate": (re.compile(r"yaw.?rate", re.I), "rad/s"),
    "v": (re.compile(r"(veh(icle)?|ground|wheel.?based|machine|xmission|transmission|wheel|road).?speed|^speed$|"
                     r"speed.?(kph|mps|veh)|^v(eh)?_?speed", re.I), "m/s"),
    "delta": (re.compile(r"(steer(ing)?|road.?wheel|wheel).?(wheel.?)?angle(?!.*(cmd|command|req|target|set))", re.I), "rad"),
    "delta_cmd": (re.compile(r"steer.*(cmd|command|req(uest)?|target|set.?point|desired)", re.I), "rad"),
}


def _guess(db, column: str, taken: set) -> SignalSource | None:
    from orchestrator.units import base_unit

    pattern, unit = GUESSES[column]
    want = base_unit(unit).exponents
    for m in db.messages:
        for sig in m.signals:
            name = f"{m.name}.{sig.name}"
            if name in taken or not (pattern.search(sig.name) or pattern.search(name.replace(".", "_"))):
                continue
            have = base_unit(sig.unit.strip()) if (sig.unit or "").strip() else None
            if have is not None and have.exponents == want:
                return SignalSource(column, m.name, sig.name)
    return None


def choose_sources(db, dbc_name: str, given: list[SignalSource] = ()) -> tuple[dict[str, SignalSource], dict[str, str], set]:
    """(column -> source, column -> why it has none, columns matched by name): the user's, else
    the first of SOURCES the DBC holds, else a signal matched by name and unit (GUESSES); a
    LogError names the DBC and what it holds when a given source does not exist."""
    names = {m.name: m for m in db.messages}
    chosen = {s.column: s for s in given}
    how: dict[str, str] = {}
    for column, candidates in SOURCES.items():
        if column not in chosen:
            found = [s for s in candidates if s.message in names]
            if found:
                chosen[column] = found[0]
    taken = {f"{s.message}.{s.signal}" for s in chosen.values()}
    for column in CAN_COLUMNS:
        if column not in chosen:
            guess = _guess(db, column, taken)
            if guess is not None:
                chosen[column] = guess
                taken.add(f"{guess.message}.{guess.signal}")
                how[column] = "matched by name and unit"
    for s in chosen.values():
        if s.message not in names or s.signal not in [x.name for x in names[s.message].signals]:
            have = [x.name for x in names[s.message].signals] if s.message in names else sorted(names)
            raise LogError(f"{dbc_name}: --signal {s}: no such {'signal' if s.message in names else 'message'}; "
                           f"{'signals of ' + s.message if s.message in names else 'messages'}: {', '.join(have)}")
    unmapped = {c: (f"no signal for it in {dbc_name} (messages: {', '.join(sorted(names)[:12])}"
                    f"{' ...' if len(names) > 12 else ''}); map one with --signal {c}=Message.Signal")
                for c in CAN_COLUMNS if c not in chosen}
    return chosen, unmapped, set(how)


def converter(db, dbc_name: str, source: SignalSource, wheelbase: float):
    """(function raw -> column value in SI, description) from the DBC unit of ``source``."""
    from orchestrator.units import base_unit

    sig = db.get_message_by_name(source.message).get_signal_by_name(source.signal)
    unit = (sig.unit or "").strip()
    have = base_unit(unit) if unit else None
    if source.column not in COLUMNS:             # an extra column: SI where the unit says how
        k = source.sign * (have.factor if have is not None else 1.0)
        return (lambda x: k * x), f"{source} [{unit or 'no unit'}] x {k:.6g} -> " + \
            ("SI" if have is not None else "as logged (a unit the units library does not know)")
    target = COLUMNS[source.column][0]
    want = base_unit(target)
    if not unit:
        return (lambda x: source.sign * x), f"{source}: no unit in the DBC, taken as {target}"
    if have is not None and have.exponents == want.exponents:
        k = source.sign * have.factor / want.factor
        return (lambda x: k * x), f"{source} [{unit}] x {k:.6g} -> {target}"
    curvature = have is not None and have.exponents == tuple(-1 if i == 1 else 0 for i in range(len(want.exponents)))
    if curvature and target == "rad":
        k = source.sign * have.factor
        return (lambda x: np.arctan(wheelbase * k * x)), \
            f"{source} [{unit}]: curvature to wheel angle, atan({wheelbase:g} m x {k:.6g} x kappa) -> rad"
    raise LogError(f"{dbc_name}: signal {source.message}.{source.signal} is in {unit!r}; column {source.column!r} "
                   f"needs {target} or a unit convertible to it" + (" (or a curvature, 1/m)" if target == "rad" else ""))
