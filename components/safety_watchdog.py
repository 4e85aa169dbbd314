"""Watchdog between the guidance and the actuators: a GPS fix older than ``max_fix_age`` or
worse than ``min_fix_quality`` (4 = RTK fixed; 5 = RTK float is worse; 0 = no fix) brings the
commands to a safe state: speed 0 and the wheel angle held where it was measured when the
watchdog tripped. So does a steering system that reports itself not ready, or the operator's
mechanical lockout (ISO 11783-7 Guidance Machine Info, read by can_actuators with
``protocol = "isobus"``): guidance disengages. So does a pose estimate whose own cross-track
standard deviation passes ``max_position_std`` (an estimator that rides through a GNSS outage on
dead reckoning: the user's bound on how far it may trust it). It stays tripped until every
condition has been good for ``recovery_time``. So does any input that is not finite (a NaN or
inf command, fix age, quality or estimate uncertainty: something upstream is broken, whatever the
stream's timing says); the wheel angle held is then the last finite one measured. Every trip and
recovery is logged with its reason.
"""
from __future__ import annotations

import math

from agrobot.orchestrator.component import Component, inp, out, par

from .hardware.nmea import fix_at_least
from .models.loop_blocks import Block, passthrough

REASONS = {0: "ok", 1: "stale GPS fix", 2: "GPS fix below the required quality",
           3: "steering system not ready", 4: "operator lockout of automatic steering",
           5: "position estimate too uncertain", 6: "non-finite command or estimate"}
CHECKED = ("steer_angle_cmd", "speed_cmd", "fix_age", "fix_quality", "machine_ready", "machine_lockout", "position_std")


class SafetyWatchdog(Component):
    sampled = True
    roles = ("watchdog",)
    variables = (
        inp("steer_angle_cmd", "rad", 0.0, "wheel-angle command from the controller"),
        inp("speed_cmd", "m/s", 0.0, "speed command from the controller"),
        inp("steer_angle_measured", "rad", 0.0, "measured wheel angle (held in the safe state)"),
        inp("fix_age", "s", 0.0, "time since the last good GPS fix"),
        inp("fix_quality", "1", 4.0, "GGA fix quality"),
        inp("machine_ready", "1", 1.0, "1 while the steering system reports ready (ISO 11783-7 readiness)", optional=True),
        inp("machine_lockout", "1", 0.0, "1 while the operator's mechanical lockout is active", optional=True),
        inp("position_std", "m", 0.0, "the pose estimate's cross-track standard deviation", optional=True),
        par("max_fix_age", "s", 0.5, "older fixes trip the watchdog"),
        par("min_fix_quality", "1", 4, "lower qualities trip the watchdog"),
        par("recovery_time", "s", 1.0, "good-fix time needed to leave the safe state"),
        par("max_position_std", "m", float("inf"), "a larger position_std trips the watchdog (inf: never)"),
        out("steer_angle_cmd_out", "rad", 0.0, "wheel-angle command to the actuators"),
        out("speed_cmd_out", "m/s", 0.0, "speed command to the actuators"),
        out("safe_state", "1", 0.0, "1 while tripped"),
        out("trip_reason", "1", 0.0, "0 ok, 1 stale fix, 2 poor fix, 3 steering not ready, 4 lockout, "
            "5 estimate too uncertain, 6 non-finite command or estimate"),
    )
    feedthrough = {k: ("steer_angle_cmd", "speed_cmd", "steer_angle_measured", "fix_age", "fix_quality",
                       "machine_ready", "machine_lockout", "position_std")
                   for k in ("steer_angle_cmd_out", "speed_cmd_out", "safe_state", "trip_reason")}

    def initialize(self, t0: float, dt: float) -> None:
        self.tripped, self.good_since, self.held, self.measured = False, t0, 0.0, 0.0

    def step(self, t: float, dt: float) -> None:
        u, p, y = self.u, self.p, self.y
        if math.isfinite(u["steer_angle_measured"]):
            self.measured = u["steer_angle_measured"]
        bad = [k for k in CHECKED if not math.isfinite(u[k])]
        if bad:
            reason = 6
        elif u["machine_lockout"] > 0.5:
            reason = 4
        elif u["machine_ready"] < 0.5:
            reason = 3
        elif u["fix_age"] > p["max_fix_age"]:
            reason = 1
        elif not fix_at_least(u["fix_quality"], p["min_fix_quality"]):
            reason = 2
        else:
            reason = 5 if u["position_std"] > p["max_position_std"] else 0
        if reason:
            self.good_since = None
            if not self.tripped:
                self.tripped, self.held = True, self.measured
                bound = (f"position std {u['position_std']:.3f} m, bound {p['max_position_std']:g} m, "
                         if p["max_position_std"] < float("inf") else "")
                what = f"{', '.join(f'{k} {u[k]}' for k in bad)}; " if bad else ""
                self.event(t, f"SAFE STATE: {REASONS[reason]} ({what}fix age {u['fix_age']:.2f} s, quality "
                              f"{u['fix_quality']:.0f}, {bound}steering ready {u['machine_ready']:.0f}, lockout "
                              f"{u['machine_lockout']:.0f}); speed to 0, wheel angle held at {self.held:.4f} rad")
        else:
            if self.good_since is None:
                self.good_since = t
            if self.tripped and t - self.good_since >= p["recovery_time"]:
                self.tripped = False
                self.event(t, f"recovered: fix, estimate and steering system good for {t - self.good_since:.2f} s")
        y["safe_state"], y["trip_reason"] = float(self.tripped), float(reason)
        if self.tripped:
            y["steer_angle_cmd_out"], y["speed_cmd_out"] = self.held, 0.0
        else:
            y["steer_angle_cmd_out"], y["speed_cmd_out"] = u["steer_angle_cmd"], u["speed_cmd"]

    def linear_model(self, step: float, speed: float) -> Block:
        """The watchdog while nothing trips it: the command passes."""
        return passthrough(self.name, {"steer_angle_cmd": "steer_angle_cmd_out"})


COMPONENT = SafetyWatchdog
