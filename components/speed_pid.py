"""Cascaded speed controller (paper section II): two PID-type loops.

    outer:  pedal_cmd = clip(k_ff * v_d + PID_v(v_d - v), 0, 1)          speed -> pedal position
    inner:  V         = clip(V_n + PID_p(pedal_cmd - pedal), V_min, V_max) pedal -> valve voltage

k_ff is a nominal (linear) pedal-per-speed feed-forward; the drivetrain's map is not linear.
"""
from __future__ import annotations

from pathlib import Path
from agrobot.orchestrator.compiled.cores import CoreDescription
from agrobot.orchestrator.component import Component, inp, out, par

from .models.pid import DiscretePID
from .models.c_sources import GUIDANCE_LAWS


class SpeedPID(Component):
    sampled = True
    roles = ("speed_controller",)
    c_core = CoreDescription(Path(__file__).with_suffix(".c"), extra_sources=GUIDANCE_LAWS)
    OFF_THE_LATERAL_LOOP = True   # moves nothing of the lateral channel at first order (margins)
    variables = (
        inp("speed_desired", "m/s", 0.0, "desired speed v_d (kinematic tracker)"),
        inp("speed", "m/s", 0.0, "measured / estimated speed"),
        inp("pedal_position", "1", 0.0, "measured pedal position"),
        par("kp", "1/(m/s)", 0.25, "outer loop proportional gain"),
        par("ki", "1/m", 0.15, "outer loop integral gain"),
        par("kd", "s/m", 0.0, "outer loop derivative gain"),
        par("integral_limit", "1", 0.05, "outer loop integral clamp (pedal travel)"),
        par("feedforward", "1/(m/s)", 0.25, "nominal pedal per m/s"),
        par("inner_kp", "V", 40.0, "inner loop proportional gain (V per pedal travel)"),
        par("inner_ki", "V/s", 0.0, "inner loop integral gain"),
        par("inner_kd", "V s", 0.0, "inner loop derivative gain"),
        par("neutral_voltage", "V", 6.0, "valve voltage with the pedal at rest"),
        par("voltage_min", "V", 0.0, "lowest valve voltage"),
        par("voltage_max", "V", 12.0, "highest valve voltage"),
        out("pedal_position_cmd", "1", 0.0, "desired pedal position"),
        out("pedal_valve_voltage", "V", 6.0, "voltage for the electro-mechanic valve"),
    )
    feedthrough = {
        "pedal_position_cmd": ("speed_desired", "speed"),
        "pedal_valve_voltage": ("speed_desired", "speed", "pedal_position"),
    }

    def initialize(self, t0: float, dt: float) -> None:
        p = self.p
        self.outer = DiscretePID(p["kp"], p["ki"], p["kd"], 0.0, 1.0, p["integral_limit"])
        vn = p["neutral_voltage"]
        self.inner = DiscretePID(p["inner_kp"], p["inner_ki"], p["inner_kd"],
                                 p["voltage_min"] - vn, p["voltage_max"] - vn)

    def step(self, t: float, dt: float) -> None:
        u, p = self.u, self.p
        v_d = float(u["speed_desired"])
        pedal_cmd = self.outer.update(v_d - float(u["speed"]), dt, offset=p["feedforward"] * v_d)
        voltage = p["neutral_voltage"] + self.inner.update(pedal_cmd - float(u["pedal_position"]), dt)
        self.y["pedal_position_cmd"], self.y["pedal_valve_voltage"] = pedal_cmd, voltage


COMPONENT = SpeedPID
