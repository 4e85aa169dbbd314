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


# The substep loop (module docstring) as statements, in the general loop's order: the same floats to
# the bit. A clamp at +-inf changes nothing, not even a NaN (both comparisons are false): without an
# extra rate limit the move is not clamped.
_DEAD = ("if error > dead:", "    error = error - dead", "elif error < no_dead:", "    error = error + dead", "else:",
         "    error = 0.0")
_INTEGRATE = ("integral += {ki_e}", "if integral > i_lim:", "    integral = i_lim", "elif integral < no_i:",
              "    integral = no_i")
_PI = ("raw = {kp_e} + integral", "if raw > v_hi:", "    v_rel = v_hi", "    if not error > 0:",
       *("        " + line for line in _INTEGRATE), "elif raw < v_lo:", "    v_rel = v_lo", "    if not error < 0:",
       *("        " + line for line in _INTEGRATE), "else:", "    v_rel = raw", *("    " + line for line in _INTEGRATE))
_VALVE = ("if v_rel > db:", "    target = (v_rel - db) * opening_scale", "    if target > 1.0:", "        target = 1.0",
          "elif v_rel < no_db:", "    target = (v_rel + db) * opening_scale", "    if target < -1.0:",
          "        target = -1.0", "else:", "    target = 0.0")
_LIMITED_MOVE = ("move = rate_step * opening", "if move > max_move:", "    move = max_move", "elif move < no_move:",
                 "    move = no_move", "delta += move")
_STOP = ("if delta > lim:", "    delta = lim", "elif delta < no_lim:", "    delta = no_lim")
# With a resolution the error holds while the potentiometer's level does: ``reading`` (lo, hi, level)
# is an interval of delta whose ends read that level (the rounding is monotonic: every delta between
# them reads it too; NaN ends when its ends do not), kept from step to step; the error and its
# products by k_p and k_i h are made when delta leaves it or the command changes. Once a substep finds
# the error 0 and leaves the integral as it was (nonzero: I + 0 = I), the PI and the valve are fixed
# until the level changes: the next substeps only move the spool and the wheel.
_LEVEL = ("level = (delta * inv_res + rounder) - rounder",
          "lo, hi = (level - 0.4990234375) * res, (level + 0.4990234375) * res",
          "if not ((lo * inv_res + rounder) - rounder) == level == ((hi * inv_res + rounder) - rounder):",
          "    lo = hi = NAN")
_ERROR = ("error = cmd - res * level",)
_PRODUCTS = ("kp_e, ki_e = kp * error, ki_h * error",)
_QUIET = ("quiet = error == 0.0 and integral == before and integral != 0.0",)


# the outputs after the last substep (the potentiometer's reading is quantize's, inline); the wheel
# rate is max(-max_move, min(max_move, rate)) / h as min and max choose
_OUTPUTS = ("y['steer_angle'] = delta", "y['valve_voltage'] = vn + v_rel", "if abs(delta) < lim:",
            "    rate = opening * rate_step", "    rate = rate if rate < max_move else max_move",
            "    y['steer_rate'] = (rate if rate > -max_move else -max_move) / h", "else:", "    y['steer_rate'] = 0.0")


def _indent(lines, spaces: int) -> list[str]:
    return [" " * spaces + line for line in lines]


_BOUND = ("h", "vn", "db", "opening_scale", "rate_step", "lim", "res", "alpha", "kp", "ki_h", "v_lo", "v_hi",
          "i_lim", "dead", "max_move", "inv_res", "rounder", "no_dead", "no_i", "no_db", "no_move", "no_lim")


def _loop_source(dead: bool, resolution: bool, limit: bool) -> str:
    """The source of ``make(constants)``, which returns the substep loop of one form with the
    step's constants bound as its locals (defaults: made once per run and step)."""
    wheel = ["opening += alpha * (target - opening)"] + \
        (list(_LIMITED_MOVE) if limit else ["delta += rate_step * opening"]) + list(_STOP)
    dead_band = _DEAD if dead else ()
    if resolution:
        pi = [line.format(kp_e="kp_e", ki_e="ki_e") for line in _PI]
        lines = ["lo, hi, level = reading", *_ERROR, *dead_band, *_PRODUCTS, "v_rel = 0.0", "quiet = False",
                 "for _ in range(n):", "    if lo <= delta <= hi:", "        if quiet:", *_indent(wheel, 12),
                 "            continue", "    else:", *_indent(_LEVEL + _ERROR + dead_band + _PRODUCTS, 8),
                 "        quiet = False", "    before = integral",
                 *_indent(pi + list(_VALVE) + wheel + list(_QUIET), 4)]
    else:
        pi = [line.format(kp_e="kp * error", ki_e="ki_h * error") for line in _PI]
        lines = ["v_rel = error = 0.0", "for _ in range(n):", "    error = cmd - delta",
                 *_indent(tuple(dead_band) + tuple(pi) + _VALVE, 4), *_indent(wheel, 4)]
    lines += list(_OUTPUTS) + ["y['steer_angle_measured'] = res * round(delta / res)" if resolution else
                               "y['steer_angle_measured'] = delta"]
    lines += ["return delta, opening, integral, error, reading" if not resolution else
              "return delta, opening, integral, error, (lo, hi, level)"]
    bound = ", ".join(f"{name}={name}" for name in _BOUND)
    return "\n".join([
        "def make(constants):",
        "    h, vn, db, opening_scale, rate_step, lim, res, alpha, kp, ki_h, v_lo, v_hi, i_lim, dead, max_move, "
        "inv_res = constants",
        "    rounder, no_dead, no_i, no_db, no_move, no_lim = ROUNDER, -dead, -i_lim, -db, -max_move, -lim",
        f"    def loop(n, cmd, delta, opening, integral, reading, y, {bound}):",
        *_indent(lines, 8), "    return loop", ""])


_LOOPS: dict[tuple[bool, bool, bool], object] = {}


def substep_loop(dead: bool, resolution: bool, limit: bool):
    """``make(constants)`` -> ``loop(n, cmd, delta, opening, integral, reading, y)`` -> (delta,
    opening, integral, error, reading) after n substeps, the outputs set in ``y``; compiled once per
    form (an angle dead band, a potentiometer resolution, an extra rate limit: each present or not):
    the general loop without the tests that do not change for the run, and with a resolution its
    quiet substeps (``_QUIET``) reduced to the spool and the wheel."""
    key = (dead, resolution, limit)
    loop = _LOOPS.get(key)
    if loop is None:
        space = {"ROUNDER": ROUNDER, "NAN": math.nan}
        exec(compile(_loop_source(*key), f"<steering substeps {key}>", "exec"), space)  # noqa: S102
        loop = _LOOPS[key] = space["make"]
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
        self._delayed = steps > 0
        self.pi = DiscretePID(p["kp"], p["ki"], 0.0, p["voltage_min"] - p["neutral_voltage"],
                              p["voltage_max"] - p["neutral_voltage"], p["integral_limit"])
        self.delta = float(p["delta0"])
        self.opening = 0.0
        self._per_step: dict = {}                             # step -> its substep loop (_step_of)
        self._reading = (math.nan, math.nan, math.nan)        # the potentiometer level's interval (substep_loop)
        self.y["steer_angle"] = self.delta
        self.y["steer_angle_measured"] = quantize(self.delta, p["potentiometer_resolution"])

    def __getstate__(self) -> dict:
        """Pickled without the substep loops made for each step (a generated function is not
        picklable); ``step`` makes them again."""
        return {**self.__dict__, "_per_step": {}}

    def _constants(self, dt: float) -> tuple:
        """The substep's constants for step ``dt`` (the parameters are fixed from ``initialize`` on):
        (h, V_n, db, opening scale, rate step, angle limit, resolution, alpha, k_p, k_i h, PI bounds,
        integral limit, angle dead band, rate limit per substep, 1 / resolution)."""
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

    def _step_of(self, dt: float):
        """The substep loop for step ``dt`` with the constants bound, made once per run and step."""
        c = self._constants(dt)
        return substep_loop(bool(c[13]), c[6] > 0, self.p["rate_limit"] > 0)(c)

    def step(self, t: float, dt: float) -> None:
        """The substep loop of the module docstring as one function made for this configuration
        (``substep_loop``), which also sets the outputs; DiscretePID.update (kd = 0), valve_opening
        and quantize inlined in it; tests check it against those functions and against the general
        loop, to the bit."""
        loop = self._per_step.get(dt)
        if loop is None:
            loop = self._per_step[dt] = self._step_of(dt)
        pi = self.pi
        cmd = float(self.u["steer_angle_cmd"])
        if self._delayed:
            history = self.command_history
            history.append(cmd)
            cmd = history[0]
        self.delta, self.opening, pi.integral, pi.prev_error, self._reading = \
            loop(self.substeps, cmd, self.delta, self.opening, pi.integral, self._reading, self.y)

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
