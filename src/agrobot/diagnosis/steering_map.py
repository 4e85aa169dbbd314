"""The steering map between the angle a log reads (the command and the potentiometer) and the
angle the road wheels turn, as the diagnosis's map effects (steering_gain, steering_asymmetry,
steering_ratio_curve) set it:

    g = k r (1 + a sign r),    wheels = M(r) = g (1 + c g^2)

for a reading r, a gain k, a left/right asymmetry a and a ratio curve c [1/rad2] (the yaw stage's
wheel angle, diagnosis.candidates.Replay.yaw_input, in the same order).

The steering actuator moves the wheels: its rate limit is a wheel rate (the pump's flow per
radian of the wheels, paper section II) and its dead-band a wheel angle. Read through a map
that is off, the log sees the rate as r_wheels / M'(r): a gain error of 1.2 looks like a pump
20 % short of flow, an asymmetry like a rate that differs left and right, a curve like one that
falls in tight turns. The steering stage is therefore replayed in wheel angles, the command and
the start mapped through M, and read back through M^-1 (``mapped_steering``); the offset cancels
(the loop closes on a difference of angles).
"""
from __future__ import annotations

from typing import Mapping

import numpy as np

from .replay import steering_replay

KEYS = ("steering_gain", "steering_asymmetry", "steering_ratio_curvature")
DEFAULTS = (1.0, 0.0, 0.0)


def map_of(v: Mapping[str, float]) -> tuple[float, float, float]:
    """(k, a, c) of ``v``, the identity's where ``v`` does not set them."""
    return tuple(float(v.get(key, d)) for key, d in zip(KEYS, DEFAULTS))


def wheel_angle(r: np.ndarray, k: float, a: float, c: float) -> np.ndarray:
    """M(r) [rad] of a reading or command r [rad] (module docstring)."""
    g = k * r * (1.0 + a * np.sign(r))
    return g * (1.0 + c * g * g)


def reading_of(wheels: np.ndarray, k: float, a: float, c: float, span: float) -> np.ndarray:
    """M^-1(wheels): the reading that turns the wheels to ``wheels``, by interpolation in M
    tabulated over readings within +-``span`` [rad]; where M stops rising (a curve c < 0 beyond
    1 + 3 c g^2 = 0) the table holds its largest value (no reading turns the wheels further)."""
    r = np.linspace(-span, span, 2001)
    m = wheel_angle(r, k, a, c)
    m = np.maximum.accumulate(m)
    return np.interp(wheels, m, r)


def mapped_steering(cmd: np.ndarray, h: float, v: Mapping[str, float], delta0: float,
                    kernel: str = "auto") -> np.ndarray:
    """The steering stage's reading under ``v``: the first-order equivalent (replay.steering_replay)
    run in wheel angles from M(delta_cmd) and M(delta0), read back through M^-1; the plain replay
    when ``v`` sets the identity map."""
    k, a, c = map_of(v)
    if (k, a, c) == DEFAULTS:
        return steering_replay(cmd, h, v, delta0, kernel)
    wheels = steering_replay(wheel_angle(np.asarray(cmd, float), k, a, c), h, v,
                             float(wheel_angle(np.array(delta0), k, a, c)), kernel)
    span = 1.5 * max(float(np.max(np.abs(cmd), initial=0.0)), abs(delta0), 1e-3)
    return reading_of(wheels, k, a, c, span)
