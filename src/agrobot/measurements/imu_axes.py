"""An IMU's vertical axis, told by its accelerometer: the axis that carries gravity.

A resting accelerometer reads the specific force of its support, +g along the axis that points
up (REP 103: a level IMU reads about +9.81 m/s^2 on z). Over a drive the vehicle's own
accelerations average out, so the mean reading of each axis names the vertical one: an IMU
mounted on its side (a Husky's with y up, a logger with x up) reads gravity on x or y, and its
yaw rate is that axis's angular velocity, signed as the reading (an axis reading -g points down).

The axis is named only on clear evidence: its mean within GRAVITY_BAND of g and each other mean
below LEVEL_SHARE of g; otherwise no decision (an accelerometer without gravity, a tilted mount).
"""
from __future__ import annotations

import math

import numpy as np

GRAVITY = 9.80665          # m/s^2, standard gravity
GRAVITY_BAND = (0.75, 1.25)  # the vertical axis's mean reading, in g
LEVEL_SHARE = 0.35         # each other axis's mean reading at most this, in g
AXES = ("x", "y", "z")


def vertical_axis(readings: dict[str, np.ndarray]) -> tuple[str, float, dict[str, float]] | None:
    """(axis, sign, mean reading per axis [m/s^2]) of the axis carrying gravity, from the
    accelerometer's readings per axis ('x', 'y', 'z'); None without clear evidence."""
    means = {a: float(np.nanmean(readings[a])) for a in AXES if a in readings and np.isfinite(readings[a]).any()}
    if len(means) < 3:
        return None
    axis = max(means, key=lambda a: abs(means[a]))
    lo, hi = GRAVITY_BAND
    if not lo * GRAVITY <= abs(means[axis]) <= hi * GRAVITY:
        return None
    if any(abs(m) > LEVEL_SHARE * GRAVITY for a, m in means.items() if a != axis):
        return None
    return axis, math.copysign(1.0, means[axis]), means


def describe(topic: str, axis: str, sign: float, means: dict[str, float]) -> str:
    """The reader's note for a yaw rate taken from a vertical axis other than z."""
    readings = ", ".join(f"{a} {m:+.2f}" for a, m in means.items())
    return (f"yaw_rate: {'-' if sign < 0 else ''}{topic}.angular_velocity.{axis}: the IMU's vertical axis is {axis}, "
            f"not z (its accelerometer reads gravity there: mean linear_acceleration {readings} m/s^2); "
            f"--signal yaw_rate={topic}.angular_velocity.z keeps z")
