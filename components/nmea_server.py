"""NMEA 0183 out, as a receiver sends it (the emulated tractor's GPS): at each step the sentences
of ``sentences`` (default GGA, GST, PGRME, VTG, RMC, ZDA) for the antenna position (east/north about the
datum -> latitude/longitude), UTC time and date counted from ``epoch``, GST and PGRME errors from
``position_std`` (the GPS error model's), HDOP and mode consistent with the fix quality; without a
fix, the same sentences with empty fields (quality 0, RMC status V). They go to every client
connected to ``host:port`` (TCP) and, with ``serial_port`` set, to that serial device (pyserial).
With ``record_file`` every sentence also goes to that file, after the host's UNIX time
(``1777622400.050123 $GNGGA,...``), written as sent. Fault injection for tests: ``stop_after`` (s, the stream stops) and ``float_after`` (s, the fix
quality drops to 5, RTK float); negative = never.

The server listens on ``host`` (loopback by default; the address it bound is logged), and a write
never waits: each client has at most ``client_buffer`` bytes queued (the socket's own send buffer
included), and a client that lets more pile up (it does not read) is dropped with a message.

Imported where used: serial (the hardware extra, pyserial).
"""
from __future__ import annotations

import datetime
import socket
import time

from agrobot.orchestrator.component import Component, out, par

from .hardware.nmea import (DATUM_PARAMETERS, RECEIVER_INPUTS, RECEIVER_PARAMETERS, RTK_FIXED, LocalFrame,
                            receiver_sentences, receiver_settings)


class NMEAServer(Component):
    sampled = True
    roles = ("nmea_server",)
    variables = (
        *RECEIVER_INPUTS,
        par("host", "", "127.0.0.1", "address to listen on"),
        par("port", "1", 10110, "TCP port to listen on"),
        par("client_buffer", "B", 1 << 20, "bytes a client may leave unread before it is dropped (1 MiB: about "
            "100 s of 20 Hz NMEA, so a guidance slow to start is not dropped)"),
        *DATUM_PARAMETERS,
        *RECEIVER_PARAMETERS,
        par("serial_port", "", "", "serial device to send on besides TCP (empty: TCP only)"),
        par("baudrate", "1/s", 115200, "serial line speed"),
        par("record_file", "", "", "record what is sent: one sentence per line after the host's UNIX time "
            "(empty: no recording)"),
        par("stop_after", "s", -1.0, "fault injection: stop sending after this time"),
        par("float_after", "s", -1.0, "fault injection: report RTK float after this time"),
        out("clients", "1", 0.0, "connected clients"),
        out("sentences_sent", "1", 0.0, "sentences sent so far"),
    )
    feedthrough = {}

    def initialize(self, t0: float, dt: float) -> None:
        p = self.p
        self.sentence_set, self.epoch = receiver_settings(self)
        self.frame = LocalFrame.of(p)
        self.record = None
        if p["record_file"]:
            try:
                self.record = open(p["record_file"], "a", buffering=1, encoding="ascii")
            except OSError as exc:
                self.require(False, f"cannot record NMEA to {p['record_file']!r}: {exc}")
        self.serial = None
        if p["serial_port"]:
            import serial

            try:
                self.serial = serial.serial_for_url(p["serial_port"], baudrate=int(p["baudrate"]), timeout=0,
                                                    write_timeout=0)
            except (serial.SerialException, OSError, ValueError) as exc:
                self.require(False, f"cannot open serial port {p['serial_port']!r}: {exc}")
        self.server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            self.server.bind((p["host"], int(p["port"])))
        except OSError as exc:
            self.server.close()
            self.require(False, f"cannot listen on {p['host']}:{p['port']}: {exc}")
        self.server.listen(4)
        self.server.setblocking(False)
        host, port = self.server.getsockname()[:2]
        reach = "this host only" if host.startswith("127.") else "every host that can reach this address"
        self.event(t0, f"NMEA server listening on {host}:{port} ({reach})")
        self.clients: list[socket.socket] = []
        self.pending: dict[socket.socket, bytes] = {}
        self.sent, self.stopped, self.floating = 0, False, False

    def step(self, t: float, dt: float) -> None:
        p, u = self.p, self.u
        while True:
            try:
                conn, addr = self.server.accept()
            except (BlockingIOError, OSError):
                break
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            conn.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, int(p["client_buffer"]) // 2)
            conn.setblocking(False)
            self.clients.append(conn)
            self.pending[conn] = b""
            self.event(t, f"NMEA client {addr[0]}:{addr[1]} connected")
        if 0 <= p["stop_after"] <= t and not self.stopped:
            self.stopped = True
            self.event(t, "fault injection: NMEA stream stopped")
        if 0 <= p["float_after"] <= t and not self.floating:
            self.floating = True
            self.event(t, "fault injection: fix quality drops to RTK float")
        if not self.stopped and (self.clients or self.serial is not None or self.record is not None):
            when = self.epoch + datetime.timedelta(seconds=t)
            if u["fix_valid"] > 0.5:
                lat, lon, h = self.frame.to_geodetic(u["x"], u["y"])
                quality = 5 if self.floating else RTK_FIXED
            else:
                lat = lon = None
                h, quality = 0.0, 0
            data = receiver_sentences(when, lat, lon, h, u["vel_east"], u["vel_north"], quality, talker=p["talker"],
                                      sentences=self.sentence_set, position_std=p["position_std"])
            if self.record is not None:
                stamp = f"{time.time():.6f} "
                self.record.write("".join(stamp + line + "\n" for line in data.decode("ascii").split("\r\n") if line))
            if self.serial is not None:
                try:
                    self.serial.write(data)
                except Exception as exc:         # noqa: BLE001 - a full or gone line loses this epoch only
                    self.event(t, f"NMEA serial write failed: {exc}")
            for conn in list(self.clients):
                self.write(t, conn, data)
            self.sent += len(self.sentence_set)
        self.y["clients"], self.y["sentences_sent"] = float(len(self.clients)), float(self.sent)

    def write(self, t: float, conn: socket.socket, data: bytes) -> None:
        """Send what the client can take now; keep the rest; drop a client that falls behind."""
        queued = self.pending[conn] + data
        try:
            sent = conn.send(queued)
        except BlockingIOError:
            sent = 0
        except OSError:
            self.drop(t, conn, "NMEA client gone")
            return
        self.pending[conn] = queued[sent:]
        if len(self.pending[conn]) > int(self.p["client_buffer"]) // 2:
            self.drop(t, conn, f"NMEA client dropped: it left more than {self.p['client_buffer']} bytes unread "
                               "(it does not read)")

    def drop(self, t: float, conn: socket.socket, why: str) -> None:
        self.clients.remove(conn)
        self.pending.pop(conn, None)
        try:
            where = "{}:{}".format(*conn.getpeername()[:2])
        except OSError:
            where = "?"
        conn.close()
        self.event(t, f"{why} ({where})")

    def terminate(self) -> None:
        if getattr(self, "record", None) is not None:
            self.record.close()
            self.record = None
        if getattr(self, "serial", None) is not None:
            self.serial.close()
            self.serial = None
        for conn in getattr(self, "clients", []):
            conn.close()
        if getattr(self, "server", None) is not None:
            self.server.close()
            self.server = None


COMPONENT = NMEAServer
