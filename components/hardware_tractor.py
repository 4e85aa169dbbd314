"""The tractor reached over its hardware interfaces, as one component with the ports that
studies/tractor_side.toml exports (the simulated tractor, a composite subsystem): an ``nmea_gps`` (GPS over NMEA 0183 from a serial port or TCP socket) and a
``can_actuators`` (set-points out, wheel angle, yaw rate and speed back over CAN) inside. A study
swaps simulation for hardware by changing this component's line only. Truth outputs are NaN.
"""
from __future__ import annotations

import math

from agrobot.orchestrator.component import Component, inp, out, par

from .can_actuators import CANActuators
from .hardware.can_link import CAN_PARAMETERS, prefixed
from .hardware.nmea import DATUM_PARAMETERS
from .nmea_gps import NMEAGPS

TRACTOR_PORTS = (
    inp("steer_angle_cmd", "rad", 0.0, "wheel-angle set-point"),
    inp("speed_cmd", "m/s", 0.0, "speed set-point"),
    inp("safe_state", "1", 0.0, "1 while the guidance holds the tractor safe"),
    out("gps_x", "m", 0.0, "GPS antenna east position"),
    out("gps_y", "m", 0.0, "GPS antenna north position"),
    out("gps_vel_east", "m/s", 0.0, "GPS east velocity"),
    out("gps_vel_north", "m/s", 0.0, "GPS north velocity"),
    out("fix_valid", "1", 0.0, "1 when a new good fix arrived"),
    out("fix_age", "s", 0.0, "time since the last good fix"),
    out("fix_quality", "1", 0.0, "GGA fix quality (4 RTK fixed)"),
    out("steer_angle_measured", "rad", 0.0, "measured wheel angle"),
    out("yaw_rate", "rad/s", 0.0, "measured yaw rate"),
    out("speed_measured", "m/s", 0.0, "measured speed"),
    out("x_cg", "m", 0.0, "truth: CG east position (NaN on hardware)"),
    out("y_cg", "m", 0.0, "truth: CG north position (NaN on hardware)"),
    out("heading", "rad", 0.0, "truth: heading (NaN on hardware)"),
    out("machine_ready", "1", 1.0, "the steering system reports ready (ISO 11783-7; the agrobot messages: 1)"),
    out("machine_lockout", "1", 0.0, "the operator's mechanical lockout is active (ISO 11783-7)"),
)

GPS_OUTPUTS = {"gps_x": "x", "gps_y": "y", "gps_vel_east": "vel_east", "gps_vel_north": "vel_north",
               "fix_valid": "fix_valid", "fix_age": "fix_age", "fix_quality": "fix_quality"}
CAN_OUTPUTS = {"steer_angle_measured": "steer_angle_measured", "yaw_rate": "yaw_rate", "speed_measured": "speed_measured",
               "machine_ready": "machine_ready", "machine_lockout": "machine_lockout"}


class HardwareTractor(Component):
    sampled = True
    roles = ("tractor",)
    variables = TRACTOR_PORTS + (
        par("nmea_url", "", "socket://127.0.0.1:10110", "pyserial URL or device of the GPS receiver"),
        par("nmea_baudrate", "1/s", 115200, "serial line speed"),
        *DATUM_PARAMETERS,
        par("min_fix_quality", "1", 4, "GGA quality of a valid fix"),
        par("connect_timeout", "s", 5.0, "how long to retry opening the GPS port"),
        par("nmea_record_file", "", "", "record the receiver's lines, host-stamped (empty: no recording)"),
        *prefixed(CAN_PARAMETERS, "can_"),
    )
    feedthrough = {}

    def initialize(self, t0: float, dt: float) -> None:
        p = self.p
        self.gps = NMEAGPS(f"{self.name}.gps", {
            "url": p["nmea_url"], "baudrate": p["nmea_baudrate"],
            **{v.name: p[v.name] for v in DATUM_PARAMETERS},
            "min_fix_quality": p["min_fix_quality"], "connect_timeout": p["connect_timeout"],
            "record_file": p["nmea_record_file"]})
        self.can = CANActuators(f"{self.name}.can", {v.name: p["can_" + v.name] for v in CAN_PARAMETERS})
        self.can.initialize(t0, dt)
        try:
            self.gps.initialize(t0, dt)
        except Exception:
            self.can.terminate()
            raise
        self.gps.events[:0] = self.can.events
        self.events = self.gps.events        # one log for both adapters
        self.can.events = self.events
        for k in ("x_cg", "y_cg", "heading"):
            self.y[k] = math.nan

    def step(self, t: float, dt: float) -> None:
        """Read: CAN feedback and NMEA fixes that arrived since the last instant."""
        self.can.step(t, dt)
        self.gps.step(t, dt)
        for port, name in GPS_OUTPUTS.items():
            self.y[port] = self.gps.y[name]
        for port, name in CAN_OUTPUTS.items():
            self.y[port] = self.can.y[name]

    def actuate(self, t: float) -> None:
        """Write: the set-points computed at this instant, over CAN."""
        for k in ("steer_angle_cmd", "speed_cmd", "safe_state"):
            self.can.u[k] = self.u[k]
        self.can.actuate(t)

    def terminate(self) -> None:
        for part in (getattr(self, "gps", None), getattr(self, "can", None)):
            if part is not None:
                part.terminate()


COMPONENT = HardwareTractor
