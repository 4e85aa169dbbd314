"""Steering hydraulics (paper section II): low-level PI -> electro-hydraulic valve -> wheel angle.

Per internal step h (``internal_step``, default 1 ms)::

    V       = clip(V_neutral + PI(delta_cmd - delta_measured), V_min, V_max)        [0..12 V]
    o_cmd   = sign(V - V_n) * max(|V - V_n| - deadband, 0) / (V_max - V_n - deadband)   [-1..1]
    do/dt   = (o_cmd - o) / tau_valve                                               spool lag
    ddelta/dt = o * Q_max / V_per_rad                                               flow -> rate
    delta   in [-delta_max, delta_max] (mechanical stop)
    delta_measured = resolution * round(delta / resolution)                         potentiometer

Q_max = 12 L/min; with the default cylinder volume per radian the fastest steering rate is 60 deg/s.

Extensions (off by default; entries of the diagnosis catalogue): ``command_delay`` (the command
acts ``d`` seconds late, resolved to the component's step), ``angle_deadband`` (the PI sees
sign(e) max(|e| - D, 0): errors below D are ignored) and ``rate_limit`` (|ddelta/dt| <= r, on top
of the valve's flow limit; 0 = no extra limit).

``quantization_guard`` (a controller setting, on in the shipped figure-8): the PI also ignores
errors within half the potentiometer resolution. Without it the PI hunts between two sensor levels
(the wheel-rate reverses about 9 times a second on the figure-8); with it, once a second. The
diagnosis' first-order equivalent leaves it out, as it leaves out the potentiometer's quantisation.
"""
from __future__ import annotations

import math
from collections import deque
from pathlib import Path

import numpy as np

from agrobot.orchestrator.compiled.cores import CoreDescription, capacity
from agrobot.orchestrator.component import Component, inp, out, par

from .models.c_sources import delay_steps, substeps, substeps_define
from .models.pid import DiscretePID
from .models.loop_blocks import Block, delay_line, lifted


def valve_opening(voltage: float, neutral: float, deadband: float, full_scale: float) -> float:
    """Normalised spool opening for a valve voltage, with a symmetric dead-band around neutral."""
    e = voltage - neutral
    excess = abs(e) - deadband
    if excess <= 0.0:
        return 0.0
    return math.copysign(min(excess / (full_scale - deadband), 1.0), e)


# x + 1.5 2^52 - 1.5 2^52 is round(x), half to even, as a float, for |x| < 2^51 (the sum keeps no
# fraction, and the hardware rounds half to even): the potentiometer's level in the substep loop,
# where |delta / resolution| stays below the stop's angle_limit / resolution, without a call
ROUNDER = 1.5 * 2.0 ** 52


def quantize(value: float, resolution: float) -> float:
    return resolution * round(value / resolution) if resolution > 0 else value


def _steering_compiled(comp, period: float) -> str:
    return substeps_define(comp, period) + f"#define DELAY_STEPS {delay_steps(comp.p['command_delay'], period)}\n"


def _steering_runtime(comp, period: float) -> tuple[str, dict[str, float]]:
    steps = delay_steps(comp.p["command_delay"], period)
    return (substeps_define(comp, period) + f"#define DELAY_CAPACITY {capacity(steps)}\n"
            "#define DELAY_STEPS ((int)p[P__delay_steps])\n", {"_delay_steps": float(steps)})


class SteeringHydraulics(Component):
    sampled = False
    roles = ("steering",)
    c_core = CoreDescription(Path(__file__).with_suffix(".c"), _steering_compiled, ("internal_step", "command_delay"),
                             runtime=_steering_runtime)      # its C model core, beside this file
    variables = (
        inp("steer_angle_cmd", "rad", 0.0, "desired front wheel angle (from the yaw-rate MPC)"),
        par("kp", "V/rad", 150.0, "low-level PI proportional gain"),
        par("ki", "V/(rad s)", 20.0, "low-level PI integral gain"),
        par("integral_limit", "V", 2.0, "anti-windup clamp of the PI integral"),
        par("neutral_voltage", "V", 6.0, "valve voltage with no flow"),
        par("voltage_min", "V", 0.0, "lowest valve voltage"),
        par("voltage_max", "V", 12.0, "highest valve voltage"),
        par("deadband", "V", 0.5, "valve dead-band half-width around neutral"),
        par("max_flow", "m3/s", 12.0 / 60000.0, "valve flow at full opening (12 L/min)"),
        par("volume_per_rad", "m3/rad", (12.0 / 60000.0) / math.radians(60.0),
            "cylinder volume per radian of wheel angle"),
        par("valve_time_constant", "s", 0.03, "spool lag"),
        par("angle_limit", "rad", math.radians(45.0), "mechanical stop |delta|"),
        par("potentiometer_resolution", "rad", math.radians(1.0), "angle sensor resolution"),
        par("internal_step", "s", 0.001, "integration and low-level control step"),
        par("delta0", "rad", 0.0, "initial wheel angle"),
        par("command_delay", "s", 0.0, "extension: transport delay of the command"),
        par("angle_deadband", "rad", 0.0, "extension: angle errors below this are ignored"),
        par("quantization_guard", "1", 0, "1: the PI also ignores errors within half the potentiometer "
            "resolution (no hunting between two sensor levels)"),
        par("rate_limit", "rad/s", 0.0, "extension: extra wheel-rate limit (0 = the valve's only)"),
        out("steer_angle", "rad", 0.0, "true front wheel angle delta"),
        out("steer_angle_measured", "rad", 0.0, "potentiometer reading (quantised)"),
        out("valve_voltage", "V", 6.0, "voltage applied to the electro-hydraulic valve"),
        out("steer_rate", "rad/s", 0.0, "wheel angle rate"),
    )
    feedthrough = {}

    def initialize(self, t0: float, dt: float) -> None:
        p = self.p
        self.require(p["voltage_min"] < p["neutral_voltage"] < p["voltage_max"],
                     "need voltage_min < neutral_voltage < voltage_max")
        self.require(0 <= p["deadband"] < p["voltage_max"] - p["neutral_voltage"],
                     "deadband must be >= 0 and below the valve's voltage span")
        self.require(p["internal_step"] > 0 and p["valve_time_constant"] > 0, "time constants must be > 0")
        self.substeps = substeps(dt, p["internal_step"])
        for key in ("command_delay", "angle_deadband", "rate_limit"):
            self.require(float(p[key]) >= 0, f"parameter {key} must be >= 0, got {p[key]}")
        self.require(p["quantization_guard"] in (0, 1), f"parameter quantization_guard must be 0 or 1, "
                     f"got {p['quantization_guard']!r}")
        res = p["potentiometer_resolution"]
        self.require(res <= 0 or abs(p["angle_limit"]) / res < 2.0 ** 51,        # the substeps' rounding (ROUNDER)
                     f"parameter potentiometer_resolution must be 0 (none) or above angle_limit / 2^51, got {res}")
        steps = delay_steps(p["command_delay"], dt)
        self.command_history = deque([0.0] * steps, maxlen=steps + 1)
        self.pi = DiscretePID(p["kp"], p["ki"], 0.0, p["voltage_min"] - p["neutral_voltage"],
                              p["voltage_max"] - p["neutral_voltage"], p["integral_limit"])
        self.delta = float(p["delta0"])
        self.opening = 0.0
        self._per_step: dict[float, tuple] = {}
        self.y["steer_angle"] = self.delta
        self.y["steer_angle_measured"] = quantize(self.delta, p["potentiometer_resolution"])

    def _constants(self, dt: float) -> tuple:
        """The substep's constants for step ``dt`` (made once per run and step: the parameters are
        fixed from ``initialize`` on)."""
        p = self.p
        h = dt / self.substeps
        vn, db = p["neutral_voltage"], p["deadband"]
        res = p["potentiometer_resolution"]
        pi = self.pi
        return (h, vn, db, 1.0 / (p["voltage_max"] - vn - db), h * p["max_flow"] / p["volume_per_rad"],
                p["angle_limit"], res, 1.0 - math.exp(-h / p["valve_time_constant"]),
                pi.kp, pi.ki * h, pi.u_min, pi.u_max, pi.integral_limit,
                p["angle_deadband"] + (0.5 * res if p["quantization_guard"] else 0.0),
                p["rate_limit"] * h if p["rate_limit"] > 0 else math.inf, 1.0 / res if res > 0 else 0.0)

    def step(self, t: float, dt: float) -> None:
        """The substep loop inlines DiscretePID.update (kd = 0), valve_opening and quantize
        (a call costs as much as the arithmetic here; the rounding by ROUNDER); tests check it
        against those functions."""
        constants = self._per_step.get(dt)
        if constants is None:
            constants = self._per_step[dt] = self._constants(dt)
        h, vn, db, opening_scale, rate_step, lim, res, alpha, kp, ki_h, v_lo, v_hi, i_lim, dead, max_move, inv_res = \
            constants
        pi = self.pi
        integral = pi.integral
        history = self.command_history
        history.append(float(self.u["steer_angle_cmd"]))
        cmd = history[0]
        delta, opening = self.delta, self.opening
        v_rel = 0.0
        rounder, no_dead, no_i, no_db, no_move, no_lim = ROUNDER, -dead, -i_lim, -db, -max_move, -lim
        for _ in range(self.substeps):
            error = cmd - (res * ((delta * inv_res + rounder) - rounder) if inv_res else delta)
            if dead:
                error = error - dead if error > dead else (error + dead if error < no_dead else 0.0)
            raw = kp * error + integral
            if raw > v_hi:
                v_rel = v_hi
                windup = error > 0
            elif raw < v_lo:
                v_rel = v_lo
                windup = error < 0
            else:
                v_rel, windup = raw, False
            if not windup:
                integral += ki_h * error
                if integral > i_lim:
                    integral = i_lim
                elif integral < no_i:
                    integral = no_i
            if v_rel > db:
                target = (v_rel - db) * opening_scale
                target = 1.0 if target > 1.0 else target
            elif v_rel < no_db:
                target = (v_rel + db) * opening_scale
                target = -1.0 if target < -1.0 else target
            else:
                target = 0.0
            opening += alpha * (target - opening)
            move = rate_step * opening
            if move > max_move:
                move = max_move
            elif move < no_move:
                move = no_move
            delta += move
            if delta > lim:
                delta = lim
            elif delta < no_lim:
                delta = no_lim
        pi.integral, pi.prev_error = integral, error
        voltage = vn + v_rel
        self.delta, self.opening = delta, opening
        y = self.y
        y["steer_angle"] = delta
        y["steer_angle_measured"] = res * round(delta / res) if res > 0 else delta      # quantize, inline
        y["valve_voltage"] = voltage
        y["steer_rate"] = max(-max_move, min(max_move, opening * rate_step)) / h if abs(delta) < lim else 0.0

    def linear_model(self, step: float, speed: float) -> Block:
        """The hydraulics' substep (components.steering_hydraulics) beyond its dead bands, lifted over
        the substeps of one step, with the command delay in whole steps:

            e = c - delta;  I <- I + k_i h e;  o <- o + alpha (s_o (k_p e + I) - o);  delta <- delta + r_s o

        s_o = 1 / (V_max - V_n - V_db) the valve's slope above its dead band, alpha = 1 - exp(-h / tau_valve),
        r_s = h Q_max / V_rad. The potentiometer reads delta."""
        p = self.p
        m = substeps(step, p["internal_step"])
        h = step / m
        s_o = 1.0 / (p["voltage_max"] - p["neutral_voltage"] - p["deadband"])
        alpha = 1.0 - math.exp(-h / p["valve_time_constant"])
        rs = h * p["max_flow"] / p["volume_per_rad"]
        kp, kih = p["kp"], p["ki"] * h
        A1 = np.array([[1.0, 0.0, -kih], [alpha * s_o, 1.0 - alpha, -alpha * s_o * kp], [0.0, 0.0, 1.0]])
        B1 = np.array([kih, alpha * s_o * kp, 0.0])
        A1[2] += rs * A1[1]                               # delta uses the new opening
        B1[2] += rs * B1[1]
        As, Bs = lifted(A1, B1.reshape(3, 1), m)
        d = delay_steps(p["command_delay"], step)
        line = delay_line("", ["c"], ["c"], d)
        # state [I, o, delta; registers]; the hydraulics act on the delayed command
        n = 3 + line.n
        A = np.zeros((n, n))
        A[:3, :3] = As
        A[:3, 3:] = Bs @ line.C
        A[3:, 3:] = line.A
        B = np.vstack([Bs @ line.D, line.B])
        C = np.zeros((2, n))
        C[:, 2] = 1.0
        return Block.of(self.name, ["steer_angle_cmd"], ["steer_angle", "steer_angle_measured"], A, B, C, sampled=False)


COMPONENT = SteeringHydraulics
