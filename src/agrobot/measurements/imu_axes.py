"""An IMU's vertical axis, told by its accelerometer: the axis that carries gravity.

A resting accelerometer reads the specific force of its support, +g along the axis that points
up (REP 103: a level IMU reads about +9.81 m/s^2 on z). Over a drive the vehicle's own
accelerations average out, so the mean reading of each axis names the vertical one: an IMU
mounted on its side (a Husky's with y up, a logger with x up) reads gravity on x or y, and its
yaw rate is that axis's angular velocity, signed as the reading (an axis reading -g points down).

The axis is named only on clear evidence: its mean within GRAVITY_BAND of g and each other mean
below LEVEL_SHARE of g; otherwise no decision (an accelerometer without gravity, a tilted mount).

Any reader whose yaw rate is one axis of a set (a CAN message's ``AngularRateZ`` beside
``AccelerationX/Y/Z``, a table's ``gyro_z`` beside ``acc_x/y/z``): axis_siblings finds the
accelerometer's channels by their names, and axis_check names a yaw rate mapped from an axis that
is not the vertical one (the report's ``imu_axes``; the audit makes it a finding).
"""
from __future__ import annotations

import math
import re

import numpy as np

from .findings import finding

GRAVITY = 9.80665          # m/s^2, standard gravity
GRAVITY_BAND = (0.75, 1.25)  # the vertical axis's mean reading, in g
LEVEL_SHARE = 0.35         # each other axis's mean reading at most this, in g
AXES = ("x", "y", "z")
AXIS_NAME = re.compile(r"^(?P<stem>.*?)[_ .]?(?P<axis>[xyz])$", re.I)
RATE_STEM = re.compile(r"rate|gyro|angular|omega|rot", re.I)
ACCEL_STEM = re.compile(r"acc", re.I)


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


def axis_siblings(rate: str, names: list[str]) -> tuple[str, dict[str, str]] | None:
    """(the rate's axis, {axis: accelerometer channel}) when ``rate`` names one axis of an angular
    rate (``...RateZ``, ``gyro_z``) and ``names`` hold an accelerometer channel for each of x, y, z
    (``AccelerationX``, ``acc_x``); None otherwise."""
    m = AXIS_NAME.match(rate)
    if not m or not RATE_STEM.search(m["stem"]):
        return None
    accel = {}
    for n in names:
        a = AXIS_NAME.match(n)
        if a and ACCEL_STEM.search(a["stem"]) and not RATE_STEM.search(a["stem"]):
            accel.setdefault(a["axis"].lower(), n)
    return (m["axis"].lower(), accel) if set(accel) == set(AXES) else None


def axis_check(column: str, rate: str, axis: str, accel: dict[str, str], readings: dict[str, np.ndarray],
               scale: float = 1.0) -> dict | None:
    """The report's ``imu_axes`` entry when ``column`` (a yaw rate read from ``rate``, one axis of
    an IMU) is not the axis whose accelerometer ``readings`` (per axis, x ``scale`` to m/s^2) carry
    gravity: {column, mapped, mapped_axis, vertical, sign, means, use}; None when it is, or
    without clear evidence (vertical_axis)."""
    found = vertical_axis({a: np.asarray(x, float) * scale for a, x in readings.items()})
    if found is None or found[0] == axis:
        return None
    up, sign, means = found
    m = AXIS_NAME.match(rate)
    cut = m.start("axis")
    use = rate[:cut] + (up.upper() if rate[cut].isupper() else up) + rate[cut + 1:]
    return {"column": column, "mapped": rate, "mapped_axis": axis, "vertical": up, "sign": sign,
            "means": {accel[a]: means[a] for a in AXES}, "use": ("-" if sign < 0 else "") + use}


def axis_findings(report: dict) -> list[dict]:
    """A ``mislabelled_channel`` finding per yaw rate mapped from an axis that is not the vertical
    one (report["imu_axes"], axis_check): unresolved, with the mapping that reads the vertical axis."""
    out = []
    for c in report.get("imu_axes") or []:
        readings = ", ".join(f"{n} {m:+.2f}" for n, m in c["means"].items())
        out.append(finding("mislabelled_channel", [c["column"]], max(abs(m) for m in c["means"].values()), None,
                           "m/s^2", f"{c['column']} reads {c['mapped']} (the IMU's {c['mapped_axis']} axis), but the "
                           f"IMU's vertical axis is {c['vertical']}: its accelerometer reads gravity there (mean "
                           f"{readings} m/s^2), so {c['mapped']} is a roll or pitch rate, not the yaw rate; "
                           f"--signal {c['column']}={c['use']} (with its unit) reads the vertical axis"))
    return out
