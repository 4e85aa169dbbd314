"""The steering's closed-loop first-order equivalent (paper section II: a PI around a valve
whose flow sets the wheel rate), the model a replay of delta_cmd -> delta uses::

    ddelta/dt = clip(dz(delta_cmd(t - d) - delta, D) / tau, -r, r)

derived from the hydraulics' parameters (``components.steering_hydraulics``):

    tau = V_rad (V_max - V_n - V_db) / (k_p Q_max) + tau_valve    small-signal loop gain + spool lag
    D   = V_db / k_p (+ angle_deadband)                            valve dead-band seen as an angle
    r   = Q_max / V_rad (or rate_limit if lower)                   full-opening rate
    d   = command_delay
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping

import numpy as np


@dataclass(frozen=True)
class FirstOrderSteering:
    time_constant: float      # tau [s]
    deadband: float           # D [rad]
    rate_limit: float         # r [rad/s]
    delay: float              # d [s]

    @classmethod
    def of(cls, p: Mapping[str, float]) -> "FirstOrderSteering":
        """From the steering hydraulics' resolved parameters (SI)."""
        kp = float(p["kp"])
        span = p["voltage_max"] - p["neutral_voltage"] - p["deadband"]
        valve_rate = p["max_flow"] / p["volume_per_rad"]
        rate = min(valve_rate, p["rate_limit"]) if p["rate_limit"] > 0 else valve_rate
        return cls(p["volume_per_rad"] * span / (kp * p["max_flow"]) + p["valve_time_constant"],
                   p["deadband"] / kp + p["angle_deadband"], rate, p["command_delay"])


def delayed_command(cmd: np.ndarray, h: float, delay: float) -> tuple[np.ndarray, np.ndarray, float]:
    """The held command delayed by ``delay`` = (n + f) h over [t_k, t_k + h): cmd[k - n - 1] for
    the first f h, then cmd[k - n]. Returns (earlier, later, f)."""
    n = int(math.floor(delay / h + 1e-12))
    f = delay / h - n
    k = np.arange(len(cmd))
    later = cmd[np.clip(k - n, 0, None)]
    if f <= 1e-12:
        return later, later, 0.0
    return cmd[np.clip(k - n - 1, 0, None)], later, f


def step_pieces(cmd: np.ndarray, h: float, time_constant: float, rate_limit: float,
                delay: float) -> list[tuple[np.ndarray, float, float]]:
    """The pieces of each sample step on which the delayed held command is constant (one, or two
    when the delay is not a whole number of samples), each (command, alpha, r s) with
    alpha = 1 - exp(-s/tau) for the piece's length s."""
    earlier, later, f = delayed_command(np.asarray(cmd, float), h, delay)
    tau = max(time_constant, 1e-4)
    pieces = [(later, h)] if f == 0.0 else [(earlier, f * h), (later, (1.0 - f) * h)]
    return [(c, 1.0 - math.exp(-s / tau), rate_limit * s) for c, s in pieces]


def simulate(cmd: np.ndarray, h: float, time_constant: float, deadband: float, rate_limit: float,
             delay: float, delta0: float) -> np.ndarray:
    """delta <- delta + clip(alpha dz(c - delta, D), -r s, r s), alpha = 1 - exp(-s/tau): the exact
    step of length s of ddelta/dt = dz(c - delta, D)/tau away from the limits, taken over each
    piece of the interval on which the delayed held command is constant (two pieces when the
    delay is not a whole number of samples, so a step of the command lands at its true time)."""
    steps = [(c.tolist(), alpha, move_max) for c, alpha, move_max in step_pieces(cmd, h, time_constant, rate_limit,
                                                                                  delay)]
    out = [0.0] * len(steps[0][0])
    d = float(delta0)
    for k in range(len(out)):
        out[k] = d
        for c, alpha, move_max in steps:
            e = c[k] - d
            if e > deadband:
                e -= deadband
            elif e < -deadband:
                e += deadband
            else:
                continue
            m = alpha * e
            d += move_max if m > move_max else (-move_max if m < -move_max else m)
    return np.asarray(out)
