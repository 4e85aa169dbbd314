"""The steering map between the angle a log reads (the command and the potentiometer) and the
angle the road wheels turn: the pointwise transforms of the diagnosis's effects present (Effect.wheel_angle
with ``pointwise``; the map effects steering_gain, steering_asymmetry, steering_ratio_curve set

    g = k r (1 + a sign r),    wheels = M(r) = g (1 + c g^2)

for a reading r, a gain k, a left/right asymmetry a and a ratio curve c [1/rad2]), in their order,
as the yaw stage's wheel angle (replay.wheel_angle_input) applies them.

The steering actuator moves the wheels: its rate limit is a wheel rate (the pump's flow per
radian of the wheels, paper section II) and its dead-band a wheel angle. Read through a map
that is off, the log sees the rate as r_wheels / M'(r): a gain error of 1.2 looks like a pump
20 % short of flow, an asymmetry like a rate that differs left and right, a curve like one that
falls in tight turns. The steering stage is therefore replayed in wheel angles, the command and
the start mapped through M, and read back through M^-1 (``mapped_steering``); the offset cancels
(the loop closes on a difference of angles).
"""
from __future__ import annotations

from typing import Callable, Mapping

import numpy as np

from .catalogue import CATALOGUE
from .replay import steering_replay


def steering_map(v: Mapping[str, float]) -> Callable[[np.ndarray], np.ndarray] | None:
    """M under ``v``: the pointwise transforms of the effects present, in their order; None where
    each is absent at ``v`` (Effect.wheel_angle returns None: the identity map)."""
    probe = np.array([0.1, -0.1])
    maps = [e for e in CATALOGUE.transforms(v, pointwise=True) if e.wheel_angle(probe, v, None) is not None]

    def M(r: np.ndarray) -> np.ndarray:
        for effect in maps:
            r = effect.wheel_angle(r, v, None)
        return r

    return M if maps else None


def reading_of(wheels: np.ndarray, M: Callable[[np.ndarray], np.ndarray], span: float) -> np.ndarray:
    """M^-1(wheels): the reading that turns the wheels to ``wheels``, by interpolation in M
    tabulated over readings within +-``span`` [rad]; where M stops rising (a curve c < 0 beyond
    1 + 3 c g^2 = 0) the table holds its largest value (no reading turns the wheels further)."""
    r = np.linspace(-span, span, 2001)
    m = M(r)
    m = np.maximum.accumulate(m)
    return np.interp(wheels, m, r)


def mapped_steering(cmd: np.ndarray, h: float, v: Mapping[str, float], delta0: float,
                    kernel: str = "auto") -> np.ndarray:
    """The steering stage's reading under ``v``: the first-order equivalent (replay.steering_replay)
    run in wheel angles from M(delta_cmd) and M(delta0), read back through M^-1; the plain replay
    when ``v`` sets the identity map."""
    M = steering_map(v)
    if M is None:
        return steering_replay(cmd, h, v, delta0, kernel)
    wheels = steering_replay(M(np.asarray(cmd, float)), h, v, float(M(np.array(delta0))), kernel)
    span = 1.5 * max(float(np.max(np.abs(cmd), initial=0.0)), abs(delta0), 1e-3)
    return reading_of(wheels, M, span)
