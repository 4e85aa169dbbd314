"""A steady signal whose only variation is floating-point rounding has no spikes: a counter's rate
at a steady speed (ticks over intervals of 0.01 s that are not exact in binary) differs from its
median by 1e-13 of itself, which a MAD of 0 made a threshold of 0. A true glitch on the same
signal is still found."""
from __future__ import annotations

import numpy as np

from agrobot.measurements.quirks import spikes


def _steady_rate(n: int = 200) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(n) * 0.01
    ticks = np.arange(n, dtype=float)
    return 0.5 * (t[1:] + t[:-1]), np.diff(ticks) / np.diff(t) * 0.01      # 1 m/s, rounding only


def test_rounding_of_a_steady_rate_is_no_spike():
    t, v = _steady_rate()
    assert np.ptp(v) > 0                       # the rounding is there
    assert len(spikes(t, v)) == 0


def test_a_glitch_on_a_steady_rate_is_still_a_spike():
    t, v = _steady_rate()
    v[100] = 40.0
    assert list(spikes(t, v)) == [100]
