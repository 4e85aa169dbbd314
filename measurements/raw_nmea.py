"""A recorded NMEA 0183 file as a table of GNSS epochs .

A line is a sentence, optionally after a host timestamp (UNIX seconds, ``1777622400.05 $GNGGA,...``,
candump style ``(1777622400.050000) $GNGGA,...``, or ISO 8601, ``2026-05-01T08:00:00.05Z $GNGGA,...``;
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
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .log import LogError

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


def read_nmea_file(path: str | Path) -> NMEARecording:
    """Every GNSS epoch of an NMEA file; a LogError names the file and line when nothing usable
    is in it. Bad checksums, malformed and unused sentences are counted in ``counts``."""
    from pynmeagps import VALCKSUM, NMEAReader

    path = Path(path)
    counts: Counter = Counter()
    rows: dict[tuple, dict] = {}
    order: list[tuple] = []
    dates: list[tuple[float, float, float]] = []        # (host, time of day, date seconds) per dated sentence
    last_key = None
    day_index, last_tod = 0, None
    try:
        text = path.read_bytes().decode("ascii", errors="replace")
    except OSError as exc:
        raise LogError(f"{path}: cannot read: {exc}") from None
    for number, raw in enumerate(text.splitlines(), 1):
        if not raw.strip():
            continue
        counts["lines"] += 1
        if raw.lstrip().startswith("#"):
            counts["comment"] += 1
            continue
        m = _STAMP.match(raw)
        if m is None:
            counts["not a sentence"] += 1
            continue
        prefix, sentence = m.groups()
        try:
            host = _host_stamp(prefix)
        except ValueError as exc:
            raise LogError(f"{path}: line {number}: {exc}") from None
        ident = sentence[3:6] if not sentence.startswith("$P") else "proprietary"
        if ident not in USED:
            counts[f"unused {ident}"] += 1
            continue
        try:
            msg = NMEAReader.parse(sentence.strip().encode() + b"\r\n", validate=VALCKSUM)
        except Exception as exc:               # noqa: BLE001 - a parser error is one bad sentence
            counts["bad checksum" if "checksum" in str(exc).lower() else "malformed"] += 1
            continue
        try:
            if ident in ("GGA", "RMC", "ZDA"):
                if msg.time == "":
                    counts[f"{ident} without time"] += 1
                    continue
                tod = _seconds_of_day(msg.time)
            if ident == "GGA":
                if last_tod is not None and tod < last_tod - DAY / 2:
                    day_index += 1                       # past midnight
                last_tod = tod
                key = (day_index, round(tod, 3))
                if key in rows:
                    counts["repeated epoch"] += 1
                    last_key = key
                    continue
                fix = msg.quality not in ("", 0) and msg.lat != ""
                alt = (float(msg.alt) if msg.alt != "" else 0.0) + (float(msg.sep) if msg.sep != "" else 0.0)
                rows[key] = dict(tod=tod, day=day_index, host=host, lat=float(msg.lat) if fix else math.nan,
                                 lon=float(msg.lon) if fix else math.nan, height=alt if fix else math.nan,
                                 quality=int(msg.quality) if fix else 0, speed=math.nan, course=math.nan,
                                 heading=math.nan, position_std=math.nan)
                order.append(key)
                last_key = key
                counts["GGA"] += 1
            elif ident == "RMC":
                if msg.date != "":
                    dates.append((host, tod, _date_seconds(msg.date)))
                key = (day_index, round(tod, 3))
                if key in rows and msg.status == "A" and msg.spd != "":
                    rows[key]["speed"] = float(msg.spd) * KNOTS
                    rows[key]["course"] = math.radians(float(msg.cog)) if msg.cog != "" else math.nan
                counts["RMC"] += 1
            elif ident == "ZDA":
                if msg.year != "":
                    dates.append((host, tod, _date_seconds(datetime.date(int(msg.year), int(msg.month), int(msg.day)))))
                counts["ZDA"] += 1
            elif ident in ("HDT", "THS"):      # true heading, clockwise from north -> ENU yaw
                value = msg.headingT if ident == "HDT" else msg.headt
                if last_key is not None and value != "":
                    rows[last_key]["heading"] = math.pi / 2 - math.radians(float(value))
                counts[ident] += 1
            elif ident == "GST":
                if last_key is not None and msg.stdLat != "" and msg.stdLong != "":
                    rows[last_key]["position_std"] = math.hypot(float(msg.stdLat), float(msg.stdLong))
                counts["GST"] += 1
            else:   # VTG: no time of its own, it belongs to the epoch its GGA opened
                if last_key is not None and msg.sogk != "":
                    row = rows[last_key]
                    if not math.isfinite(row["speed"]):
                        row["speed"] = float(msg.sogk) / 3.6
                        row["course"] = math.radians(float(msg.cogt)) if msg.cogt != "" else math.nan
                counts["VTG"] += 1
        except (TypeError, ValueError, AttributeError):
            counts["malformed"] += 1
    if not order:
        what = ", ".join(f"{v} {k}" for k, v in counts.most_common(6)) or "no lines"
        raise LogError(f"{path}: no GGA sentence with a time (the reader needs GGA for position and time; "
                       f"found {what})")
    frame = pd.DataFrame([rows[k] for k in order])
    notes: list[str] = []
    frame["utc"] = _utc(frame, dates, notes, path)
    frame = frame.sort_values("utc", kind="stable").drop_duplicates("utc").reset_index(drop=True)
    return NMEARecording(path, frame[["utc", "host", "lat", "lon", "height", "quality", "speed", "course", "heading",
                                      "position_std"]], counts, notes)


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
