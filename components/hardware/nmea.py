"""NMEA 0183 in and out: a byte stream parser that never raises, sentence writers, and the local
east/north/up frame about a datum (pymap3d, WGS-84).

Imported where used: pynmeagps, pymap3d (the hardware extra).
"""
from __future__ import annotations

import datetime
import math
from dataclasses import dataclass, field

from agrobot.orchestrator.component import inp, par

KNOTS = 1852.0 / 3600.0          # m/s per knot
TALKERS = {"GP", "GN", "GL", "GA", "GB", "GQ", "GI"}
USED = {"GGA", "VTG", "RMC", "GST", "HDT"}      # ZDA, GSA, GSV ... are counted as unused, quietly
RTK_FIXED = 4
# GGA fix quality codes are not ordered by goodness (5, RTK float, is worse than 4, RTK fixed):
# rank them before comparing. 6 dead reckoning, 7 manual and 8 simulation carry no measurement.
FIX_RANK = {0: 0, 1: 1, 2: 2, 3: 2, 9: 2, 5: 3, 4: 4, 6: 0, 7: 0, 8: 0}


def fix_at_least(quality: float, required: float) -> bool:
    """True when GGA ``quality`` is as good as ``required`` (by FIX_RANK)."""
    return FIX_RANK.get(int(quality), 0) >= FIX_RANK.get(int(required), 4)


@dataclass
class Position:
    latitude: float                 # rad
    longitude: float                # rad
    height: float                   # m above the ellipsoid (MSL altitude + geoid separation)
    quality: int                    # GGA fix quality: 0 none, 1 GPS, 2 DGPS, 4 RTK fixed, 5 RTK float
    satellites: int


@dataclass
class Velocity:
    speed: float                    # m/s over ground
    course: float                   # rad, from north, clockwise


@dataclass
class PositionError:
    """GST: 1-sigma errors of the position (m)."""

    std_north: float
    std_east: float
    std_height: float


@dataclass
class Heading:
    """HDT: true heading of a dual-antenna receiver (rad, from north, clockwise)."""

    heading: float


@dataclass
class StreamCounters:
    sentences: int = 0
    bad_checksum: int = 0
    malformed: int = 0              # checksum fine but fields unusable, or the parser refused it
    unknown: int = 0                # unknown talker or a sentence this adapter does not use
    partial: int = 0                # truncated lines, bytes before '$', overlong garbage
    poor_fix: int = 0               # GGA below the required fix quality
    bad_value: int = 0              # a field not finite or outside its physical range (PLAUSIBLE)
    dropped_bytes: int = 0          # bytes skipped unread because more arrived than a step may take


# physical ranges of the fields the adapter uses (NaN and inf are outside every range): a sentence
# carrying a value outside is dropped and counted; a GGA's fix is downgraded to quality 0
PLAUSIBLE = {"lat": (-90.0, 90.0), "lon": (-180.0, 180.0), "alt": (-1000.0, 20000.0), "sep": (-200.0, 200.0),
             "numSV": (0, 99), "speed": (0.0, 99.99), "course": (0.0, 360.0), "std": (0.0, 1000.0),
             "heading": (0.0, 360.0)}


class BadValue(ValueError):
    """A field that parsed but is not a physical value (NaN, inf, out of range)."""


def plausible(name: str, value: float) -> float:
    """``value`` when finite and inside PLAUSIBLE[name]; ValueError naming the field otherwise."""
    low, high = PLAUSIBLE[name]
    if not (math.isfinite(value) and low <= value <= high):
        raise BadValue(f"{name} {value!r}: expected a finite value in [{low:g}, {high:g}]")
    return value


@dataclass
class NMEAStream:
    """Feed bytes as they arrive; complete lines are parsed with pynmeagps. Nothing raises."""

    max_line: int = 256
    counters: StreamCounters = field(default_factory=StreamCounters)
    _buffer: bytes = b""

    def resync(self) -> None:
        """Forget a partial line (the bytes before the next ones were skipped)."""
        self._buffer = b""

    def feed(self, data: bytes) -> list[Position | Velocity | PositionError | Heading]:
        out: list[Position | Velocity | PositionError | Heading] = []
        self._buffer += bytes(data)
        *lines, self._buffer = self._buffer.split(b"\n")
        if len(self._buffer) > self.max_line:          # no newline in sight: garbage
            self.counters.partial += 1
            self._buffer = b""
        for line in lines:
            item = self._line(line.strip(b"\r"))
            if item is not None:
                out.append(item)
        return out

    def _line(self, line: bytes):
        from pynmeagps import NMEAReader, VALCKSUM
        from pynmeagps.exceptions import NMEAParseError

        c = self.counters
        start = line.rfind(b"$")
        if start < 0:
            if line.strip():
                c.partial += 1
            return None
        if start > 0:
            c.partial += 1                               # the end of a cut sentence before '$'
            line = line[start:]
        if b"*" not in line or len(line) < 10 or len(line) > self.max_line:
            c.partial += 1
            return None
        c.sentences += 1
        if line.startswith(b"$P"):                      # proprietary (PGRME, PUBX ...): not used here
            c.unknown += 1
            return None
        try:
            msg = NMEAReader.parse(line + b"\r\n", validate=VALCKSUM)
        except NMEAParseError as exc:
            if "checksum" in str(exc).lower():
                c.bad_checksum += 1
            else:
                c.malformed += 1
            return None
        except Exception:                                # noqa: BLE001 - a parser error is a bad sentence
            c.malformed += 1
            return None
        talker, ident = getattr(msg, "talker", ""), getattr(msg, "msgID", "")
        if msg is None or talker not in TALKERS or ident not in USED:
            c.unknown += 1
            return None
        try:
            return self._fields(msg, ident)
        except BadValue:
            c.bad_value += 1
            if ident == "GGA":                           # the fix is downgraded: no position this epoch
                return Position(math.nan, math.nan, math.nan, 0, 0)
            return None
        except (TypeError, ValueError, AttributeError):
            c.malformed += 1
            return None

    def _fields(self, msg, ident: str):
        if ident == "GGA" and msg.quality in ("", 0):
            return Position(math.nan, math.nan, math.nan, 0, 0)    # a receiver without a fix says so
        if ident == "GGA" and (msg.lat == "" or msg.lon == ""):
            raise BadValue("a fix quality without a position")
        if (ident == "RMC" and msg.status == "V") or (ident == "VTG" and msg.sogk == "" and msg.sogn == "") \
                or (ident == "GST" and msg.stdLat == ""):
            return None                                          # no fix: nothing to measure
        if ident == "GGA":
            q = int(msg.quality)
            if not 0 <= q <= 9:
                raise ValueError("quality out of range")
            lat, lon = plausible("lat", float(msg.lat)), plausible("lon", float(msg.lon))
            alt = plausible("alt", float(msg.alt)) if msg.alt != "" else 0.0
            sep = plausible("sep", float(msg.sep)) if getattr(msg, "sep", "") != "" else 0.0
            sats = int(plausible("numSV", float(msg.numSV))) if msg.numSV != "" else 0
            return Position(math.radians(lat), math.radians(lon), alt + sep, q, sats)
        if ident == "GST":
            std = (plausible("std", float(msg.stdLat)), plausible("std", float(msg.stdLong)),
                   plausible("std", float(msg.stdAlt)) if msg.stdAlt != "" else math.nan)
            return PositionError(*std)
        if ident == "HDT":
            return Heading(math.radians(plausible("heading", float(msg.headingT))))
        if ident == "VTG":
            if msg.sogk != "":
                speed = float(msg.sogk) / 3.6
            else:
                speed = float(msg.sogn) * KNOTS
            course = float(msg.cogt) if msg.cogt != "" else 0.0
        else:   # RMC
            if msg.status != "A":
                raise ValueError(f"RMC status {msg.status!r}")
            speed, course = float(msg.spd) * KNOTS, float(msg.cog) if msg.cog != "" else 0.0
        return Velocity(plausible("speed", speed), math.radians(plausible("course", course)))


DATUM_PARAMETERS = (
    par("datum_latitude", "rad", 0.0, "latitude of the local frame's origin"),
    par("datum_longitude", "rad", 0.0, "longitude of the local frame's origin"),
    par("datum_height", "m", 0.0, "ellipsoidal height of the origin"),
)


class LocalFrame:
    """East/north/up about a datum (WGS-84), angles in radians."""

    def __init__(self, latitude: float, longitude: float, height: float) -> None:
        self.datum = (latitude, longitude, height)

    @classmethod
    def of(cls, p: dict) -> "LocalFrame":
        """From a component's DATUM_PARAMETERS."""
        return cls(p["datum_latitude"], p["datum_longitude"], p["datum_height"])

    def to_local(self, latitude: float, longitude: float, height: float) -> tuple[float, float, float]:
        import pymap3d

        e, n, u = pymap3d.geodetic2enu(latitude, longitude, height, *self.datum, deg=False)
        return float(e), float(n), float(u)

    def to_geodetic(self, east: float, north: float, up: float = 0.0) -> tuple[float, float, float]:
        import pymap3d

        lat, lon, h = pymap3d.enu2geodetic(east, north, up, *self.datum, deg=False)
        return float(lat), float(lon), float(h)


# what a receiver sends, and the writer can write. GST carries the 1-sigma errors; PGRME (Garmin's
# estimated position error, 50 % radii) is what gpsd 3.22 turns into its TPV epx/epy/epv, and it
# must come within the epoch's cycle (before RMC, which ends gpsd's cycle)
SENTENCES = ("GGA", "GST", "PGRME", "VTG", "RMC", "ZDA")
CEP50 = math.sqrt(2.0 * math.log(2.0))        # 1.1774: the 50 % radius of a circular 2-D normal, in sigmas
HALF_1D = 0.6745                              # the 50 % half-width of a 1-D normal, in sigmas
DEFAULT_EPOCH = "2026-05-01T08:00:00Z"                 # UTC of t = 0 when a study names none
# fix quality -> (FAA mode indicator of VTG/RMC, HDOP): an RTK fix sees many satellites
FIX_MODES = {0: ("N", 99.99), 1: ("A", 1.2), 2: ("D", 0.9), 4: ("R", 0.7), 5: ("F", 0.8)}


# what a receiver's NMEA is made of (the emulator's server and the bus recorder write it)
RECEIVER_INPUTS = (
    inp("x", "m", 0.0, "antenna east position"),
    inp("y", "m", 0.0, "antenna north position"),
    inp("vel_east", "m/s", 0.0, "antenna east velocity"),
    inp("vel_north", "m/s", 0.0, "antenna north velocity"),
    inp("fix_valid", "1", 1.0, "1 when a fix is available"),
)
RECEIVER_PARAMETERS = (
    par("talker", "", "GN", "NMEA talker id (GN, GP, GL, GA, GB, GQ, GI)"),
    par("sentences", "", ",".join(SENTENCES), "sentences sent each step, in order (of GGA, GST, PGRME, VTG, RMC, ZDA)"),
    par("epoch", "", DEFAULT_EPOCH, "UTC date and time of t = 0 (ISO 8601)"),
    par("position_std", "m", 0.02, "1-sigma horizontal position error reported in GST (the GPS error model's)"),
)


def receiver_settings(component) -> tuple[tuple[str, ...], datetime.datetime]:
    """(sentence ids, epoch) from a component's RECEIVER_PARAMETERS; bad values are the
    component's error, naming the parameter."""
    p = component.p
    component.require(p["talker"] in TALKERS, f"talker {p['talker']!r}: expected one of {', '.join(sorted(TALKERS))}")
    sentences = tuple(x.strip().upper() for x in str(p["sentences"]).split(",") if x.strip())
    component.require(bool(sentences) and all(x in SENTENCES for x in sentences),
                      f"sentences {p['sentences']!r}: expected a comma-separated list of {', '.join(SENTENCES)}")
    try:
        epoch = parse_epoch(p["epoch"])
    except ValueError:
        component.require(False, f"epoch {p['epoch']!r}: expected an ISO 8601 UTC time like {DEFAULT_EPOCH}")
    return sentences, epoch


def parse_epoch(text: str) -> datetime.datetime:
    """An ISO 8601 UTC time (``2026-05-01T08:00:00Z``) as an aware datetime; ValueError otherwise."""
    when = datetime.datetime.fromisoformat(str(text).replace("Z", "+00:00"))
    if when.tzinfo is None:
        when = when.replace(tzinfo=datetime.timezone.utc)
    return when.astimezone(datetime.timezone.utc)


def receiver_sentences(when: datetime.datetime, latitude: float | None, longitude: float | None, height: float,
                       vel_east: float, vel_north: float, quality: int = RTK_FIXED, *, talker: str = "GN",
                       sentences=SENTENCES, position_std: float = 0.02, height_std: float | None = None,
                       satellites: int = 14) -> bytes:
    """What a receiver sends for one epoch at UTC ``when``: GGA (position, quality, HDOP), VTG and
    RMC (speed and course; RMC with the date, status A or V), GST (the 1-sigma position errors:
    ``position_std`` per horizontal axis, ``height_std`` vertically, default 2x), PGRME (the same
    errors as 50 % radii: CEP50 = 1.1774 sigma) and ZDA (date and time), in the order of ``sentences``. ``quality`` 0 (no fix) writes the sentences with empty
    position fields, RMC status V and mode N, as receivers do. Minutes of arc with 7 decimals
    (0.2 mm)."""
    from pynmeagps import GET, NMEAMessage

    fix = quality != 0 and latitude is not None
    mode, hdop = FIX_MODES.get(int(quality), ("A", 1.5))
    stamp = when.time().replace(tzinfo=None)
    speed = math.hypot(vel_east, vel_north)
    course = math.degrees(math.atan2(vel_east, vel_north)) % 360.0
    where = dict(lat=math.degrees(latitude), NS="N" if latitude >= 0 else "S", lon=math.degrees(longitude),
                 EW="E" if longitude >= 0 else "W") if fix else dict(lat="", NS="", lon="", EW="")
    out = []
    for ident in sentences:
        if ident == "GGA":
            fields = dict(time=stamp, **where, quality=int(quality) if fix else 0, numSV=int(satellites) if fix else 0,
                          HDOP=hdop if fix else 99.99, alt=round(height, 4) if fix else "", altUnit="M",
                          sep=0.0 if fix else "", sepUnit="M", diffAge=1.0 if quality in (2, 4, 5) else "",
                          diffStation=0 if quality in (2, 4, 5) else "")
        elif ident == "VTG":
            fields = dict(cogt=round(course, 2) if fix else "", cogtUnit="T", cogm="", cogmUnit="M",
                          sogn=round(speed / KNOTS, 4) if fix else "", sognUnit="N",
                          sogk=round(speed * 3.6, 4) if fix else "", sogkUnit="K", posMode=mode if fix else "N")
        elif ident == "RMC":
            fields = dict(time=stamp, status="A" if fix else "V", **where, spd=round(speed / KNOTS, 4) if fix else "",
                          cog=round(course, 2) if fix else "", date=when.date(), mv="", mvEW="",
                          posMode=mode if fix else "N", navStatus="S" if fix else "V")
        elif ident == "GST" and not fix:
            fields = dict(time=stamp, rangeRms="", stdMajor="", stdMinor="", orient="", stdLat="", stdLong="", stdAlt="")
        elif ident == "GST":
            sh = float(position_std)
            sv = float(height_std) if height_std is not None else 2.0 * sh
            fields = dict(time=stamp, rangeRms=round(sh * math.sqrt(2.0), 4), stdMajor=round(sh, 4), stdMinor=round(sh, 4),
                          orient=0.0, stdLat=round(sh, 4), stdLong=round(sh, 4), stdAlt=round(sv, 4))
        elif ident == "ZDA":
            fields = dict(time=stamp, day=when.day, month=when.month, year=when.year, ltzh="00", ltzn="00")
        elif ident == "PGRME":
            sh = float(position_std)
            sv = float(height_std) if height_std is not None else 2.0 * sh
            hpe, vpe = CEP50 * sh, HALF_1D * sv
            body = f"PGRME,{hpe:.4f},M,{vpe:.4f},M,{math.hypot(hpe, vpe):.4f},M" if fix else "PGRME,,M,,M,,M"
            out.append(_with_checksum(body))
            continue
        else:
            raise ValueError(f"sentence {ident!r}: the writer knows {', '.join(SENTENCES)}")
        out.append(NMEAMessage(talker, ident, GET, hpnmeamode=ident in ("GGA", "RMC"), **fields).serialize())
    return b"".join(out)


def _with_checksum(body: str) -> bytes:
    """``$body*hh`` and CR LF: a sentence pynmeagps does not write (a proprietary one)."""
    check = 0
    for ch in body.encode():
        check ^= ch
    return f"${body}*{check:02X}\r\n".encode()


def gga_vtg(t: float, latitude: float, longitude: float, height: float, vel_east: float, vel_north: float,
            quality: int = RTK_FIXED, satellites: int = 14, talker: str = "GN") -> bytes:
    """GGA and VTG for ``t`` seconds after the default epoch (the pair the first emulator sent)."""
    when = parse_epoch(DEFAULT_EPOCH) + datetime.timedelta(seconds=t)
    return receiver_sentences(when, latitude, longitude, height, vel_east, vel_north, quality, talker=talker,
                              sentences=("GGA", "VTG"), satellites=satellites)
