"""What a data logger on a simulated tractor would record, without real time (``run --record``):
the receiver's NMEA (``gps.nmea``: each sentence after a host timestamp) and the CAN bus
(``can.log``: candump, or .asc/.blf by the name's suffix) carrying the guidance's set-points and
the tractor's feedback in the study's message set (the project's frames, or ISO 11783-7).

Clocks, so that an import can be tested against known truth: the receiver's UTC is ``epoch + t``;
the host clock reads epoch + t (1 + drift) + offset; an NMEA sentence is stamped
``nmea_latency`` (plus up to ``nmea_latency_jitter``) after its epoch, a CAN frame when it is sent. With ``reference_log`` set, the
same signals are also written as the measured log (t, delta_cmd, delta, v, yaw_rate, x, y): the
simulation's own log, to compare an imported recording against. A frame whose values are not
finite is not recorded (the adapters never send one).

Imported where used: can (the hardware extra, python-can).
"""
from __future__ import annotations

import datetime
import math
from pathlib import Path

from agrobot.orchestrator.component import Component, inp, par

from .hardware.guidance_messages import PROTOCOLS, messages_for
from .hardware.nmea import DATUM_PARAMETERS, RECEIVER_INPUTS, RECEIVER_PARAMETERS, RTK_FIXED, LocalFrame, \
    receiver_sentences, receiver_settings


class BusRecorder(Component):
    sampled = True
    roles = ("bus_recorder",)
    OFF_THE_LATERAL_LOOP = True   # moves nothing of the lateral channel at first order (margins)
    variables = (
        *RECEIVER_INPUTS,
        inp("steer_angle_cmd", "rad", 0.0, "wheel-angle set-point sent to the tractor", optional=True),
        inp("speed_cmd", "m/s", 0.0, "speed set-point sent to the tractor (a study that sends none: 0)", optional=True),
        inp("safe_state", "1", 0.0, "1 while the guidance holds the tractor safe (a study without a watchdog: 0)",
            optional=True),
        inp("steer_angle_measured", "rad", 0.0, "wheel angle the tractor reports"),
        inp("yaw_rate", "rad/s", 0.0, "yaw rate the tractor reports"),
        inp("speed", "m/s", 0.0, "speed the tractor reports"),
        inp("machine_ready", "1", 1.0, "steering system ready", optional=True),
        inp("machine_lockout", "1", 0.0, "operator lockout active", optional=True),
        par("nmea_record_file", "", "", "the NMEA recording (host-stamped sentences)"),
        par("can_record_file", "", "", "the CAN recording (.log candump, .asc, .blf by its suffix)"),
        par("reference_record_file", "", "", "also write the simulation's own measured log here (CSV; empty: no)"),
        par("protocol", "", "agrobot", f"CAN message set: {' or '.join(PROTOCOLS)}"),
        par("dbc", "", "", "DBC (empty: the protocol's own)"),
        par("wheelbase", "m", 1.4, "isobus: curvature = tan(wheel angle) / wheelbase"),
        *DATUM_PARAMETERS,
        *RECEIVER_PARAMETERS,
        par("host_clock_offset", "s", 0.0, "host clock minus UTC at t = 0"),
        par("host_clock_drift", "1", 0.0, "host clock rate error (1e-6 = 1 ppm)"),
        par("nmea_latency", "s", 0.0, "a sentence reaches the host this long after its epoch"),
        par("nmea_latency_jitter", "s", 0.0, "plus a uniform random 0 to this (the component's random stream)"),
    )
    feedthrough = {}

    def initialize(self, t0: float, dt: float) -> None:
        import can

        p = self.p
        self.require(bool(p["nmea_record_file"]) and bool(p["can_record_file"]),
                     "nmea_record_file, can_record_file: expected the files to record into")
        self.sentences, self.epoch = receiver_settings(self)
        self.require(p["nmea_latency"] >= 0, f"nmea_latency {p['nmea_latency']}: expected >= 0 s")
        try:
            self.guidance = messages_for(p["protocol"], p["dbc"], "guidance", p["wheelbase"])
            self.tractor = messages_for(p["protocol"], p["dbc"], "tractor", p["wheelbase"])
        except (OSError, KeyError, ValueError) as exc:
            self.require(False, f"CAN messages (protocol {p['protocol']!r}): {exc}")
        self.nmea = self.can = self.reference = None
        try:
            self.nmea = open(p["nmea_record_file"], "w", buffering=1 << 16, encoding="ascii")
            self.can = can.Logger(str(p["can_record_file"]))
            if p["reference_record_file"]:
                self.reference = open(p["reference_record_file"], "w", encoding="ascii")
                self.reference.write("t,delta_cmd,delta,v,yaw_rate,x,y\n")
        except (OSError, ValueError) as exc:
            self.terminate()
            self.require(False, f"cannot record into {Path(p['nmea_record_file']).parent}: {exc}")
        self.frame = LocalFrame.of(p)
        self.epoch_posix = self.epoch.timestamp()

    def host_time(self, t: float) -> float:
        p = self.p
        return self.epoch_posix + t * (1.0 + p["host_clock_drift"]) + p["host_clock_offset"]

    def step(self, t: float, dt: float) -> None:
        import can

        u, p = self.u, self.p
        when = self.epoch + datetime.timedelta(seconds=t)
        if u["fix_valid"] > 0.5:
            lat, lon, h = self.frame.to_geodetic(u["x"], u["y"])
            quality = RTK_FIXED
        else:
            lat = lon = None
            h, quality = 0.0, 0
        data = receiver_sentences(when, lat, lon, h, u["vel_east"], u["vel_north"], quality, talker=p["talker"],
                                  sentences=self.sentences, position_std=p["position_std"])
        late = p["nmea_latency"] + (p["nmea_latency_jitter"] * self.rng.random() if p["nmea_latency_jitter"] > 0 else 0.0)
        stamp = f"{self.host_time(t) + late:.6f} "
        self.nmea.write("".join(stamp + line + "\n" for line in data.decode("ascii").split("\r\n") if line))
        host = self.host_time(t)
        frames = []
        if math.isfinite(u["steer_angle_cmd"]) and math.isfinite(u["speed_cmd"]):   # what the adapters would send
            frames += self.guidance.command(u["steer_angle_cmd"], u["speed_cmd"], u["safe_state"] <= 0.5)
        if all(math.isfinite(u[k]) for k in ("steer_angle_measured", "yaw_rate", "speed")):
            frames += self.tractor.feedback(u["steer_angle_measured"], u["yaw_rate"], u["speed"],
                                            ready=u["machine_ready"] > 0.5, lockout=u["machine_lockout"] > 0.5, dt=dt)
        for i, (fid, payload) in enumerate(frames):
            self.can(can.Message(timestamp=host + 1e-4 * i, arbitration_id=fid, data=payload,
                                 is_extended_id=self.guidance.extended, channel="can0"))
        if self.reference is not None:
            self.reference.write(f"{t:.6f},{u['steer_angle_cmd']:.9g},{u['steer_angle_measured']:.9g},{u['speed']:.9g},"
                                 f"{u['yaw_rate']:.9g},{u['x']:.9g},{u['y']:.9g}\n")

    def terminate(self) -> None:
        for name in ("nmea", "reference"):
            f = getattr(self, name, None)
            if f is not None:
                f.close()
                setattr(self, name, None)
        if getattr(self, "can", None) is not None:
            self.can.stop()
            self.can = None


COMPONENT = BusRecorder
