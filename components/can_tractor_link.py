"""The emulated tractor's side of the CAN bus: set-points in, measured wheel angle, yaw rate and
speed out, frames from the same DBC as can_actuators. If no command is accepted for
``command_timeout`` the tractor makes itself safe (speed 0, wheel angle held) and logs it.

Only the expected sender steers: a command frame is accepted only from the configured channel
(and, on udp_multicast, from this host), from the guidance's source address (isobus), with the
next rolling counter and a right checksum (agrobot), and with values inside the DBC's ranges and
the machine's limits (``max_steer_angle``, ``max_speed``); any other is refused and counted, and
the tractor keeps the last accepted command until the timeout stops it. At most ``max_frames`` are
read per step; a step that reads them all is flooded and accepts nothing (the newest command kept
in force only until the timeout).
"""
from __future__ import annotations

import math

from agrobot.orchestrator.component import Component, inp, out, par

from .hardware.can_link import CAN_PARAMETERS, binding, connect, drain, send


class CANTractorLink(Component):
    sampled = True
    roles = ("tractor_link",)
    variables = (
        inp("steer_angle_measured", "rad", 0.0, "wheel angle to report"),
        inp("yaw_rate", "rad/s", 0.0, "yaw rate to report"),
        inp("speed", "m/s", 0.0, "speed to report"),
        *CAN_PARAMETERS,
        par("command_timeout", "s", 0.5, "commands older than this make the tractor safe"),
        par("max_steer_angle", "rad", 0.8, "machine limit: a larger wheel-angle command is refused"),
        par("max_speed", "m/s", 5.0, "machine limit: a faster speed command is refused"),
        par("lockout_after", "s", -1.0, "fault injection: the operator's lockout switch is set at this time "
            "(isobus: reported in Guidance Machine Info; negative = never)"),
        par("not_ready_after", "s", -1.0, "fault injection: the steering system reports not ready from this time"),
        out("steer_angle_cmd", "rad", 0.0, "received wheel-angle set-point"),
        out("speed_cmd", "m/s", 0.0, "received speed set-point"),
        out("guidance_safe_state", "1", 0.0, "the guidance's safe-state flag"),
        out("command_age", "s", 0.0, "time since the last accepted command frame"),
        out("refused_commands", "1", 0.0, "command frames refused (channel, sender, counter, checksum, DBC range, "
            "machine limits) so far"),
        out("flooded_steps", "1", 0.0, "steps that read max_frames frames and accepted none, so far"),
    )
    feedthrough = {}

    def initialize(self, t0: float, dt: float) -> None:
        self.bus = None
        p = self.p
        self.require(p["max_steer_angle"] > 0 and p["max_speed"] > 0,
                     f"max_steer_angle {p['max_steer_angle']}, max_speed {p['max_speed']}: expected positive limits")
        self.messages, self.bus = connect(self, "tractor")
        self.last_command, self.timed_out, self.seen = t0, False, False
        self.held = 0.0
        self.refused = self.flooded = 0
        self.event(t0, binding(p["interface"], p["channel"], p["port"], self.bus))

    def within_limits(self, frame: dict) -> bool:
        p = self.p
        return abs(frame.get("steer_angle_cmd", 0.0)) <= p["max_steer_angle"] and \
            0.0 <= frame.get("speed_cmd", 0.0) <= p["max_speed"]

    def step(self, t: float, dt: float) -> None:
        y, u, p = self.y, self.u, self.p
        got = drain(self.bus, self.messages.read_command, p["channel"], int(p["max_frames"]))
        self.refused += got.foreign
        if got.flooded:
            if not self.flooded:
                self.event(t, f"CAN commands flooded: {got.read} frames or datagrams in one step ({got.foreign} refused: "
                                  f"another channel or host, or no frame); such steps accept no command")
            self.flooded += 1
        for frame in ([] if got.flooded else got.frames):
            if not self.within_limits(frame):
                if not self.refused:
                    self.event(t, f"command refused, outside the machine's limits: {frame}")
                self.refused += 1
                continue
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
        report = (u["steer_angle_measured"], u["yaw_rate"], u["speed"])
        if all(map(math.isfinite, report)):        # a tractor that cannot measure stays silent: its feedback ages
            frames = self.messages.feedback(report[0], report[1], max(0.0, report[2]), ready=ready, lockout=lockout,
                                            dt=dt)
            send(self.bus, frames, self.messages.extended)
        y["refused_commands"] = float(self.refused + self.messages.refused)
        y["flooded_steps"] = float(self.flooded)

    def terminate(self) -> None:
        if getattr(self, "bus", None) is not None:
            self.bus.shutdown()
            self.bus = None


COMPONENT = CANTractorLink
