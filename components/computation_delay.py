"""The controller's commands reach the actuators ``samples`` controller steps after the inputs
they were computed from (computation, bus and scheduling time on the controller side):

    steer_angle_cmd_out(t_k) = steer_angle_cmd(t_{k - n}),  pedal_valve_voltage_out(t_k) = pedal_valve_voltage(t_{k - n})

n = 0 passes the commands through in the same instant (the paper's timing). Before the first n
samples the outputs hold the first command received.
"""
from __future__ import annotations

from pathlib import Path
from collections import deque

from agrobot.orchestrator.compiled.cores import CoreDescription, capacity
from agrobot.orchestrator.component import Component, inp, out, par

from .models.loop_blocks import Block, delay_line


def _delay_compiled(comp, period: float) -> str:
    return f"#define DELAY_SAMPLES {int(comp.p['samples'])}\n"


def _delay_runtime(comp, period: float) -> tuple[str, dict[str, float]]:
    samples = int(comp.p["samples"])
    return (f"#define DELAY_CAPACITY {capacity(samples)}\n#define DELAY_SAMPLES ((int)p[P__samples])\n",
            {"_samples": float(samples)})


class ComputationDelay(Component):
    sampled = True
    roles = ("computation_delay",)
    c_core = CoreDescription(Path(__file__).with_suffix(".c"), _delay_compiled, ("samples",), runtime=_delay_runtime)
    variables = (
        inp("steer_angle_cmd", "rad", 0.0, "wheel-angle command as computed"),
        inp("pedal_valve_voltage", "V", 6.0, "pedal valve voltage as computed"),
        par("samples", "1", 0, "delay in steps of this component (0: none)"),
        out("steer_angle_cmd_out", "rad", 0.0, "wheel-angle command as the steering receives it"),
        out("pedal_valve_voltage_out", "V", 6.0, "pedal valve voltage as the drivetrain receives it"),
    )
    feedthrough = {"steer_angle_cmd_out": ("steer_angle_cmd",), "pedal_valve_voltage_out": ("pedal_valve_voltage",)}

    def initialize(self, t0: float, dt: float) -> None:
        n = self.p["samples"]
        self.require(float(n).is_integer() and n >= 0, f"samples must be a whole number >= 0, got {n}")
        self.buffer: deque = deque(maxlen=int(n) + 1)

    def step(self, t: float, dt: float) -> None:
        u = self.u
        self.buffer.append((u["steer_angle_cmd"], u["pedal_valve_voltage"]))
        self.y["steer_angle_cmd_out"], self.y["pedal_valve_voltage_out"] = self.buffer[0]

    def linear_model(self, step: float, speed: float) -> Block:
        return delay_line(self.name, ["steer_angle_cmd"], ["steer_angle_cmd_out"], int(self.p["samples"]))


COMPONENT = ComputationDelay
