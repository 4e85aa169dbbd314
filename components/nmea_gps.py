"""GPS receiver over NMEA 0183 (hardware adapter): the outputs of gps_sensor plus fix quality.

Reads whatever bytes arrived since the last step from a pyserial URL (``/dev/ttyUSB0``,
``socket://127.0.0.1:10110``, ``rfc2217://...``), parses GGA (position, fix quality) and VTG or RMC
(speed, course over ground), GST (position error statistics) and HDT (true heading of a dual
antenna) with pynmeagps, any talker (GN, GP, GL, ...), and converts latitude/longitude/height to
east/north about the study's datum; other sentences (ZDA, GSA, GSV ...) are counted as unused. Bad checksums, partial lines, unknown sentences and fixes worse than
``min_fix_quality`` (4 = RTK fixed; 5, RTK float, is worse) are counted in outputs and flagged
(``fix_valid`` = 0); none is fatal. ``fix_age`` is the time since the last good fix arrived.
"""
from __future__ import annotations

import math
import time

from agrobot.orchestrator.component import Component, out, par

from .hardware.nmea import (DATUM_PARAMETERS, RTK_FIXED, Heading, LocalFrame, NMEAStream, Position,
                           PositionError, Velocity, fix_at_least)


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
        chunks = []
        while True:
            try:
                data = self.port.read(4096)
            except Exception as exc:           # noqa: BLE001 - a dropped link is a stale fix, not a crash
                self.event(t, f"GPS read failed: {exc}")
                break
            if not data:
                break
            chunks.append(data)
        return b"".join(chunks)

    def step(self, t: float, dt: float) -> None:
        data = self.read_available(t)
        if self.record is not None and data:        # whole lines, stamped when they arrived
            *lines, self.partial = (self.partial + data).split(b"\n")
            stamp = f"{time.time():.6f} "
            self.record.write("".join(stamp + ln.rstrip(b"\r").decode("ascii", "replace") + "\n" for ln in lines if ln.strip()))
        self.apply(t, self.stream.feed(data))

    def apply(self, t: float, items: list[Position | Velocity | PositionError | Heading]) -> None:
        """Update the outputs from parsed sentences (shared by the serial path and the tests)."""
        y, c = self.y, self.stream.counters
        y["fix_valid"] = y["heading_valid"] = 0.0
        for item in items:
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

    def terminate(self) -> None:
        if getattr(self, "record", None) is not None:
            self.record.close()
            self.record = None
        if self.port is not None:
            self.port.close()
            self.port = None


COMPONENT = NMEAGPS
