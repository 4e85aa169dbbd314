"""Two independent estimates of one quantity, side by side: the understeer gradient from the
dynamic fit and from steady states, the command-to-yaw delay from the fit and from a
cross-correlation, the gyro bias from the fit and from the GNSS course. Each pair is reported with
its intervals; intervals that do not overlap are flagged with what the disagreement suggests.
"""
from __future__ import annotations

import math

import numpy as np

from agrobot.estimation import compare

pair = compare           # the shared rule (agrobot.estimation.compare): intervals that overlap agree


def course_bias(t: np.ndarray, x: np.ndarray, y: np.ndarray, r: np.ndarray, v: np.ndarray,
                min_speed: float, chord: float = 1.0) -> tuple[float, float] | None:
    """(bias, std) of the gyro against the GNSS course: the course psi_c of 1 s chords of the
    track, b = mean(r - d psi_c / dt) where moving (the course turns with the body when the
    side-slip is steady); std from the spread over 20 s blocks. None without 60 s of moving track."""
    h = float(np.median(np.diff(t)))
    k = max(1, int(round(0.5 * chord / h)))
    if len(t) < 4 * k + 10:
        return None
    dx, dy = x[2 * k:] - x[:-2 * k], y[2 * k:] - y[:-2 * k]
    course = np.unwrap(np.arctan2(dy, dx))
    rate = np.gradient(course, h)
    ok = (np.hypot(dx, dy) > min_speed * 2 * k * h) & (v[k:-k] > min_speed)
    ok &= np.abs(rate) < 2.0
    if ok.sum() * h < 60.0:
        return None
    diff = (r[k:-k] - rate)[ok]
    block = max(2, int(round(20.0 / h)))
    means = [diff[i:i + block].mean() for i in range(0, len(diff) - block + 1, block)]
    sd = float(np.std(means) / math.sqrt(len(means))) if len(means) > 1 else math.nan
    return float(np.median(diff)), sd
