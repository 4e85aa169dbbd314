"""The emulated tractor's side of the CAN bus: set-points in, measured wheel angle, yaw rate and
speed out, frames from the same DBC as can_actuators. If no command arrives for
``command_timeout`` the tractor makes itself safe (speed 0, wheel angle held) and logs it.
"""
from __future__ import annotations

from orchestrator.component import Component, inp, out, par

from .hardware.can_link import CAN_PARAMETERS, connect, drain, send


class CANTractorLink(Component):
    sampled = True
    roles = ("tractor_link",)
    variables = (
        inp("steer_angle_measured", "rad", 0.0, "wheel angle to report"),
        inp("yaw_rate", "rad/s", 0.0, "yaw rate to report"),
        inp("speed", "m/s", 0.0, "speed to report"),
        *CAN_PARAMETERS,
        par("command_timeout", "s", 0.5, "commands older than this make the tractor safe"),
        out("steer_angle_cmd", "rad", 0.0, "received wheel-angle set-point"),
        out("speed_cmd", "m/s", 0.0, "received speed set-point"),
        out("guidance_safe_state", "1", 0.0, "the guidance's safe-state flag"),
        out("command_age", "s", 0.0, "time since the last command frame"),
    )
    feedthrough = {}

    def initialize(self, t0: float, dt: float) -> None:
        self.bus = None
        self.codec, self.bus = connect(self, "TractorFeedback", "GuidanceCommand")
        self.last_command, self.timed_out, self.seen = t0, False, False
        self.held = 0.0

    def step(self, t: float, dt: float) -> None:
        y, u = self.y, self.u
        for frame in drain(self.bus, self.codec):
            y["steer_angle_cmd"], y["speed_cmd"] = frame["SteerAngleCmd"], frame["SpeedCmd"]
            y["guidance_safe_state"] = float(frame["SafeState"])
            self.last_command, self.seen = t, True
        y["command_age"] = t - self.last_command
        stale = self.seen and y["command_age"] > self.p["command_timeout"]
        if stale and not self.timed_out:
            self.held = u["steer_angle_measured"]
            self.event(t, f"no command for {y['command_age']:.2f} s: speed to 0, wheel angle held")
        elif self.timed_out and not stale:
            self.event(t, "commands back")
        self.timed_out = stale
        if stale:
            y["speed_cmd"], y["steer_angle_cmd"] = 0.0, self.held
        send(self.bus, self.codec, SteerAngle=u["steer_angle_measured"], YawRate=u["yaw_rate"], Speed=max(0.0, u["speed"]))

    def terminate(self) -> None:
        if getattr(self, "bus", None) is not None:
            self.bus.shutdown()
            self.bus = None


COMPONENT = CANTractorLink
