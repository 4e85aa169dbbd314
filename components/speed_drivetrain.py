"""Speed drivetrain (paper section II): electro-mechanic valve -> pedal -> hydrostatic drive -> speed.

    o          = valve opening of (V - V_n) with dead-band (as the steering valve)
    dp/dt      = o * pedal_rate_max,             p in [0, 1]          pedal actuator
    v_ss(p)    = v_max * clip((p - p_0)/(1 - p_0), 0, 1) ** n         dead zone and curvature
    dv/dt      = (v_ss(p) - v) / tau                                  drivetrain lag

The dead zone p_0 and the curvature n make the pedal-to-speed gain vary with the operating point;
the speed PID's clamped integral then cannot remove the whole error: the steady-state error the
paper observed.
"""
from __future__ import annotations

from pathlib import Path
import math

from agrobot.orchestrator.compiled.cores import CoreDescription
from agrobot.orchestrator.component import Component, inp, out, par

from .models.c_sources import substeps, substeps_define


def steady_state_speed(pedal: float, v_max: float, dead_zone: float, exponent: float) -> float:
    """v_ss(p) of the hydrostatic drive."""
    x = min(max((pedal - dead_zone) / (1.0 - dead_zone), 0.0), 1.0)
    return v_max * x ** exponent


class SpeedDrivetrain(Component):
    sampled = False
    roles = ("drivetrain",)
    c_core = CoreDescription(Path(__file__).with_suffix(".c"), substeps_define, ("internal_step",))
    OFF_THE_LATERAL_LOOP = True   # moves nothing of the lateral channel at first order (margins)
    variables = (
        inp("pedal_valve_voltage", "V", 6.0, "voltage of the electro-mechanic pedal valve"),
        par("neutral_voltage", "V", 6.0, "voltage with the pedal at rest"),
        par("voltage_max", "V", 12.0, "highest valve voltage"),
        par("deadband", "V", 0.4, "valve dead-band half-width"),
        par("pedal_rate_max", "1/s", 1.0, "pedal speed at full valve opening (pedal travel / s)"),
        par("pedal_dead_zone", "1", 0.12, "pedal travel that does not move the tractor"),
        par("max_speed", "m/s", 4.0, "speed at full pedal"),
        par("speed_exponent", "1", 1.3, "curvature of the pedal-to-speed map"),
        par("time_constant", "s", 0.8, "drivetrain lag"),
        par("internal_step", "s", 0.005, "integration step"),
        par("speed0", "m/s", 0.0, "initial speed"),
        par("pedal0", "1", 0.0, "initial pedal position"),
        out("pedal_position", "1", 0.0, "pedal position 0..1"),
        out("speed", "m/s", 0.0, "longitudinal speed of the CG"),
    )
    feedthrough = {}

    def initialize(self, t0: float, dt: float) -> None:
        p = self.p
        self.require(0 <= p["pedal_dead_zone"] < 1, "pedal_dead_zone must be in [0, 1)")
        self.require(p["time_constant"] > 0 and p["internal_step"] > 0, "time constants must be > 0")
        self.substeps = substeps(dt, p["internal_step"])
        self.pedal, self.v = float(p["pedal0"]), float(p["speed0"])
        self._per_step: dict[float, tuple] = {}
        self._still: tuple = (None, 0.0)          # (pedal, v_ss) of the last step the pedal stood still
        self.y["pedal_position"], self.y["speed"] = self.pedal, self.v

    def _constants(self, dt: float) -> tuple:
        """The step's constants for step ``dt`` (made once per run and step: the parameters are
        fixed from ``initialize`` on)."""
        p = self.p
        h = dt / self.substeps
        vn, db = p["neutral_voltage"], p["deadband"]
        decay = math.exp(-h / p["time_constant"])
        return (vn, db, (p["voltage_max"] - vn) - db, h, p["pedal_rate_max"], decay, decay ** self.substeps,
                p["max_speed"], p["pedal_dead_zone"], 1.0 - p["pedal_dead_zone"], p["speed_exponent"])

    def step(self, t: float, dt: float) -> None:
        """valve_opening and steady_state_speed inlined, their arithmetic unchanged (a call costs as
        much as the arithmetic here)."""
        constants = self._per_step.get(dt)
        if constants is None:
            constants = self._per_step[dt] = self._constants(dt)
        vn, db, span, h, rate_max, decay, decay_step, v_max, p0, travel, expo = constants
        e = float(self.u["pedal_valve_voltage"]) - vn
        excess = abs(e) - db
        opening = 0.0 if excess <= 0.0 else math.copysign(min(excess / span, 1.0), e)
        pedal, v = self.pedal, self.v
        rate = h * opening * rate_max
        # min(max(a, 0.0), 1.0) as the builtins choose (max keeps its first argument unless the second
        # is greater, min unless the second is smaller; a NaN too), without their calls
        if rate == 0.0 or (pedal == 0.0 and rate < 0.0) or (pedal == 1.0 and rate > 0.0):
            # the pedal does not move over this step: v_ss is constant, the lag is exact in one go;
            # v_ss kept with the pedal value it was made of (the same object: the same number)
            held, v_ss = self._still
            if pedal is not held:
                a = (pedal - p0) / travel
                a = 0.0 if 0.0 > a else a
                v_ss = v_max * (1.0 if 1.0 < a else a) ** expo
                self._still = (pedal, v_ss)
            v = v_ss + (v - v_ss) * decay_step
        else:
            for _ in range(self.substeps):
                pedal = pedal + rate
                pedal = 0.0 if 0.0 > pedal else pedal
                pedal = 1.0 if 1.0 < pedal else pedal
                a = (pedal - p0) / travel
                a = 0.0 if 0.0 > a else a
                v_ss = v_max * (1.0 if 1.0 < a else a) ** expo
                v = v_ss + (v - v_ss) * decay
        self.pedal, self.v = pedal, v
        y = self.y
        y["pedal_position"], y["speed"] = pedal, v

COMPONENT = SpeedDrivetrain
