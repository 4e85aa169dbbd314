"""Yaw-rate gyro: measured = true + bias + white noise (std ``noise_std``), sampled at its step."""
from __future__ import annotations

from agrobot.orchestrator.component import Component, inp, out, par

from .models.loop_blocks import Block, passthrough


class GyroSensor(Component):
    sampled = True
    roles = ("gyro",)
    variables = (
        inp("yaw_rate", "rad/s", 0.0, "true yaw rate"),
        par("noise_std", "rad/s", 0.0, "white measurement noise (1 sigma)"),
        par("bias", "rad/s", 0.0, "constant offset"),
        out("yaw_rate_measured", "rad/s", 0.0, "gyro reading"),
    )
    feedthrough = {"yaw_rate_measured": ("yaw_rate",)}

    def step(self, t: float, dt: float) -> None:
        noise = self.rng.standard_normal() * self.p["noise_std"] if self.p["noise_std"] > 0 else 0.0
        self.y["yaw_rate_measured"] = self.u["yaw_rate"] + self.p["bias"] + noise

    def linear_model(self, step: float, speed: float) -> Block:
        """The gyro without bias and noise: it reads the yaw rate."""
        return passthrough(self.name, {"yaw_rate": "yaw_rate_measured"})


COMPONENT = GyroSensor
