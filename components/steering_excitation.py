"""Steering excitation for identification experiments (paper section IV): plays one period of a
designed signal (a multisine) on repeat as the steering-angle command,
delta_cmd_k = values[k mod N] * scale, one value per step, held between steps."""
from __future__ import annotations

import numpy as np

from agrobot.orchestrator.component import Component, out, par


class SteeringExcitation(Component):
    sampled = True
    roles = ("excitation",)
    variables = (
        par("values", "", [0.0], "one period of the signal, one value per step"),
        par("scale", "rad", 1.0, "radians per unit of values"),
        out("steer_angle_cmd", "rad", 0.0, "steering-angle command"),
    )
    feedthrough = {}

    def initialize(self, t0: float, dt: float) -> None:
        self.values = np.asarray(self.p["values"], dtype=float) * float(self.p["scale"])
        self.require(self.values.ndim == 1 and len(self.values) > 0, "values must be a non-empty list")
        self.t0, self.dt = t0, dt

    def step(self, t: float, dt: float) -> None:
        k = int(round((t - self.t0) / self.dt))
        self.y["steer_angle_cmd"] = float(self.values[k % len(self.values)])


COMPONENT = SteeringExcitation
