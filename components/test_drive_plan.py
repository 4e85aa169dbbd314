"""A field test drive for identification and diagnosis (the truth tractor's plan,
measurements.truth_tractor.driving_plan): 20 s segments cycling through a steering multisine,
steps, a headland-like turn and small corrections, at speeds cycling through ``speeds``
(smooth 3 s changes, from rest). The steering command is held at 20 Hz; the plan is drawn from
the component's random stream (the study seed)."""
from __future__ import annotations

from orchestrator.component import Component, out, par


class TestDrivePlan(Component):
    sampled = True
    variables = (
        par("duration", "s", 600.0, "length of the drawn plan (held at its last value after)"),
        par("speeds", "m/s", [1.0, 2.0, 3.0], "segment speeds, cycled"),
        par("steer_scale", "1", 1.0, "factor on the plan's steering (a car at highway speed: 0.05)"),
        out("steer_angle_cmd", "rad", 0.0, "front wheel angle command"),
        out("speed_cmd", "m/s", 0.0, "speed set-point"),
    )
    feedthrough = {}

    def initialize(self, t0: float, dt: float) -> None:
        from measurements.truth_tractor import driving_plan

        speeds = tuple(float(v) for v in (self.p["speeds"] if isinstance(self.p["speeds"], list) else [self.p["speeds"]]))
        self.require(self.p["duration"] > 0 and speeds and min(speeds) >= 0,
                     f"duration {self.p['duration']} s and speeds {speeds}: expected a positive duration and speeds >= 0")
        self.t_plan, self.cmd, self.speed_of = driving_plan(self.rng, float(self.p["duration"]), speeds_cycle=speeds)
        self.cmd = self.cmd * float(self.p["steer_scale"])
        self.t0 = t0

    def step(self, t: float, dt: float) -> None:
        k = min(max(int((t - self.t0) * 20.0 + 1e-9), 0), len(self.cmd) - 1)
        self.y["steer_angle_cmd"] = float(self.cmd[k])
        self.y["speed_cmd"] = float(self.speed_of(min(t - self.t0, float(self.p["duration"]))))


COMPONENT = TestDrivePlan
