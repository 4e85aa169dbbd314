"""The gyro filter's time constant from a gyro the import interpolated from its own, slower samples.

Truth: generated tractor logs (harness.truth_tractor.make_log, 45 s, rows at 50 Hz) whose yaw rate is
read through a first-order low-pass of known time constant (hidden_effects.filtered_gyro, integrated
exactly on a 1 ms grid), then sampled at 10 Hz on jittered stamps (30 % of an interval) and
interpolated back onto the rows (harness.own_stamps), as a recording's import gives it. Fitted on
the yaw stage after the baseline's refit (diagnosis.candidates): each seed's 95 % interval holds the
truth, and the estimates are unbiased -- their mean within two standard errors (their own) of it.
Read without the gyro's own samples (the interpolation smooths the measurement, not the model), the
eight estimates' mean is 0.0975 s, 2.5 standard errors low (0.0993 read at them)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from agrobot.diagnosis.candidates import Replay, fit_baseline, fitted, refit_free
from agrobot.diagnosis.catalogue import CATALOGUE
from agrobot.diagnosis.pipeline import baseline_from_study, load_study
from harness.hidden_effects import BASELINES, filtered_gyro
from harness.own_stamps import on_own_stamps
from harness.truth_tractor import make_log

TAU, GYRO_HZ, SEEDS = 0.1, 10.0, range(8)
FILTER = next(e for e in CATALOGUE if e.id == "gyro_filter")


def estimate(seed: int) -> tuple[float, float]:
    """(tau_g fitted, its standard deviation) on one generated log."""
    frame, _ = make_log(seed, None, duration=45.0, rate=50.0)
    frame, _ = on_own_stamps(filtered_gyro(frame, TAU).drop(columns=["x", "y"]), {("yaw_rate",): (GYRO_HZ, 0.0)},
                             seed=100 + seed)
    replay = Replay(frame, baseline_from_study(load_study(BASELINES["tractor"])))
    assert replay.yaw_sampling is not None
    base, sigma = fit_baseline(replay)
    fit = fitted(replay, base.values, refit_free(replay, ("yaw",), [FILTER]), ("yaw",),
                 [{"gyro_time_constant": 0.05}], sigma)
    return fit.values["gyro_time_constant"], fit.std("gyro_time_constant")


@pytest.fixture(scope="module")
def estimates():
    return [estimate(seed) for seed in SEEDS]


def test_each_interval_holds_the_time_constant(estimates):
    assert all(abs(v - TAU) <= 1.96 * sd for v, sd in estimates), estimates


def test_the_estimate_is_unbiased(estimates):
    values, sds = np.array(estimates).T
    standard_error = math.sqrt(float(np.sum(sds ** 2))) / len(sds)
    assert abs(values.mean() - TAU) <= 2 * standard_error, (values.mean(), standard_error, estimates)
