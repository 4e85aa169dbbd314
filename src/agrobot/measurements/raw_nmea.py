"""A recorded NMEA 0183 file as a table of GNSS epochs .

A line is a sentence (or several glued together, each read with its own checksum), optionally
after a host timestamp (UNIX seconds, ``1777622400.05 $GNGGA,...``, candump style ``(1777622400.050000) $GNGGA,...``, or ISO 8601, ``2026-05-01T08:00:00.05Z $GNGGA,...``;
separated by blanks, a comma or a semicolon); lines starting with ``#`` are comments. Any talker
(GP, GN, GL, GA, GB, BD, IN, ...). GGA opens an epoch (UTC time of day, position at whatever
precision the receiver writes, fix quality kept as its code: 1 GPS, 2 DGPS, 4 RTK fixed, 5 RTK
float ...); RMC and ZDA give the date, RMC and VTG speed and course, HDT or THS a dual antenna's
heading, GST the receiver's position error. The epoch's time is the receiver's UTC; the host
stamp, where the file has one, is kept beside it (the clock alignment uses both). Sentences are
parsed by pynmeagps with their checksums checked; what is not used (GSA, GSV, GLL, TXT, $PUBX,
$PASHR and other proprietary sentences ...) is counted, not parsed.
"""
from __future__ import annotations

import datetime
import math
import re
from array import array
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .log import LogError
from .quirks import ordered_in_time
from .streams import iso
from .time_base import rollover_by_written

NMEA_SUFFIXES = (".nmea", ".gps", ".nma")
NMEA_TEXT_SUFFIXES = (".log", ".txt")      # NMEA when they hold sentences

KNOTS = 1852.0 / 3600.0
USED = ("GGA", "RMC", "VTG", "ZDA", "HDT", "THS", "GST")
_STAMP = re.compile(r"^\s*([^$]*?)[\s,;]*(\$.*)$")
DAY = 86400.0


@dataclass
class NMEARecording:
    """Epochs (``utc`` and ``host`` as POSIX seconds, ``lat``/``lon`` in degrees, ``height`` m,
    ``quality`` GGA code, ``speed`` m/s and ``course`` rad from north where a sentence gave them)
    and what the reader saw."""

    path: Path
    epochs: pd.DataFrame
    counts: Counter = field(default_factory=Counter)
    notes: list[str] = field(default_factory=list)
    breaks: list[dict] = field(default_factory=list)     # where the clock stepped back (measurements.quirks)
    time_base: list[dict] = field(default_factory=list)  # {finding, at}: its dates (measurements.time_base)

    @property
    def has_host_time(self) -> bool:
        return bool(np.isfinite(self.epochs["host"]).any())


def _host_stamp(prefix: str) -> float:
    """UNIX seconds or an ISO 8601 time before the sentence; NaN when there is none."""
    prefix = prefix.strip()
    if prefix.startswith("(") and ")" in prefix:          # candump: (1777622400.050000) [can0 ...]
        prefix = prefix[1:prefix.index(")")]
    if not prefix:
        return math.nan
    try:
        return float(prefix)
    except ValueError:
        pass
    try:
        when = datetime.datetime.fromisoformat(prefix.replace("Z", "+00:00"))
    except ValueError:
        raise ValueError(f"the text before '$' ({prefix[:30]!r}) is neither UNIX seconds nor an ISO 8601 time")
    if when.tzinfo is None:
        when = when.replace(tzinfo=datetime.timezone.utc)
    return when.timestamp()


def _seconds_of_day(t: datetime.time) -> float:
    return t.hour * 3600.0 + t.minute * 60.0 + t.second + t.microsecond * 1e-6


def _date_seconds(d: datetime.date) -> float:
    return datetime.datetime(d.year, d.month, d.day, tzinfo=datetime.timezone.utc).timestamp()


def looks_like_nmea(path: Path) -> bool:
    """True when the first non-empty lines of ``path`` hold NMEA sentences ('$' and a '*')."""
    try:
        with open(path, "rb") as f:
            head = f.read(4096)
    except OSError:
        return False
    lines = [ln for ln in head.split(b"\n") if ln.strip() and not ln.lstrip().startswith(b"#")][:20]
    return bool(lines) and sum(b"$" in ln and b"*" in ln for ln in lines) >= max(1, len(lines) // 2)


def _checksums_ok(bodies: list[bytes], given: list[bytes]) -> np.ndarray:
    """True where the XOR of a sentence's characters between '$' and '*' equals its two hex digits
    (NMEA 0183), for a batch of sentences at once."""
    if not bodies:
        return np.zeros(0, bool)
    lengths = np.fromiter((len(b) for b in bodies), int, len(bodies))
    data = np.frombuffer(b"".join(bodies) + b"\0", np.uint8)
    starts = np.concatenate([[0], np.cumsum(lengths)[:-1]])
    xor = np.bitwise_xor.reduceat(data, starts)
    xor = np.where(lengths > 0, xor, 0)
    want = np.array([int(g, 16) if len(g) == 2 and all(c in b"0123456789abcdefABCDEF" for c in g) else -1
                     for g in given])
    return xor == want


def _hms(text: bytes) -> float:
    """Seconds of the day of 'hhmmss[.ss]'; ValueError otherwise."""
    if len(text) < 6 or not text[:6].isdigit():
        raise ValueError("not hhmmss")
    h, m, sec = int(text[:2]), int(text[2:4]), float(text[4:])
    if h > 23 or m > 59 or not 0 <= sec < 61:
        raise ValueError("not a time of day")
    return h * 3600.0 + m * 60.0 + sec


def _degrees(value: bytes, hemisphere: bytes, width: int) -> float:
    """Decimal degrees of NMEA's (d)ddmm.mmmm and N/S/E/W."""
    deg = int(value[:width]) + float(value[width:]) / 60.0
    if hemisphere in (b"S", b"W"):
        return -deg
    if hemisphere not in (b"N", b"E"):
        raise ValueError("no hemisphere")
    return deg


def _number(text: bytes) -> float:
    return float(text) if text else math.nan


class _Epochs:
    """The epochs read so far, column by column in compact arrays (8 bytes a value), with the
    file line of each; the last few epochs are kept by (day, time of day) so that RMC, VTG, HDT and
    GST find the epoch their GGA opened."""

    COLUMNS = ("tod", "day", "host", "lat", "lon", "height", "quality", "speed", "course", "heading", "position_std")

    def __init__(self) -> None:
        self.columns = {c: array("d") for c in self.COLUMNS}
        self.lines = array("q")
        self.recent: dict[tuple, int] = {}
        self.talkers: dict[int, list] = {}       # epoch -> the talkers whose GGA gave it, the first opened it

    def add(self, key: tuple, line: int, tod: float, day: float, host: float, lat: float = math.nan,
            lon: float = math.nan, height: float = math.nan, quality: float = 0.0) -> int:
        i = len(self.lines)
        c = self.columns
        for name, value in (("tod", tod), ("day", day), ("host", host), ("lat", lat), ("lon", lon), ("height", height),
                            ("quality", quality), ("speed", math.nan), ("course", math.nan), ("heading", math.nan),
                            ("position_std", math.nan)):
            c[name].append(value)
        self.lines.append(line)
        self.recent[key] = i
        if len(self.recent) > 32:
            self.talkers.pop(self.recent.pop(next(iter(self.recent))), None)
        return i

    def set(self, i: int, column: str, value: float) -> None:
        self.columns[column][i] = value

    def get(self, i: int, column: str) -> float:
        return self.columns[column][i]


CHUNK = 1 << 22          # bytes read at a time: the reader's memory does not grow with the file


def _lines(path: Path):
    """(line number, bytes) of the file, a chunk at a time."""
    number = 0
    rest = b""
    with open(path, "rb") as f:
        while True:
            chunk = f.read(CHUNK)
            if not chunk:
                break
            lines = (rest + chunk).split(b"\n")
            rest = lines.pop()
            for line in lines:
                number += 1
                yield number, line
    if rest:
        yield number + 1, rest


def _sentences(text: bytes) -> list[tuple[bytes, bytes]]:
    """(body between '$' and '*', its two checksum digits) of each sentence in ``text`` from its
    first '$': a line may carry several sentences glued together ('$..*hh$..*hh'); '$' opens a
    sentence and appears nowhere inside one (NMEA 0183 reserved character)."""
    out = []
    for piece in text.split(b"$")[1:]:
        star = piece.rfind(b"*")
        out.append((piece[:star], piece[star + 1:star + 3]) if star >= 0 else (piece.rstrip(), b""))
    return out


def _batches(path: Path, first_line: dict, size: int = 20000):
    """Batches of (line number, host prefix, sentence id, fields, checksum ok) of the sentences this
    reader uses, and the counts of everything else (comments, binary, unused sentences)."""
    counts: Counter = Counter()
    batch, bodies, given = [], [], []
    for number, raw in _lines(path):
        line = raw.strip()
        if not line:
            continue
        counts["lines"] += 1
        if line.startswith(b"#"):
            counts["comment"] += 1
            continue
        start = line.find(b"$")
        if start < 0:
            kind = "binary data (UBX or another binary protocol)" if _binary(line) else "not a sentence"
            counts[kind] += 1
            first_line.setdefault(kind, number)
            continue
        for body, checksum in _sentences(line[start:]):
            talker = body[2:5] if not body.startswith(b"P") else b"proprietary"
            ident = talker.decode("ascii", "replace")
            if ident not in USED:
                counts[f"unused {ident}"] += 1
                continue
            fields = body.split(b",")
            fields[0] = fields[0][:2]             # the talker (GP, GN ...): GGA from two of them share an epoch
            batch.append((number, line[:start], ident, fields))
            bodies.append(body)
            given.append(checksum)
        if len(batch) >= size:
            yield batch, _checksums_ok(bodies, given), counts
            batch, bodies, given = [], [], []
    yield batch, _checksums_ok(bodies, given), counts


def _binary(data: bytes) -> bool:
    return any(b < 9 or 13 < b < 32 or b > 126 for b in data)


def read_nmea_file(path: str | Path) -> NMEARecording:  # noqa: C901 - one pass over the sentences
    """Every GNSS epoch of an NMEA file, read a chunk at a time; a LogError names the file and line
    when nothing usable is in it. Bad checksums, malformed and unused sentences, binary data
    between sentences (UBX ...) and lines whose text before '$' is not a time are skipped and
    counted (the first line of each kind named); epochs dated before ones already read (the
    receiver's clock stepping back) are masked and named, and the recording is split there."""
    path = Path(path)
    epochs = _Epochs()
    dates: list[tuple[float, float, float]] = []        # (host, time of day, date seconds) per dated sentence
    first_line: dict[str, int] = {}
    last = None
    day_index, last_tod = 0, None
    counts: Counter = Counter()
    try:
        for batch, ok, counts in _batches(path, first_line):
            for (number, prefix, ident, f), good in zip(batch, ok):
                kind = _sentence(ident, f, prefix, good, number, epochs, dates, counts, first_line, (day_index, last_tod, last))
                if kind is not None:
                    day_index, last_tod, last = kind
    except OSError as exc:
        raise LogError(f"{path}: cannot read: {exc}") from None
    if not len(epochs.lines):
        what = ", ".join(f"{v} {k}" for k, v in counts.most_common(6)) or "no lines"
        bad = "; ".join(f"{k} first at line {n}" for k, n in first_line.items())
        raise LogError(f"{path}: no GGA sentence with a time (the reader needs GGA for position and time, "
                       f"'[host time] $..GGA,hhmmss.ss,ddmm.mm,N,dddmm.mm,E,q,...*hh' a line; found {what}"
                       + (f"; {bad}" if bad else "") + ")")
    frame = pd.DataFrame({c: np.frombuffer(epochs.columns[c], float) for c in _Epochs.COLUMNS})
    frame["line"] = np.frombuffer(epochs.lines, np.int64)
    notes: list[str] = []
    frame["utc"] = _utc(frame, dates, notes, path)
    for kind, n in first_line.items():
        notes.append(f"{path.name}: {counts[kind]} line(s) with {kind} removed, the sentence after it read (the first "
                     f"at line {n})" if kind.startswith("binary data before") else
                     f"{path.name}: {counts[kind]} line(s) skipped: {kind} (the first at line {n})")
    notes += _talker_notes(counts, path.name)
    if counts["repeated epoch"]:
        notes.append(f"{path.name}: {counts['repeated epoch']} GGA sentence(s) repeat the time of an epoch already "
                     f"read (an epoch written twice): the first kept")
    frame, breaks = ordered_in_time(frame, path.name, notes)
    said = rollover_by_written(path, float(frame["utc"].iloc[-1]), path.name) if len(frame) else None
    return NMEARecording(path, frame[["utc", "host", "lat", "lon", "height", "quality", "speed", "course", "heading",
                                      "position_std"]].reset_index(drop=True), counts, notes, breaks,
                         [{"at": None, "finding": said}] if said else [])


def _sentence(ident, f, prefix, good, number, epochs, dates, counts, first_line, state):
    """One sentence into the epochs; the new (day index, last time of day, last epoch) or None."""
    day_index, last_tod, last = state
    if not good:
        counts["bad checksum"] += 1
        first_line.setdefault("bad checksum", number)
        return None
    host = math.nan
    if prefix.strip():
        try:
            host = _host_stamp(prefix.decode("ascii"))
        except (ValueError, UnicodeDecodeError):
            kind = ("binary data before '$' (UBX or another binary protocol)" if _binary(prefix)
                    else "text before '$' that is neither UNIX seconds nor an ISO 8601 time")
            counts[kind] += 1
            first_line.setdefault(kind, number)
            if _binary(prefix):
                host = math.nan          # the sentence itself is whole (its checksum holds): used
            else:
                return None
    try:
        if ident in ("GGA", "RMC", "ZDA"):
            if not f[1]:
                counts[f"{ident} without time"] += 1
                return None
            tod = _hms(f[1])
        if ident == "GGA":
            if last_tod is not None and tod < last_tod - DAY / 2:
                day_index += 1                       # past midnight
            last_tod = tod
            key = (day_index, round(tod, 3))
            if key in epochs.recent:          # the epoch written again, or by a second talker
                return _again(epochs, epochs.recent[key], f, counts, (day_index, last_tod))
            quality = int(f[6]) if f[6] else 0
            fix = quality != 0 and bool(f[2])
            if fix:
                alt = (float(f[9]) if f[9] else 0.0) + (float(f[11]) if len(f) > 11 and f[11] else 0.0)
                last = epochs.add(key, number, tod, day_index, host, _degrees(f[2], f[3], 2), _degrees(f[4], f[5], 3),
                                  alt, float(quality))
            else:
                last = epochs.add(key, number, tod, day_index, host)
            epochs.talkers[last] = [f[0]]
            counts["GGA"] += 1
        elif ident == "RMC":
            if not dates and len(f) > 9 and len(f[9]) == 6 and f[9].isdigit():      # the first date is the one used
                yy = int(f[9][4:6])
                d = datetime.date(yy + (2000 if yy < 69 else 1900), int(f[9][2:4]), int(f[9][0:2]))
                dates.append((host, tod, _date_seconds(d)))
            i = epochs.recent.get((day_index, round(tod, 3)))
            if i is not None and f[2] == b"A" and f[7] and not math.isfinite(epochs.get(i, "speed")):
                epochs.set(i, "speed", float(f[7]) * KNOTS)
                epochs.set(i, "course", math.radians(float(f[8])) if f[8] else math.nan)
            counts["RMC"] += 1
        elif ident == "ZDA":
            if not dates and f[4]:
                dates.append((host, tod, _date_seconds(datetime.date(int(f[4]), int(f[3]), int(f[2])))))
            counts["ZDA"] += 1
        elif ident in ("HDT", "THS"):      # true heading, clockwise from north -> ENU yaw
            if last is not None and f[1]:
                epochs.set(last, "heading", math.pi / 2 - math.radians(float(f[1])))
            counts[ident] += 1
        elif ident == "GST":
            if last is not None and len(f) > 7 and f[6] and f[7]:
                epochs.set(last, "position_std", math.hypot(float(f[6]), float(f[7])))
            counts["GST"] += 1
        else:   # VTG: no time of its own, it belongs to the epoch its GGA opened
            if last is not None and len(f) > 7 and f[7] and not math.isfinite(epochs.get(last, "speed")):
                epochs.set(last, "speed", float(f[7]) / 3.6)
                epochs.set(last, "course", math.radians(float(f[1])) if f[1] else math.nan)
            counts["VTG"] += 1
    except (TypeError, ValueError, IndexError, OverflowError):
        counts["malformed"] += 1
        first_line.setdefault("malformed", number)
    return day_index, last_tod, last


COMBINED = b"GN"         # the talker of a solution from every constellation the receiver tracks


def _again(epochs: _Epochs, i: int, f: list, counts: Counter, state: tuple):
    """A GGA whose time is that of epoch ``i``: from the talker that opened it, the epoch written
    again (counted, the first kept); from another talker (GP beside GN), a second solution of the
    same epoch (counted per pair; the combined one, GN, kept where the other opened the epoch)."""
    seen = epochs.talkers.setdefault(i, [f[0]])
    if f[0] == seen[0]:
        counts["repeated epoch"] += 1
    elif f[0] not in seen:
        seen.append(f[0])
        counts["second talker " + "+".join(t.decode("ascii", "replace") for t in seen[:2])] += 1
        if f[0] == COMBINED and f[6] and int(f[6]) != 0 and f[2]:
            alt = (float(f[9]) if f[9] else 0.0) + (float(f[11]) if len(f) > 11 and f[11] else 0.0)
            for column, value in (("lat", _degrees(f[2], f[3], 2)), ("lon", _degrees(f[4], f[5], 3)), ("height", alt),
                                  ("quality", float(int(f[6])))):
                epochs.set(i, column, value)
    return state[0], state[1], i


def _talker_notes(counts: Counter, name: str) -> list[str]:
    """A note per pair of talkers that both gave GGA for the same epochs."""
    out = []
    for key, n in counts.items():
        if key.startswith("second talker "):
            first, second = key.removeprefix("second talker ").split("+")
            kept = "GN" if "GN" in (first, second) else first
            out.append(f"{name}: two talkers give GGA for the same epochs ({first} first, {second} second) on {n} "
                       f"epochs: one solution per epoch kept, {kept}'s"
                       + (" (the combined solution of every constellation)" if kept == "GN" else " (the first)"))
    return out


def _utc(frame: pd.DataFrame, dates: list, notes: list[str], path: Path) -> np.ndarray:
    """POSIX seconds of each epoch: the date from RMC or ZDA (the first one, days counted on past
    midnight), else from the host stamps, else 1970-01-01 with a note."""
    tod, day = frame["tod"].to_numpy(float), frame["day"].to_numpy(float)
    if dates:
        _, date_tod, date0 = dates[0]
        # the dated sentence's day index: that of the first GGA at or after its time of day
        base = date0 - DAY * day[int(np.argmin(np.abs(tod - date_tod)))]
        return base + DAY * day + tod
    host = frame["host"].to_numpy(float)
    if np.isfinite(host).any():
        i = int(np.argmax(np.isfinite(host)))
        guess = host[i] - tod[i] - DAY * day[i]
        base = DAY * round(guess / DAY)
        notes.append(f"{path.name}: no RMC or ZDA date: the date is taken from the host stamps")
        return base + DAY * day + tod
    notes.append(f"{path.name}: no RMC or ZDA date and no host stamps: times are seconds of the day "
                 f"(date unknown, shown as 1970-01-01)")
    return DAY * day + tod


def list_nmea(paths: list[Path]) -> list[str]:
    """``--list``: each NMEA file's epochs, fixes, rate and span, its sentences and the ranges of its fields."""
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
