"""The emulated tractor's side of the CAN bus: set-points in, measured wheel angle, yaw rate and
speed out, frames from the same DBC as can_actuators. If no command arrives for
``command_timeout`` the tractor makes itself safe (speed 0, wheel angle held) and logs it.
"""
from __future__ import annotations

from agrobot.orchestrator.component import Component, inp, out, par

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
        par("lockout_after", "s", -1.0, "fault injection: the operator's lockout switch is set at this time "
            "(isobus: reported in Guidance Machine Info; negative = never)"),
        par("not_ready_after", "s", -1.0, "fault injection: the steering system reports not ready from this time"),
        out("steer_angle_cmd", "rad", 0.0, "received wheel-angle set-point"),
        out("speed_cmd", "m/s", 0.0, "received speed set-point"),
        out("guidance_safe_state", "1", 0.0, "the guidance's safe-state flag"),
        out("command_age", "s", 0.0, "time since the last command frame"),
    )
    feedthrough = {}

    def initialize(self, t0: float, dt: float) -> None:
        self.bus = None
        self.messages, self.bus = connect(self, "tractor")
        self.last_command, self.timed_out, self.seen = t0, False, False
        self.held = 0.0

    def step(self, t: float, dt: float) -> None:
        y, u, p = self.y, self.u, self.p
        for frame in drain(self.bus, self.messages.read_command):
            if "steer_angle_cmd" in frame:
                y["steer_angle_cmd"] = frame["steer_angle_cmd"]
            if "speed_cmd" in frame:
                y["speed_cmd"] = frame["speed_cmd"]
            if "engaged" in frame:
                y["guidance_safe_state"] = float(not frame["engaged"])
                self.last_command, self.seen = t, True
        y["command_age"] = t - self.last_command
        stale = self.seen and y["command_age"] > p["command_timeout"]
        if stale and not self.timed_out:
            self.held = u["steer_angle_measured"]
            self.event(t, f"no command for {y['command_age']:.2f} s: speed to 0, wheel angle held")
        elif self.timed_out and not stale:
            self.event(t, "commands back")
        self.timed_out = stale
        if stale:
            y["speed_cmd"], y["steer_angle_cmd"] = 0.0, self.held
        lockout = 0 <= p["lockout_after"] <= t
        ready = not (0 <= p["not_ready_after"] <= t)
        frames = self.messages.feedback(u["steer_angle_measured"], u["yaw_rate"], max(0.0, u["speed"]),
                                        ready=ready, lockout=lockout, dt=dt)
        send(self.bus, frames, self.messages.extended)

    def terminate(self) -> None:
        if getattr(self, "bus", None) is not None:
            self.bus.shutdown()
            self.bus = None


COMPONENT = CANTractorLink
