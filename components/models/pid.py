"""Discrete PID law used by the cascaded speed controller and the steering's low-level PI.

u_k = kp e_k + clamp(I_k) + kd (e_k - e_{k-1})/dt,   I_{k+1} = clamp(I_k + ki e_k dt),
u saturated to [u_min, u_max]; the integral is clamped to +-integral_limit (anti-windup) and
frozen while the output saturates in the direction of the error.
"""
from __future__ import annotations

import math


class DiscretePID:
    __slots__ = ("kp", "ki", "kd", "u_min", "u_max", "integral_limit", "integral", "prev_error")

    def __init__(self, kp: float, ki: float, kd: float, u_min: float = -math.inf,
                 u_max: float = math.inf, integral_limit: float = math.inf) -> None:
        self.kp, self.ki, self.kd = kp, ki, kd
        self.u_min, self.u_max, self.integral_limit = u_min, u_max, integral_limit
        self.integral = 0.0
        self.prev_error: float | None = None

    def reset(self) -> None:
        self.integral = 0.0
        self.prev_error = None

    def update(self, error: float, dt: float, offset: float = 0.0) -> float:
        deriv = 0.0 if self.prev_error is None or self.kd == 0.0 else (error - self.prev_error) / dt
        self.prev_error = error
        raw = offset + self.kp * error + self.integral + self.kd * deriv
        u = min(max(raw, self.u_min), self.u_max)
        saturated_same_way = (raw > self.u_max and error > 0) or (raw < self.u_min and error < 0)
        if not saturated_same_way:
            lim = self.integral_limit
            self.integral = min(max(self.integral + self.ki * error * dt, -lim), lim)
        return u
