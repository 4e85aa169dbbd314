"""The steering map: the potentiometer's map from its reading to the road-wheel angle, the one
form every harness truth plants (Kayacan et al. section III: the wheels turn the reading's angle
when the map is right),

    wheels = M(reading) = k reading (1 + a sign(reading)) (1 + c reading^2) + o,

a gain k, a left/right asymmetry a (reading > 0 is left: (1 + a) k to the left, (1 - a) k to the
right), a curve c [1/rad2] and an offset o [rad]; and its inverse reading = M^-1(wheels). A log of a
machine whose map is off holds the reading M^-1 of the wheels the truth turned (``read_through``).

Drawn map effects (``draw_map``, for the diagnosis-rate benchmark), one parameter each:
``steering_map_gain`` k in 1 +- (0.05-0.30); ``steering_map_asymmetry`` a in 0.10-0.25 (a 1.13 m
against a 1.90 m radius at full lock is a = 0.25); ``steering_map_offset`` o = +-(0.03-0.045) rad x
the vehicle's steering scale; ``steering_map_curve`` c in 1.5-3 1/rad2 / the steering scale squared
(the same ratio change c delta^2 at each vehicle's angles: a car steered 1/20 of the tractor's angles
with c = 3 would turn 0.1 % more at its tightest, no fault to find).
"""
from __future__ import annotations

import math

import numpy as np

# the catalogue's id of each map effect (an asymmetry has none yet: the name a right diagnosis would give it)
MAP_IDS = {"steering_map_gain": "steering_gain", "steering_map_asymmetry": "steering_asymmetry",
           "steering_map_offset": "steering_offset", "steering_map_curve": "steering_ratio_curve"}
MAP_EFFECTS = tuple(MAP_IDS)


def wheel_angle(reading, gain: float = 1.0, asymmetry: float = 0.0, curvature: float = 0.0,
                offset: float = 0.0) -> np.ndarray:
    """M(reading): the road wheels' angle [rad] for a reading or command [rad]."""
    r = np.asarray(reading, float)
    return gain * r * (1.0 + asymmetry * np.sign(r)) * (1.0 + curvature * r * r) + offset


def reading(wheels, gain: float = 1.0, asymmetry: float = 0.0, curvature: float = 0.0,
            offset: float = 0.0):
    """M^-1(wheels): the reading [rad] that turns the wheels to ``wheels`` [rad] (an array, or a
    float for a float: the truth's integrators call it every step). With k > 0 and |a| < 1 the
    reading has the sign of wheels - o; r (1 + c r^2) = (wheels - o) / (k (1 + a sign)) is solved by
    Newton's method from r = that ratio (one root while 1 + 3 c r^2 > 0)."""
    if gain <= 0 or abs(asymmetry) >= 1:
        raise ValueError(f"the steering map must increase with the reading: gain {gain} > 0 and "
                         f"|asymmetry| {asymmetry} < 1 expected")
    scalar = np.ndim(wheels) == 0
    w = float(wheels) - offset if scalar else np.asarray(wheels, float) - offset
    side = (w > 0) - (w < 0) if scalar else np.sign(w)
    target = w / (gain * (1.0 + asymmetry * side))
    d = target
    for _ in range(60):
        step = (d + curvature * d ** 3 - target) / (1.0 + 3.0 * curvature * d * d)
        d = d - step
        if (abs(step) if scalar else np.max(np.abs(step), initial=0.0)) <= 1e-15:
            break
    miss = abs(d + curvature * d ** 3 - target) if scalar else np.max(np.abs(d + curvature * d ** 3 - target),
                                                                     initial=0.0)
    slope = 1.0 + 3.0 * curvature * d * d                    # M' / (k (1 + a sign)): the branch M increases on
    rising = (slope > 0 and d * target >= 0) if scalar else bool(np.all((slope > 0) & (d * target >= 0)))
    if not (miss <= 1e-9 and rising):
        raise ValueError(f"the steering map (curvature {curvature}) does not increase over the wheels' "
                         f"angles up to {math.degrees(float(np.max(np.abs(w)))):.1f} deg")
    return d


def read_through(frame, **planted):
    """The log as the machine with the map ``planted`` (wheel_angle's keywords) reads it: the
    command ``delta_cmd`` and the wheel angle ``delta`` become M^-1 of the truth's angles."""
    out = frame.copy()
    for col in ("delta_cmd", "delta"):
        if col in out:
            out[col] = reading(out[col].to_numpy(float), **planted)
    return out


def draw_map(effect: str, rng: np.random.Generator, steer_scale: float) -> dict:
    """The planted map of one drawn effect (module docstring), as wheel_angle's keywords."""
    sign = 1.0 if rng.random() < 0.5 else -1.0
    u = rng.uniform
    return {"steering_map_gain": {"gain": 1.0 + sign * u(0.05, 0.30)},
            "steering_map_asymmetry": {"asymmetry": u(0.10, 0.25)},
            "steering_map_offset": {"offset": sign * u(0.03, 0.045) * steer_scale},
            "steering_map_curve": {"curvature": u(1.5, 3.0) / steer_scale ** 2}}[effect]
