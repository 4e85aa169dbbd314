"""Glitch bursts at high sample rates: runs of a few rows at a sensor's range end, each edge in one
sample, shorter than 0.15 s (5 rows at 40 Hz), are spikes; a real turn of the same size is not, nor a
run as long at 10 Hz (0.5 s, which a light robot's spin can last)."""
from __future__ import annotations

import numpy as np

from agrobot.measurements.quirks import spikes


def yaw(rate: float, seconds: float = 60.0, seed: int = 2):
    """A yaw rate turning +-0.3 rad/s every few seconds with 0.01 rad/s of noise, at `rate` Hz."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, 1.0 / rate)
    return t, 0.3 * np.sin(2 * np.pi * t / 7.0) + rng.normal(0, 0.01, len(t))


def test_bursts_of_five_rows_at_40_hz_are_spikes():
    t, r = yaw(40.0)
    planted = []
    for start, width in ((400, 4), (1100, 5), (1700, 5), (2100, 4)):
        r[start:start + width] = 9.0 + 0.05 * np.arange(width)
        planted += list(range(start, start + width))
    assert sorted(spikes(t, r).tolist()) == planted


def test_a_real_turn_and_a_slow_rate_burst_are_kept():
    t, r = yaw(40.0)
    r[800:840] += 1.0                        # a 1 s turn (40 rows): a step that holds, not a glitch
    assert len(spikes(t, r)) == 0
    t10, r10 = yaw(10.0)
    r10[300:305] = 2.0                       # 5 rows at 10 Hz: a 0.5 s spin, possible for a light robot
    assert len(spikes(t10, r10)) == 0
