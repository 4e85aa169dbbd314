"""The steering hydraulics' step (components.steering_hydraulics), whose substep loop is made per form
and skips the PI and the valve while the error is 0 and the potentiometer's level holds, against the
general loop written here statement by statement (every test evaluated at every substep), to the bit,
on random parameters and command sequences: inside the quantisation guard, across levels, the voltage
saturated, the wheel at its stop, with and without a resolution, an angle dead band, a rate limit and
a command delay."""
from __future__ import annotations

import math
from collections import deque

import numpy as np

from agrobot.components.steering_hydraulics import SteeringHydraulics


class GeneralLoop:
    """The module docstring's substep equations with DiscretePID.update (kd = 0), valve_opening and
    quantize inlined, every test taken at every substep."""

    def __init__(self, p: dict, substeps: int, dt: float, delay_steps: int) -> None:
        self.p, self.n, self.h = p, substeps, dt / substeps
        self.history = deque([0.0] * delay_steps, maxlen=delay_steps + 1)
        self.delta, self.opening, self.integral, self.prev_error = float(p["delta0"]), 0.0, 0.0, 0.0

    def step(self, command: float) -> tuple[float, float, float, float]:
        p, h = self.p, self.h
        vn, db, res = p["neutral_voltage"], p["deadband"], p["potentiometer_resolution"]
        scale, rate_step = 1.0 / (p["voltage_max"] - vn - db), h * p["max_flow"] / p["volume_per_rad"]
        lim, alpha = p["angle_limit"], 1.0 - math.exp(-h / p["valve_time_constant"])
        kp, ki_h, i_lim = p["kp"], p["ki"] * h, p["integral_limit"]
        v_lo, v_hi = p["voltage_min"] - vn, p["voltage_max"] - vn
        dead = p["angle_deadband"] + (0.5 * res if p["quantization_guard"] else 0.0)
        max_move = p["rate_limit"] * h if p["rate_limit"] > 0 else math.inf
        inv_res = 1.0 / res if res > 0 else 0.0
        self.history.append(command)
        cmd, delta, opening, integral, v_rel = self.history[0], self.delta, self.opening, self.integral, 0.0
        for _ in range(self.n):
            error = cmd - (res * ((delta * inv_res + 1.5 * 2.0 ** 52) - 1.5 * 2.0 ** 52) if inv_res else delta)
            if dead:
                error = error - dead if error > dead else (error + dead if error < -dead else 0.0)
            raw = kp * error + integral
            if raw > v_hi:
                v_rel, windup = v_hi, error > 0
            elif raw < v_lo:
                v_rel, windup = v_lo, error < 0
            else:
                v_rel, windup = raw, False
            if not windup:
                integral += ki_h * error
                integral = i_lim if integral > i_lim else (-i_lim if integral < -i_lim else integral)
            if v_rel > db:
                target = min((v_rel - db) * scale, 1.0)
            elif v_rel < -db:
                target = max((v_rel + db) * scale, -1.0)
            else:
                target = 0.0
            opening += alpha * (target - opening)
            move = rate_step * opening
            move = max_move if move > max_move else (-max_move if move < -max_move else move)
            delta = min(max(delta + move, -lim), lim)
        self.delta, self.opening, self.integral, self.prev_error = delta, opening, integral, error
        measured = res * round(delta / res) if res > 0 else delta
        rate = max(-max_move, min(max_move, opening * rate_step)) / h if abs(delta) < lim else 0.0
        return delta, measured, vn + v_rel, rate


def _random_case(rng: np.random.Generator) -> tuple[dict, float, np.ndarray]:
    params = {"quantization_guard": int(rng.integers(0, 2)),
              "potentiometer_resolution": float(rng.choice([0.0, math.radians(1.0),
                                                             math.radians(rng.uniform(0.1, 2))])),
              "angle_deadband": float(rng.choice([0.0, math.radians(rng.uniform(0.0, 1.0))])),
              "rate_limit": float(rng.choice([0.0, rng.uniform(0.2, 1.5)])),
              "command_delay": float(rng.choice([0.0, 0.03])), "kp": float(rng.uniform(20.0, 400.0)),
              "ki": float(rng.choice([0.0, rng.uniform(0.0, 60.0)])), "integral_limit": float(rng.uniform(0.5, 3.0)),
              "deadband": float(rng.uniform(0.0, 1.0)), "delta0": float(rng.uniform(-0.2, 0.2))}
    dt = float(rng.choice([0.01, 0.02, 0.05]))
    # commands held over several steps (the MPC's sample time), small ones and ones past the stop
    held = rng.choice([rng.uniform(-0.05, 0.05), rng.uniform(-0.9, 0.9), 0.0], size=40, p=[0.5, 0.4, 0.1])
    return params, dt, np.repeat(held, rng.integers(2, 12))


def test_step_equals_the_general_loop_to_the_bit_on_random_cases():
    rng = np.random.default_rng(56)
    seen = set()
    for _ in range(60):
        params, dt, commands = _random_case(rng)
        s = SteeringHydraulics("steering", params)
        s.initialize(0.0, dt)
        delay = len(s.command_history)
        ref = GeneralLoop(s.p, s.substeps, dt, delay)
        for k, cmd in enumerate(commands):
            s.u["steer_angle_cmd"] = float(cmd)
            s.step(k * dt, dt)
            want = ref.step(float(cmd))
            got = (s.y["steer_angle"], s.y["steer_angle_measured"], s.y["valve_voltage"], s.y["steer_rate"])
            assert got == want, (params, dt, k, got, want)
            assert (s.pi.integral, s.pi.prev_error, s.opening) == (ref.integral, ref.prev_error, ref.opening)
            seen.add("stop" if abs(want[0]) >= s.p["angle_limit"] else "free")
            seen.add("saturated" if abs(want[2] - 6.0) >= 6.0 else "linear")
            seen.add("held error" if ref.prev_error == 0.0 and ref.integral != 0.0 else "moving error")
    assert seen == {"stop", "free", "saturated", "linear", "held error", "moving error"}, seen
