"""Wheel odometry: the rear wheels' speed, which wheel slip makes read high (grades:
models.sensor_grades).

    v_measured = v (1 + e_0 + e_k) + n_k

e_0 is a scale error drawn once per run (tyre radius, mean slip), e_k a first-order Gauss-Markov
wander (the slip changing with the soil), n_k white noise per sample; a wheel at rest gives no
pulses and reads 0.
"""
from __future__ import annotations

import math

from agrobot.orchestrator.component import Component, inp, out, par

from .models import sensor_grades as grade


class WheelOdometry(Component):
    sampled = True
    roles = ("odometry",)
    variables = (
        inp("speed", "m/s", 0.0, "true longitudinal speed"),
        par("scale_error_std", "1", grade.ODOMETRY_SCALE_ERROR, "scale error e_0, 1 sigma (drawn once)"),
        par("slip_wander_std", "1", grade.ODOMETRY_SLIP_WANDER, "Gauss-Markov scale wander, std"),
        par("slip_time_constant", "s", grade.ODOMETRY_SLIP_TIME_CONSTANT, "its correlation time"),
        par("noise_std", "m/s", grade.ODOMETRY_NOISE, "white noise per sample"),
        out("speed_measured", "m/s", 0.0, "wheel speed"),
    )
    feedthrough = {"speed_measured": ("speed",)}

    def initialize(self, t0: float, dt: float) -> None:
        p = self.p
        for key in ("scale_error_std", "slip_wander_std", "noise_std"):
            self.require(p[key] >= 0, f"parameter {key} must be >= 0, got {p[key]}")
        self.require(p["slip_time_constant"] > 0, "parameter slip_time_constant must be > 0")
        self.scale = float(self.rng.standard_normal() * p["scale_error_std"])
        self.wander = float(self.rng.standard_normal() * p["slip_wander_std"])
        self.phi = math.exp(-dt / p["slip_time_constant"])

    def step(self, t: float, dt: float) -> None:
        w = self.rng.standard_normal(2)
        v = float(self.u["speed"])
        moving = abs(v) > 1e-3
        self.y["speed_measured"] = v * (1.0 + self.scale + self.wander) + self.p["noise_std"] * w[0] if moving else 0.0
        self.wander = grade.gauss_markov_step(self.wander, self.phi, self.p["slip_wander_std"], w[1])


COMPONENT = WheelOdometry
