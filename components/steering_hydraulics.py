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


# The substep loop (module docstring) in the forms it takes: lines marked "dead" for an angle dead band
# (or the quantisation guard), "res" / "raw" for a potentiometer with or without a resolution, "limit" /
# "free" for an extra rate limit or none (a clamp at +-inf changes nothing, not even a NaN: both
# comparisons are false). The statements are the general loop's, in its order: the same floats to the bit.
_INTEGRATE = ("integral += ki_h * error", "if integral > i_lim:", "    integral = i_lim", "elif integral < no_i:",
              "    integral = no_i")
_LOOP = (
    ("", "h, vn, db, opening_scale, rate_step, lim, res, alpha, kp, ki_h, v_lo, v_hi, i_lim, dead, max_move, "
         "inv_res, _ = constants"),
    ("", "rounder, no_dead, no_i, no_db, no_move, no_lim = ROUNDER, -dead, -i_lim, -db, -max_move, -lim"),
    ("", "v_rel = error = 0.0"),
    ("", "for _ in range(n):"),
    ("res", "    error = cmd - res * ((delta * inv_res + rounder) - rounder)"),
    ("raw", "    error = cmd - delta"),
    ("dead", "    if error > dead:"), ("dead", "        error = error - dead"),
    ("dead", "    elif error < no_dead:"), ("dead", "        error = error + dead"),
    ("dead", "    else:"), ("dead", "        error = 0.0"),
    ("", "    raw = kp * error + integral"),
    ("", "    if raw > v_hi:"), ("", "        v_rel = v_hi"),
    ("", "        if not error > 0:"), *(("", "            " + line) for line in _INTEGRATE),
    ("", "    elif raw < v_lo:"), ("", "        v_rel = v_lo"),
    ("", "        if not error < 0:"), *(("", "            " + line) for line in _INTEGRATE),
    ("", "    else:"), ("", "        v_rel = raw"), *(("", "        " + line) for line in _INTEGRATE),
    ("", "    if v_rel > db:"), ("", "        target = (v_rel - db) * opening_scale"),
    ("", "        if target > 1.0:"), ("", "            target = 1.0"),
    ("", "    elif v_rel < no_db:"), ("", "        target = (v_rel + db) * opening_scale"),
    ("", "        if target < -1.0:"), ("", "            target = -1.0"),
    ("", "    else:"), ("", "        target = 0.0"),
    ("", "    opening += alpha * (target - opening)"),
    ("limit", "    move = rate_step * opening"),
    ("limit", "    if move > max_move:"), ("limit", "        move = max_move"),
    ("limit", "    elif move < no_move:"), ("limit", "        move = no_move"),
    ("limit", "    delta += move"),
    ("free", "    delta += rate_step * opening"),
    ("", "    if delta > lim:"), ("", "        delta = lim"),
    ("", "    elif delta < no_lim:"), ("", "        delta = no_lim"),
    ("", "return delta, opening, integral, error, v_rel"),
)
_LOOPS: dict[tuple[bool, bool, bool], object] = {}


def substep_loop(dead: bool, resolution: bool, limit: bool):
    """``loop(n, cmd, delta, opening, integral, constants)`` -> (delta, opening, integral, error,
    v_rel) after n substeps, made once per form (an angle dead band, a potentiometer resolution,
    an extra rate limit: each present or not): the general loop without the tests that do not
    change for the run (a third of its time)."""
    key = (dead, resolution, limit)
    loop = _LOOPS.get(key)
    if loop is None:
        kept = {"", "dead" if dead else "", "res" if resolution else "raw", "limit" if limit else "free"}
        body = "\n".join("    " + line for mark, line in _LOOP if mark in kept)
        space = {"ROUNDER": ROUNDER}
        exec(compile(f"def loop(n, cmd, delta, opening, integral, constants):\n{body}\n",  # noqa: S102
                     f"<steering substeps {key}>", "exec"), space)
        loop = _LOOPS[key] = space["loop"]
    return loop


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
                p["rate_limit"] * h if p["rate_limit"] > 0 else math.inf, 1.0 / res if res > 0 else 0.0,
                substep_loop(bool(p["angle_deadband"] + (0.5 * res if p["quantization_guard"] else 0.0)),
                             res > 0, p["rate_limit"] > 0))

    def step(self, t: float, dt: float) -> None:
        """The substep loop of the module docstring as one function made for this configuration
        (``substep_loop``); DiscretePID.update (kd = 0), valve_opening and quantize inlined in it;
        tests check it against those functions and against the general loop, to the bit."""
        constants = self._per_step.get(dt)
        if constants is None:
            constants = self._per_step[dt] = self._constants(dt)
        h, vn, res, max_move, loop = constants[0], constants[1], constants[6], constants[14], constants[-1]
        pi = self.pi
        history = self.command_history
        history.append(float(self.u["steer_angle_cmd"]))
        delta, opening, pi.integral, pi.prev_error, v_rel = \
            loop(self.substeps, history[0], self.delta, self.opening, pi.integral, constants)
        self.delta, self.opening = delta, opening
        y = self.y
        y["steer_angle"] = delta
        y["steer_angle_measured"] = res * round(delta / res) if res > 0 else delta      # quantize, inline
        y["valve_voltage"] = vn + v_rel
        if abs(delta) < constants[5]:     # max(-max_move, min(max_move, rate)) / h as min and max choose
            rate = opening * constants[4]
            rate = rate if rate < max_move else max_move
            y["steer_rate"] = (rate if rate > -max_move else -max_move) / h
        else:
            y["steer_rate"] = 0.0

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
