"""The linear range's std where the rear axle bends first: |a_y| = g mu_f rho share(C), whose std by the
delta method is sqrt(grad' Cov grad) over the fit's covariance of mu_f, rho and C (FitResult.interval_of).
A log that bends the rear alone sees mu_r = rho mu_f well and mu_f and rho each poorly, strongly
anticorrelated: read as independent, the range's std is ten times what the fit says.

Truth: a hand-made fit, mu_f 1.0 +- 0.2, rho 0.7 +- 0.14, their correlation -0.99, the shape held."""
from __future__ import annotations

import math

import numpy as np
import pytest

from agrobot.components.models.tyre import linear_share_limit
from agrobot.components.models.yaw_dynamics import GRAVITY
from agrobot.estimation import FitResult
from agrobot.identification.axle_friction import friction_ratio
from agrobot.identification.ordinary_driving import _linear_range, free_parameters
from agrobot.identification.vehicle import Vehicle

MU, RHO, SHAPE = 1.0, 0.7, 1.3
SD_MU, SD_RHO, CORR = 0.2, 0.14, -0.99


def fit() -> FitResult:
    free = [*free_parameters(Vehicle(kind="scale_car"), False, False, saturation=True), friction_ratio()]
    names = [q.name for q in free]
    cov = np.zeros((len(free), len(free)))
    i, j = names.index("friction"), names.index("friction_ratio")
    cov[i, i], cov[j, j], cov[i, j] = SD_MU ** 2, SD_RHO ** 2, CORR * SD_MU * SD_RHO
    cov[j, i] = cov[i, j]
    values = {q.name: 0.5 * (q.lower + q.upper) for q in free} | {"friction": MU, "friction_ratio": RHO, "shape": SHAPE, "c_f": 8.0, "c_r": 30.0}
    return FitResult(values, tuple(free), cov, {"yaw": 1.0}, {"yaw": 1000}, {"yaw": 500.0})


def test_the_rear_bends_first_and_its_range_std_takes_the_covariance():
    got = _linear_range(True, fit(), None, 0.5)
    share = linear_share_limit(SHAPE)
    grad = np.array([RHO, MU]) * GRAVITY * share               # d/d mu_f, d/d rho of g mu_f rho share
    cov = np.array([[SD_MU ** 2, CORR * SD_MU * SD_RHO], [CORR * SD_MU * SD_RHO, SD_RHO ** 2]])
    assert "rear axle" in got["how"]
    assert got["value"] == pytest.approx(GRAVITY * MU * RHO * share)
    assert got["std"] == pytest.approx(math.sqrt(grad @ cov @ grad), rel=1e-6)
