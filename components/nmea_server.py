"""NMEA 0183 out over TCP (the emulated tractor's GPS receiver): at each step with a fix, a GGA and
a VTG for the antenna position (east/north about the datum -> latitude/longitude) go to every
client connected to ``host:port``. Fault injection for tests: ``stop_after`` (s, the stream
stops) and ``float_after`` (s, the fix quality drops to 5, RTK float); negative = never.
"""
from __future__ import annotations

import socket

from orchestrator.component import Component, inp, out, par

from .hardware.nmea import DATUM_PARAMETERS, RTK_FIXED, LocalFrame, gga_vtg


class NMEAServer(Component):
    sampled = True
    roles = ("nmea_server",)
    variables = (
        inp("x", "m", 0.0, "antenna east position"),
        inp("y", "m", 0.0, "antenna north position"),
        inp("vel_east", "m/s", 0.0, "antenna east velocity"),
        inp("vel_north", "m/s", 0.0, "antenna north velocity"),
        inp("fix_valid", "1", 1.0, "1 when a fix is available"),
        par("host", "", "127.0.0.1", "address to listen on"),
        par("port", "1", 10110, "TCP port to listen on"),
        *DATUM_PARAMETERS,
        par("talker", "", "GN", "NMEA talker id"),
        par("stop_after", "s", -1.0, "fault injection: stop sending after this time"),
        par("float_after", "s", -1.0, "fault injection: report RTK float after this time"),
        out("clients", "1", 0.0, "connected clients"),
        out("sentences_sent", "1", 0.0, "sentences sent so far"),
    )
    feedthrough = {}

    def initialize(self, t0: float, dt: float) -> None:
        p = self.p
        self.frame = LocalFrame.of(p)
        self.server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            self.server.bind((p["host"], int(p["port"])))
        except OSError as exc:
            self.server.close()
            self.require(False, f"cannot listen on {p['host']}:{p['port']}: {exc}")
        self.server.listen(4)
        self.server.setblocking(False)
        self.clients: list[socket.socket] = []
        self.sent, self.stopped, self.floating = 0, False, False

    def step(self, t: float, dt: float) -> None:
        p, u = self.p, self.u
        while True:
            try:
                conn, addr = self.server.accept()
            except (BlockingIOError, OSError):
                break
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self.clients.append(conn)
            self.event(t, f"NMEA client {addr[0]}:{addr[1]} connected")
        if 0 <= p["stop_after"] <= t and not self.stopped:
            self.stopped = True
            self.event(t, "fault injection: NMEA stream stopped")
        if 0 <= p["float_after"] <= t and not self.floating:
            self.floating = True
            self.event(t, "fault injection: fix quality drops to RTK float")
        if u["fix_valid"] > 0.5 and not self.stopped and self.clients:
            lat, lon, h = self.frame.to_geodetic(u["x"], u["y"])
            data = gga_vtg(t, lat, lon, h, u["vel_east"], u["vel_north"], 5 if self.floating else RTK_FIXED,
                           talker=p["talker"])
            for conn in list(self.clients):
                try:
                    conn.sendall(data)
                except OSError:
                    self.clients.remove(conn)
                    conn.close()
                    self.event(t, "NMEA client gone")
            self.sent += 2
        self.y["clients"], self.y["sentences_sent"] = float(len(self.clients)), float(self.sent)

    def terminate(self) -> None:
        for conn in getattr(self, "clients", []):
            conn.close()
        if getattr(self, "server", None) is not None:
            self.server.close()
            self.server = None


COMPONENT = NMEAServer
