"""A field test drive for identification and diagnosis (``driving_plan``, the plan the truth
tractor of harness/truth_tractor.py drives too): 20 s segments cycling through a steering
multisine, steps, a headland-like turn and small corrections, at speeds cycling through ``speeds``
(smooth 3 s changes, from rest). The steering command is held at 20 Hz; the plan is drawn from
the component's random stream (the study seed)."""
from __future__ import annotations

import math

import numpy as np

from agrobot.orchestrator.component import Component, out, par

_DEG = math.pi / 180


def driving_plan(rng: np.random.Generator, duration: float, rate: float = 20.0, speeds_cycle=(1.0, 2.0, 3.0)):
    """Steering command (held at ``rate``) and a smooth speed profile: 20 s segments cycling
    through a multisine, steps, a headland-like turn and small corrections, at 1, 2 and 3 m/s
    (``speeds_cycle``: other segment speeds, e.g. one speed for a log that cannot separate
    speed-dependent effects)."""
    n = int(round(duration * rate))
    t = np.arange(n) / rate
    cmd = np.zeros(n)
    seg = int(20 * rate)
    speeds = []
    for i, a in enumerate(range(0, n, seg)):
        b = min(n, a + seg)
        tt = t[a:b] - t[a]
        kind = i % 4
        if kind == 0:
            f = rng.uniform(0.05, 1.0, 6)
            x = np.sum(np.sin(2 * np.pi * f[:, None] * tt[None, :] + rng.uniform(0, 2 * np.pi, 6)[:, None]), axis=0)
            cmd[a:b] = 6 * _DEG * x / np.sqrt(3.0)
        elif kind == 1 or kind == 3:
            span, amp = ((1.5, 3.0), 20 * _DEG) if kind == 1 else ((1.0, 2.0), 3 * _DEG)
            k = a
            while k < b:
                m = min(b, k + int(rng.uniform(*span) * rate))
                cmd[k:m] = rng.uniform(-amp, amp)
                k = m
        else:
            peak = rng.choice([-1, 1]) * rng.uniform(15, 25) * _DEG
            cmd[a:b] = np.interp(tt, [0, 2, 8, 10, 14, 16, 20], [0, peak, peak, -0.5 * peak, -0.5 * peak, 0, 0])
        speeds.append(speeds_cycle[i % len(speeds_cycle)])
    cmd = np.clip(cmd, -30 * _DEG, 30 * _DEG)

    def speed(time: float) -> float:
        i = min(int(time // 20.0), len(speeds) - 1)
        v1 = speeds[i]
        v0 = speeds[i - 1] if i > 0 else 0.0
        s = min(max((time - 20.0 * i) / 3.0, 0.0), 1.0)
        return v0 + (v1 - v0) * 0.5 * (1 - math.cos(math.pi * s))

    return t, cmd, speed


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
        speeds = tuple(float(v) for v in (self.p["speeds"] if isinstance(self.p["speeds"], list) else [self.p["speeds"]]))
        self.require(self.p["duration"] > 0 and speeds and min(speeds) >= 0,
                     f"duration {self.p['duration']} s and speeds {speeds}: expected a positive duration and speeds >= 0")
        _, self.cmd, self.speed_of = driving_plan(self.rng, float(self.p["duration"]), speeds_cycle=speeds)
        self.cmd = self.cmd * float(self.p["steer_scale"])
        self.t0 = t0

    def step(self, t: float, dt: float) -> None:
        k = min(max(int((t - self.t0) * 20.0 + 1e-9), 0), len(self.cmd) - 1)
        self.y["steer_angle_cmd"] = float(self.cmd[k])
        self.y["speed_cmd"] = float(self.speed_of(min(t - self.t0, float(self.p["duration"]))))


COMPONENT = TestDrivePlan
