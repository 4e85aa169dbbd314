"""The yaw replay's first-order hold (diagnosis.replay.first_order_hold, low_pass): the inputs linear
between the samples, so a vehicle whose yaw follows the wheels within a row replays without lag.

(1) The discretisation against independent integrations of an input linear over the step: a stiff
ODE solver (scipy solve_ivp, Radau, tolerances 1e-12) on a stable system, in Python and in C; the
gyro's filter against the closed form of a ramp through tau y' = x - y.
(2) The gyro filter's time constant on the small Ackermann machine (harness.truth_tractor
VEHICLES["small_ackermann"], yaw time constant well under a 20 Hz row), its yaw rate read through a
first-order low-pass of 0.05 s integrated on a 1 ms grid (hidden_effects.filtered_gyro), fitted on
the yaw stage after the baseline's refit: the mean of six seeds within two standard errors of the
truth. Held at the mean of the two samples around each step, the replay lagged up to half a row
and the filter's fit shrank to absorb it: 0.0225 s (standard error 0.0013) for the truth's 0.05 s."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from agrobot.diagnosis import replay_kernels
from agrobot.diagnosis.candidates import Replay, fit_baseline, fitted, refit_free
from agrobot.diagnosis.catalogue import CATALOGUE
from agrobot.diagnosis.pipeline import baseline_from_study, load_study
from agrobot.diagnosis.replay import first_order_hold, low_pass
from harness.hidden_effects import filtered_gyro
from harness.truth_tractor import make_log
from harness.vehicle_classes import study

TAU, SEEDS = 0.05, range(6)
FILTER = next(e for e in CATALOGUE if e.id == "gyro_filter")


def kernels():
    yield "python"
    if replay_kernels.choose("auto") == "c":
        yield "c"


@pytest.mark.parametrize("kernel", list(kernels()))
def test_the_hold_is_the_integral_of_a_linear_input(kernel):
    rng = np.random.default_rng(4)
    n, p, h = 3, 2, 0.05
    A = np.array([[-40.0, 5.0, 0.0], [-3.0, -2.0, 1.0], [0.0, -8.0, -0.5]]) + rng.normal(0, 0.3, (n, n))
    B = rng.standard_normal((n, p))
    x0, u0, u1 = rng.standard_normal(n), rng.standard_normal(p), rng.standard_normal(p)
    ode = solve_ivp(lambda s, x: A @ x + B @ (u0 + (u1 - u0) * s / h), (0.0, h), x0, method="Radau",
                    rtol=1e-12, atol=1e-14)
    Phi, G0, G1 = (x[0] for x in first_order_hold(A[None], B[None], h, kernel))
    assert np.allclose(Phi @ x0 + G0 @ u0 + G1 @ u1, ode.y[:, -1], rtol=0, atol=1e-9)
    assert np.abs(G1 @ (u1 - u0)).max() > 1e-3          # the slope within the step matters


def test_the_gyro_filter_follows_a_ramp_exactly():
    """x = t from rest: y = t - tau (1 - exp(-t / tau)), whatever the step."""
    for h, tau in ((0.05, 0.02), (0.05, 0.3), (0.01, 0.05)):
        t = np.arange(200) * h
        assert np.allclose(low_pass(t, h, tau), t - tau * (1.0 - np.exp(-t / tau)), rtol=0, atol=1e-12)


def estimate(seed: int, base_study) -> tuple[float, float]:
    """(tau_g fitted, its standard deviation) on one generated log, rows at 20 Hz."""
    frame, _ = make_log(seed, None, duration=45.0, vehicle="small_ackermann", rate=20.0)
    replay = Replay(filtered_gyro(frame, TAU).drop(columns=["x", "y"]), base_study)
    base, sigma = fit_baseline(replay)
    fit = fitted(replay, base.values, refit_free(replay, ("yaw",), [FILTER]), ("yaw",),
                 [{"gyro_time_constant": 0.05}], sigma)
    return fit.values["gyro_time_constant"], fit.std("gyro_time_constant")


def test_the_gyro_filter_is_read_without_the_rows_lag(tmp_path):
    base_study = baseline_from_study(load_study(study(tmp_path)))
    values, sds = np.array([estimate(seed, base_study) for seed in SEEDS]).T
    standard_error = math.sqrt(float(np.sum(sds ** 2))) / len(sds)
    assert abs(values.mean() - TAU) <= 2 * standard_error, (values, sds)
