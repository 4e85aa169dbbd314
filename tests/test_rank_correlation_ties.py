"""Spearman's correlation with tied values: each tie takes the mean of the ranks it spans
(rho = Pearson's correlation of the ranks, ties averaged). Ranks handed out to ties in the order of
the samples make every pair of tied stretches rise together in time, a correlation of their order,
not of the values: a skid-steer standing still most of the log (its command exactly 0, its gyro reading
exactly 0 through its deadband) then hides a gyro counted clockwise."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.measurements.direction import rank_correlation


def stops_and_turns(seed: int = 1, n: int = 6000) -> tuple[np.ndarray, np.ndarray]:
    """(gyro r, command u): 50-row stretches, 8 of 10 standing (u = r = 0 exactly), the others turning
    at u = +-1 with the gyro counted clockwise, r = -0.3 u + noise (truth: r and u turn against each other)."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.choice([0] * 8 + [1, -1], size=n // 50), 50).astype(float)
    r = np.where(u == 0, 0.0, -0.3 * u + 0.05 * rng.standard_normal(n))
    return r, u


def test_tied_stops_do_not_hide_a_gyro_that_turns_against_its_input():
    r, u = stops_and_turns()
    assert np.corrcoef(r, u)[0, 1] < -0.95                           # the values say so plainly
    assert rank_correlation(r, u) < -0.95


def test_ties_take_their_mean_rank():
    a = np.array([0.0, 0.0, 0.0, 1.0, 2.0, 3.0])
    b = np.array([5.0, 6.0, 7.0, 1.0, 2.0, 3.0])                # within the tie, b rises with the sample order
    ra = np.array([2.0, 2.0, 2.0, 4.0, 5.0, 6.0])
    rb = np.array([4.0, 5.0, 6.0, 1.0, 2.0, 3.0])
    assert rank_correlation(a, b) == pytest.approx(np.corrcoef(ra, rb)[0, 1], abs=1e-12)
