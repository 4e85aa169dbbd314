"""GPS receiver over NMEA 0183 (hardware adapter): the outputs of gps_sensor plus fix quality.

Reads whatever bytes arrived since the last step from a pyserial URL (``/dev/ttyUSB0``,
``socket://127.0.0.1:10110``, ``rfc2217://...``), parses GGA (position, fix quality) and VTG or RMC
(speed, course over ground), GST (position error statistics) and HDT (true heading of a dual
antenna) with pynmeagps, any talker (GN, GP, GL, ...), and converts latitude/longitude/height to
east/north about the study's datum; other sentences (ZDA, GSA, GSV ...) are counted as unused. Bad checksums, partial lines, unknown sentences and fixes worse than
``min_fix_quality`` (4 = RTK fixed; 5, RTK float, is worse) are counted in outputs and flagged
(``fix_valid`` = 0); none is fatal. ``fix_age`` is the time since the last good fix arrived.

Every field is judged before use (hardware.nmea.PLAUSIBLE: finite and in its physical range); a
sentence carrying a bad value is dropped and counted (``bad_values``), a GGA's fix downgraded to
quality 0. Work per step is bounded: at most ``max_read_bytes`` are read and the newest
``max_parse_bytes`` of them parsed (the rest counted in ``dropped_bytes``); a step that reads its
whole allowance (the receiver sends faster than a step may take) cannot tell its newest fix, so
its fixes are not used (``flooded_steps``) and the fix ages until the flood ends.

Imported where used: serial (the hardware extra, pyserial).
"""
from __future__ import annotations

import math
import time

from agrobot.orchestrator.component import Component, out, par

from .hardware.nmea import (DATUM_PARAMETERS, RTK_FIXED, Heading, LocalFrame, NMEAStream, Position,
                           PositionError, Velocity, fix_at_least)


def finite(item) -> bool:
    """Every measured field of a parsed item is finite (a GGA without a fix carries NaN by design,
    GST's height error may be absent)."""
    if isinstance(item, Position) and item.quality == 0:
        return True
    return all(math.isfinite(v) for k, v in vars(item).items() if isinstance(v, float) and k != "std_height")


class NMEAGPS(Component):
    sampled = True
    roles = ("gps_receiver",)
    variables = (
        par("url", "", "socket://127.0.0.1:10110", "pyserial URL or device of the receiver"),
        par("baudrate", "1/s", 115200, "serial line speed (ignored for sockets)"),
        *DATUM_PARAMETERS,
        par("min_fix_quality", "1", RTK_FIXED, "GGA quality needed for a valid fix (4 RTK fixed)"),
        par("connect_timeout", "s", 5.0, "how long to retry opening the port"),
        par("record_file", "", "", "record every line received, after the host's UNIX time of its arrival "
            "(empty: no recording)"),
        par("max_read_bytes", "B", 16384, "bytes read per step at most (a step reading them all is flooded)"),
        par("max_parse_bytes", "B", 4096, "the newest bytes of a step parsed (older ones counted as dropped)"),
        out("x", "m", 0.0, "east position of the antenna"),
        out("y", "m", 0.0, "north position of the antenna"),
        out("vel_east", "m/s", 0.0, "east velocity (VTG/RMC)"),
        out("vel_north", "m/s", 0.0, "north velocity"),
        out("fix_valid", "1", 0.0, "1 when a good fix arrived during this step"),
        out("fix_age", "s", 0.0, "time since the last good fix arrived"),
        out("fix_quality", "1", 0.0, "GGA quality of the latest fix (0 none, 4 RTK fixed, 5 float)"),
        out("satellites", "1", 0.0, "satellites used"),
        out("position_std", "m", 0.0, "1-sigma horizontal position error the receiver reports (GST; 0: none yet)"),
        out("heading", "rad", 0.0, "true heading of a dual antenna (HDT), from east counter-clockwise"),
        out("heading_valid", "1", 0.0, "1 when an HDT arrived during this step"),
        out("bad_checksums", "1", 0.0, "sentences with a wrong checksum so far"),
        out("malformed_sentences", "1", 0.0, "sentences the parser refused so far"),
        out("unknown_sentences", "1", 0.0, "sentences of an unknown talker or type so far"),
        out("partial_lines", "1", 0.0, "truncated lines and stray bytes so far"),
        out("poor_fixes", "1", 0.0, "fixes below min_fix_quality so far"),
        out("bad_values", "1", 0.0, "sentences dropped for a non-finite or out-of-range field so far"),
        out("dropped_bytes", "1", 0.0, "bytes skipped because more arrived than a step may take, so far"),
        out("flooded_steps", "1", 0.0, "steps that read max_read_bytes, their fixes unused, so far"),
    )
    feedthrough = {}

    def initialize(self, t0: float, dt: float) -> None:
        import serial

        p = self.p
        self.frame = LocalFrame.of(p)
        self.stream = NMEAStream()
        self.last_good = t0
        self.port = self.record = None
        self.partial = b""
        self.flooded = 0
        self.require(int(p["max_read_bytes"]) >= int(p["max_parse_bytes"]) > 256,
                     f"max_read_bytes {p['max_read_bytes']}, max_parse_bytes {p['max_parse_bytes']}: expected "
                     "max_read_bytes >= max_parse_bytes > 256 (a sentence)")
        if p["record_file"]:
            try:
                self.record = open(p["record_file"], "a", buffering=1, encoding="ascii", errors="replace")
            except OSError as exc:
                self.require(False, f"cannot record NMEA to {p['record_file']!r}: {exc}")
        deadline = time.monotonic() + float(p["connect_timeout"])
        while True:
            try:
                self.port = serial.serial_for_url(p["url"], baudrate=int(p["baudrate"]), timeout=0)
                break
            except (serial.SerialException, OSError, ValueError) as exc:
                if time.monotonic() > deadline:
                    self.require(False, f"cannot open GPS port {p['url']!r}: {exc}")
                time.sleep(0.1)
        self.event(t0, f"GPS port {p['url']} open")

    def read_available(self, t: float) -> bytes:
        """What arrived since the last step, at most ``max_read_bytes``."""
        chunks, left = [], int(self.p["max_read_bytes"])
        while left > 0:
            try:
                data = self.port.read(min(4096, left))
            except Exception as exc:           # noqa: BLE001 - a dropped link is a stale fix, not a crash
                self.event(t, f"GPS read failed: {exc}")
                break
            if not data:
                break
            chunks.append(data)
            left -= len(data)
        return b"".join(chunks)

    def step(self, t: float, dt: float) -> None:
        data = self.read_available(t)
        if self.record is not None and data:        # whole lines, stamped when they arrived
            *lines, self.partial = (self.partial + data).split(b"\n")
            stamp = f"{time.time():.6f} "
            self.record.write("".join(stamp + ln.rstrip(b"\r").decode("ascii", "replace") + "\n" for ln in lines if ln.strip()))
        flooded = len(data) >= int(self.p["max_read_bytes"])
        keep = int(self.p["max_parse_bytes"])
        if len(data) > keep:                        # the newest lines only
            tail = data[-keep:]
            tail = tail[tail.find(b"\n") + 1:]
            self.stream.counters.dropped_bytes += len(data) - len(tail)
            self.stream.resync()
            data = tail
        items = self.stream.feed(data)
        if flooded:
            if not self.flooded:
                self.event(t, f"GPS link flooded: {self.p['max_read_bytes']} bytes or more in one step; the fixes "
                              "of such steps are not used")
            self.flooded += 1
            items = [it for it in items if not isinstance(it, Position)]
        self.apply(t, items)

    def apply(self, t: float, items: list[Position | Velocity | PositionError | Heading]) -> None:
        """Update the outputs from parsed sentences (shared by the serial path and the tests)."""
        y, c = self.y, self.stream.counters
        y["fix_valid"] = y["heading_valid"] = 0.0
        for item in items:
            if not finite(item):                  # the parser judges the fields; this holds if it is bypassed
                c.bad_value += 1
                if isinstance(item, Position):    # the fix downgraded
                    y["fix_quality"] = 0.0
                continue
            if isinstance(item, PositionError):
                y["position_std"] = max(item.std_north, item.std_east)
                continue
            if isinstance(item, Heading):        # from north clockwise -> from east counter-clockwise
                y["heading"] = math.atan2(math.cos(item.heading), math.sin(item.heading))
                y["heading_valid"] = 1.0
                continue
            if isinstance(item, Velocity):
                y["vel_east"] = item.speed * math.sin(item.course)
                y["vel_north"] = item.speed * math.cos(item.course)
                continue
            y["fix_quality"], y["satellites"] = float(item.quality), float(item.satellites)
            if not fix_at_least(item.quality, self.p["min_fix_quality"]):
                c.poor_fix += 1
                continue
            y["x"], y["y"], _ = self.frame.to_local(item.latitude, item.longitude, item.height)
            y["fix_valid"] = 1.0
            self.last_good = t
        y["fix_age"] = t - self.last_good
        y["bad_checksums"], y["malformed_sentences"] = float(c.bad_checksum), float(c.malformed)
        y["unknown_sentences"], y["partial_lines"], y["poor_fixes"] = float(c.unknown), float(c.partial), float(c.poor_fix)
        y["bad_values"], y["dropped_bytes"], y["flooded_steps"] = float(c.bad_value), float(c.dropped_bytes), float(getattr(self, "flooded", 0))

    def terminate(self) -> None:
        if getattr(self, "record", None) is not None:
            self.record.close()
            self.record = None
        if self.port is not None:
            self.port.close()
            self.port = None


COMPONENT = NMEAGPS
