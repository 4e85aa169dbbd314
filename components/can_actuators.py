"""Actuators over CAN (hardware adapter): wheel-angle and speed set-points out, the measured wheel
angle, yaw rate and speed back, frames laid out by a DBC file (default: the project's
components/hardware/agrobot_tractor.dbc; ``protocol = "isobus"``: ISO 11783-7 guidance, see
components/hardware/guidance_messages.py) and sent with python-can on the study's interface and
channel ('virtual' in one process, 'udp_multicast' between processes, 'socketcan' on a tractor).

Feedback is judged before use: a frame from another channel or sender, with a wrong counter or
checksum, or a value outside its DBC range is refused and counted (``refused_frames``); at most
``max_frames`` are read per step, the newest value of each signal kept, and a step that reads its
whole allowance is flooded: its frames are not taken as fresh (``feedback_age`` grows). A set-point
that is not finite is never sent: the frame goes out in the safe state (speed 0, the wheel angle
held at the last finite one measured) and is counted.
"""
from __future__ import annotations

import math

from agrobot.orchestrator.component import Component, inp, out

from .hardware.can_link import CAN_PARAMETERS, binding, connect, drain, send


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
        out("refused_frames", "1", 0.0, "feedback frames refused (channel, sender, counter, checksum, range) so far"),
        out("flooded_steps", "1", 0.0, "steps that read max_frames frames, their frames not taken as fresh, so far"),
        out("unsafe_commands", "1", 0.0, "non-finite set-points replaced by the safe state so far"),
        out("machine_ready", "1", 1.0, "isobus: 1 while the steering system reports ready (agrobot: always 1)"),
        out("machine_lockout", "1", 0.0, "isobus: 1 while the operator's mechanical lockout is active"),
    )
    feedthrough = {}

    def initialize(self, t0: float, dt: float) -> None:
        self.bus = None
        self.messages, self.bus = connect(self, "guidance")
        self.last_feedback, self.received = t0, 0
        self.foreign = self.flooded = self.unsafe = self.send_failures = 0
        p = self.p
        self.event(t0, binding(p["interface"], p["channel"], p["port"], self.bus))

    def step(self, t: float, dt: float) -> None:
        """Read the feedback frames that arrived (at most max_frames)."""
        y, m = self.y, self.messages
        names = {"steer_angle": "steer_angle_measured", "yaw_rate": "yaw_rate", "speed": "speed_measured",
                 "ready": "machine_ready", "lockout": "machine_lockout"}
        got = drain(self.bus, m.read_feedback, self.p["channel"], int(self.p["max_frames"]))
        self.foreign += got.foreign
        if got.flooded:
            if not self.flooded:
                self.event(t, f"CAN feedback flooded: {got.read} frames or datagrams in one step ({got.foreign} refused: "
                                  f"another channel or host, or no frame); such steps' frames are not used")
            self.flooded += 1
        else:
            for frame in got.frames:
                for key, value in frame.items():
                    y[names[key]] = value
                self.last_feedback, self.received = t, self.received + 1
        y["feedback_age"] = t - self.last_feedback
        y["frames_received"], y["bad_frames"] = float(self.received), float(m.bad)
        y["refused_frames"] = float(m.refused + self.foreign)
        y["flooded_steps"], y["unsafe_commands"] = float(self.flooded), float(self.unsafe)

    def actuate(self, t: float) -> None:
        """Send the set-points of this instant (after the controllers have stepped)."""
        u = self.u
        steer, speed, engaged = u["steer_angle_cmd"], u["speed_cmd"], u["safe_state"] <= 0.5
        if not (math.isfinite(steer) and math.isfinite(speed)):
            if not self.unsafe:
                self.event(t, f"non-finite set-point (wheel angle {steer}, speed {speed}): sent as the safe state, "
                              "speed 0 and the wheel angle held")
            self.unsafe += 1
            held = self.y["steer_angle_measured"]
            steer, speed, engaged = held if math.isfinite(held) else 0.0, 0.0, False
        failed = send(self.bus, self.messages.command(steer, speed, engaged=engaged), self.messages.extended)
        if failed and not self.send_failures:
            self.event(t, f"CAN send refused by the interface ({failed} frames); counted, never waited for")
        self.send_failures += failed

    def terminate(self) -> None:
        if getattr(self, "bus", None) is not None:
            self.bus.shutdown()
            self.bus = None


COMPONENT = CANActuators
