"""The speed drivetrain's step (components.speed_drivetrain), whose arithmetic inlines valve_opening
and steady_state_speed, against those functions on random states and voltages: the valve inside
and beyond its dead band, the pedal anywhere on [0, 1] and at both stops, any speed."""
from __future__ import annotations

import math

import numpy as np

from agrobot.components.speed_drivetrain import SpeedDrivetrain, steady_state_speed
from agrobot.components.steering_hydraulics import valve_opening


def _by_the_functions(p: dict, pedal: float, v: float, volt: float, dt: float) -> tuple[float, float]:
    """One step of the module docstring's equations, substep by substep, with the named functions."""
    n = max(1, int(round(dt / p["internal_step"])))
    h = dt / n
    o = valve_opening(volt, p["neutral_voltage"], p["deadband"], p["voltage_max"] - p["neutral_voltage"])
    for _ in range(n):
        pedal = min(max(pedal + h * o * p["pedal_rate_max"], 0.0), 1.0)
        v_ss = steady_state_speed(pedal, p["max_speed"], p["pedal_dead_zone"], p["speed_exponent"])
        v = v_ss + (v - v_ss) * math.exp(-h / p["time_constant"])
    return pedal, v


def test_inlined_step_equals_valve_opening_and_steady_state_speed_on_random_inputs():
    rng = np.random.default_rng(56)
    worst = 0.0
    kinds = set()
    for case in range(2000):
        params = {"deadband": float(rng.uniform(0.0, 1.0)), "pedal_dead_zone": float(rng.uniform(0.0, 0.5)),
                  "speed_exponent": float(rng.uniform(0.5, 2.5)), "pedal_rate_max": float(rng.uniform(0.2, 3.0)),
                  "time_constant": float(rng.uniform(0.1, 2.0))}
        dt = float(rng.choice([0.01, 0.02, 0.05]))
        d = SpeedDrivetrain("d", params)
        d.initialize(0.0, dt)
        p = d.p
        pedal = float(rng.choice([0.0, 1.0, rng.uniform(0.0, 1.0)], p=[0.2, 0.2, 0.6]))
        v = float(rng.uniform(0.0, 5.0))
        vn, db = p["neutral_voltage"], p["deadband"]
        volt = float(rng.choice([rng.uniform(vn - db, vn + db), rng.uniform(0.0, p["voltage_max"])]))
        d.pedal, d.v = pedal, v
        d.u["pedal_valve_voltage"] = volt
        d.step(case * dt, dt)
        want_pedal, want_v = _by_the_functions(p, pedal, v, volt, dt)
        worst = max(worst, abs(d.y["pedal_position"] - want_pedal), abs(d.y["speed"] - want_v))
        moved = valve_opening(volt, vn, db, p["voltage_max"] - vn) != 0.0
        kinds.add(("moving" if moved and 0.0 < want_pedal < 1.0 else "still or at a stop"))
    assert kinds == {"moving", "still or at a stop"}
    assert worst <= 1e-12, worst
