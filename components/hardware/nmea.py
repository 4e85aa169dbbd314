"""NMEA 0183 in and out: a byte stream parser that never raises, sentence writers, and the local
east/north/up frame about a datum (pymap3d, WGS-84)."""
from __future__ import annotations

import datetime
import math
from dataclasses import dataclass, field

from orchestrator.component import par

KNOTS = 1852.0 / 3600.0          # m/s per knot
TALKERS = {"GP", "GN", "GL", "GA", "GB", "GQ", "GI"}
USED = {"GGA", "VTG", "RMC"}
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
class StreamCounters:
    sentences: int = 0
    bad_checksum: int = 0
    malformed: int = 0              # checksum fine but fields unusable, or the parser refused it
    unknown: int = 0                # unknown talker or a sentence this adapter does not use
    partial: int = 0                # truncated lines, bytes before '$', overlong garbage
    poor_fix: int = 0               # GGA below the required fix quality


@dataclass
class NMEAStream:
    """Feed bytes as they arrive; complete lines are parsed with pynmeagps. Nothing raises."""

    max_line: int = 256
    counters: StreamCounters = field(default_factory=StreamCounters)
    _buffer: bytes = b""

    def feed(self, data: bytes) -> list[Position | Velocity]:
        out: list[Position | Velocity] = []
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
        except (TypeError, ValueError, AttributeError):
            c.malformed += 1
            return None

    def _fields(self, msg, ident: str):
        if ident == "GGA":
            lat, lon, q = float(msg.lat), float(msg.lon), int(msg.quality)
            if not (-90 <= lat <= 90 and -180 <= lon <= 180) or not 0 <= q <= 9:
                raise ValueError("out of range")
            alt = float(msg.alt) if msg.alt != "" else 0.0
            sep = float(msg.sep) if getattr(msg, "sep", "") != "" else 0.0
            sats = int(msg.numSV) if msg.numSV != "" else 0
            return Position(math.radians(lat), math.radians(lon), alt + sep, q, sats)
        if ident == "VTG":
            if msg.sogk != "":
                speed = float(msg.sogk) / 3.6
            else:
                speed = float(msg.sogn) * KNOTS
            course = float(msg.cogt) if msg.cogt != "" else 0.0
        else:   # RMC
            if msg.status != "A":
                raise ValueError("RMC not valid")
            speed, course = float(msg.spd) * KNOTS, float(msg.cog) if msg.cog != "" else 0.0
        if not (0 <= speed < 100 and 0 <= course <= 360):
            raise ValueError("out of range")
        return Velocity(speed, math.radians(course))


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


def gga_vtg(t: float, latitude: float, longitude: float, height: float, vel_east: float, vel_north: float,
            quality: int = RTK_FIXED, satellites: int = 14, talker: str = "GN") -> bytes:
    """A GGA (position, fix quality; 7 decimals of minutes: 0.2 mm) and a VTG (speed, course) for
    time ``t`` seconds after midnight UTC. Heights: altitude given as ellipsoidal, separation 0."""
    from pynmeagps import GET, NMEAMessage

    stamp = (datetime.datetime(2000, 1, 1) + datetime.timedelta(seconds=t % 86400.0)).time()
    gga = NMEAMessage(talker, "GGA", GET, hpnmeamode=True, time=stamp,
                      lat=math.degrees(latitude), NS="N" if latitude >= 0 else "S",
                      lon=math.degrees(longitude), EW="E" if longitude >= 0 else "W",
                      quality=int(quality), numSV=int(satellites), HDOP=0.7, alt=round(height, 4), altUnit="M",
                      sep=0.0, sepUnit="M", diffAge=1.0, diffStation=0)
    speed = math.hypot(vel_east, vel_north)
    course = math.degrees(math.atan2(vel_east, vel_north)) % 360.0
    vtg = NMEAMessage(talker, "VTG", GET, cogt=round(course, 2), cogtUnit="T", cogm="", cogmUnit="M",
                      sogn=round(speed / KNOTS, 4), sognUnit="N", sogk=round(speed * 3.6, 4), sogkUnit="K",
                      posMode="R" if quality == RTK_FIXED else ("F" if quality == 5 else "A"))
    return gga.serialize() + vtg.serialize()
