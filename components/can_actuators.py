"""Actuators over CAN (hardware adapter): wheel-angle and speed set-points out, the measured wheel
angle, yaw rate and speed back, frames laid out by a DBC file (default: the project's
components/hardware/agrobot_tractor.dbc; ``protocol = "isobus"``: ISO 11783-7 guidance, see
components/hardware/guidance_messages.py) and sent with python-can on the study's interface and
channel ('virtual' in one process, 'udp_multicast' between processes, 'socketcan' on a tractor).
"""
from __future__ import annotations

from agrobot.orchestrator.component import Component, inp, out

from .hardware.can_link import CAN_PARAMETERS, connect, drain, send


class CANActuators(Component):
    sampled = True
    roles = ("actuator_link",)
    variables = (
        inp("steer_angle_cmd", "rad", 0.0, "wheel-angle set-point"),
        inp("speed_cmd", "m/s", 0.0, "speed set-point"),
        inp("safe_state", "1", 0.0, "1 while the guidance holds the tractor safe"),
        *CAN_PARAMETERS,
        out("steer_angle_measured", "rad", 0.0, "wheel angle from the tractor"),
        out("yaw_rate", "rad/s", 0.0, "yaw rate from the tractor"),
        out("speed_measured", "m/s", 0.0, "speed from the tractor"),
        out("feedback_age", "s", 0.0, "time since the last feedback frame"),
        out("frames_received", "1", 0.0, "feedback frames decoded so far"),
        out("bad_frames", "1", 0.0, "feedback frames that did not decode"),
        out("machine_ready", "1", 1.0, "isobus: 1 while the steering system reports ready (agrobot: always 1)"),
        out("machine_lockout", "1", 0.0, "isobus: 1 while the operator's mechanical lockout is active"),
    )
    feedthrough = {}

    def initialize(self, t0: float, dt: float) -> None:
        self.bus = None
        self.messages, self.bus = connect(self, "guidance")
        self.last_feedback, self.received = t0, 0

    def step(self, t: float, dt: float) -> None:
        """Read every feedback frame that arrived."""
        y, m = self.y, self.messages
        names = {"steer_angle": "steer_angle_measured", "yaw_rate": "yaw_rate", "speed": "speed_measured",
                 "ready": "machine_ready", "lockout": "machine_lockout"}
        for frame in drain(self.bus, m.read_feedback):
            for key, value in frame.items():
                y[names[key]] = value
            self.last_feedback, self.received = t, self.received + 1
        y["feedback_age"] = t - self.last_feedback
        y["frames_received"], y["bad_frames"] = float(self.received), float(m.bad)

    def actuate(self, t: float) -> None:
        """Send the set-points of this instant (after the controllers have stepped)."""
        send(self.bus, self.messages.command(self.u["steer_angle_cmd"], self.u["speed_cmd"],
                                             engaged=self.u["safe_state"] <= 0.5), self.messages.extended)

    def terminate(self) -> None:
        if getattr(self, "bus", None) is not None:
            self.bus.shutdown()
            self.bus = None


COMPONENT = CANActuators
