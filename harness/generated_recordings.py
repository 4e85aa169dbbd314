"""Small generated recordings for the reader tests and benchmarks: an NMEA track, a candump log and an ISO 11783-10
time log, each with the fault a test puts into it (written here from known values, so that what a
reader returns can be compared with what was written)."""
from __future__ import annotations

import datetime
import math
import struct
from functools import reduce
from pathlib import Path

LAT0, LON0 = 52.0, 5.0
EPOCH_1980 = datetime.datetime(1980, 1, 1, tzinfo=datetime.timezone.utc)


def sentence(body: str) -> str:
    """'$BODY*hh' with the NMEA 0183 checksum (XOR of the body's characters)."""
    return f"${body}*{reduce(lambda a, c: a ^ ord(c), body, 0):02X}"


def _dm(value: float, width: int) -> str:
    d = int(abs(value))
    return f"{d:0{width}d}{(abs(value) - d) * 60:08.5f}"


def track(t: float, speed: float = 2.0) -> tuple[float, float]:
    """(lat, lon) of a vehicle driving east at ``speed`` m/s from (LAT0, LON0)."""
    east = speed * t
    return LAT0, LON0 + math.degrees(east / (6_371_000.0 * math.cos(math.radians(LAT0))))


def nmea_epoch(utc: datetime.datetime, lat: float, lon: float, speed: float = 2.0) -> list[str]:
    hms = utc.strftime("%H%M%S.") + f"{utc.microsecond // 10000:02d}"
    gga = (f"GPGGA,{hms},{_dm(lat, 2)},{'N' if lat >= 0 else 'S'},{_dm(lon, 3)},{'E' if lon >= 0 else 'W'},"
           f"4,12,0.8,10.0,M,47.0,M,,")
    rmc = (f"GPRMC,{hms},A,{_dm(lat, 2)},{'N' if lat >= 0 else 'S'},{_dm(lon, 3)},{'E' if lon >= 0 else 'W'},"
           f"{speed / (1852 / 3600):.3f},90.0,{utc.strftime('%d%m%y')},,,A")
    return [sentence(gga), sentence(rmc)]


def nmea_lines(seconds: float, rate: float = 10.0, step_back: tuple[float, float] | None = None,
               start=datetime.datetime(2026, 5, 1, 8, 0, tzinfo=datetime.timezone.utc)):
    """NMEA lines of a straight drive; ``step_back`` = (at, by): from ``at`` s on the receiver's
    clock reads ``by`` s less (a clock that steps back), the position still the true one."""
    for k in range(int(seconds * rate)):
        t = k / rate
        shown = t - (step_back[1] if step_back and t >= step_back[0] else 0.0)
        yield from nmea_epoch(start + datetime.timedelta(seconds=shown), *track(t))


def write_nmea(path: Path, seconds: float = 120.0, **kw) -> Path:
    path.write_text("\n".join(nmea_lines(seconds, **kw)) + "\n")
    return path


# --- ISO 11783-10 time log ----------------------------------------------------------------------------
TLG_HEADER = ('<?xml version="1.0" encoding="UTF-8"?>\n<TIM A="" D="4">\n<PTN A="" B="" D=""/>\n'
              '<DLV A="0084" B="" C="DET-1"/>\n</TIM>\n')


def tlg_record(utc: datetime.datetime, lat: float, lon: float, speed_mm_s: int = 2000) -> bytes:
    since = utc - EPOCH_1980
    ms = int(round((since.total_seconds() % 86400) * 1000))
    return (struct.pack("<IH", ms, since.days) + struct.pack("<iiB", round(lat * 1e7), round(lon * 1e7), 4)
            + struct.pack("<BBi", 1, 0, speed_mm_s))


def write_timelog(folder: Path, seconds: int = 300, lat_at: dict | None = None, step_back: tuple | None = None,
                  padding: int = 0, name: str = "TLG00001",
                  start=datetime.datetime(2026, 5, 1, 8, 0, tzinfo=datetime.timezone.utc)) -> Path:
    """A 1 Hz time log of a straight drive: ``lat_at`` {record: latitude} puts a latitude in place
    of the true one, ``step_back`` (at, by) sets the clock back, ``padding`` zero records at the end."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"{name}.xml").write_text(TLG_HEADER)
    out = bytearray()
    for k in range(seconds):
        lat, lon = track(float(k))
        lat = (lat_at or {}).get(k, lat)
        shown = k - (step_back[1] if step_back and k >= step_back[0] else 0)
        out += tlg_record(start + datetime.timedelta(seconds=shown), lat, lon)
    out += bytes(struct.calcsize("<IHiiB") * padding + padding)     # a zero record: no time, no fix, N = 0
    (folder / f"{name}.bin").write_bytes(bytes(out))
    return folder


# --- CAN (candump -L) ----------------------------------------------------------------------------------
def candump_lines(seconds: float, rate: float = 20.0, start: float = 1_777_622_400.0):
    """candump lines of the project's TractorFeedback (0x280) at ``rate``: a wheel angle of
    0.2 sin(0.5 t) rad, a yaw rate of 0.1 sin(0.5 t) rad/s, 2 m/s (encoded with its DBC's scaling)."""
    for k in range(int(seconds * rate)):
        t = k / rate
        angle = round(0.2 * math.sin(0.5 * t) / 1e-4)
        yaw = round(0.1 * math.sin(0.5 * t) / 1e-4)
        data = struct.pack("<hhH", angle, yaw, 2000) + bytes([(k % 16) << 4, 0])
        yield f"({start + t:.6f}) can0 280#{data.hex().upper()}"


def write_candump(path: Path, seconds: float = 60.0, bad: dict[int, str] | None = None, **kw) -> Path:
    """A candump log; ``bad`` {index: text} puts a line that is not a frame before the index-th frame."""
    lines = []
    for k, line in enumerate(candump_lines(seconds, **kw)):
        if bad and k in bad:
            lines.append(bad[k])
        lines.append(line)
    path.write_text("\n".join(lines) + "\n")
    return path
