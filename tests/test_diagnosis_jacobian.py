"""The diagnosis' fits take their Jacobian from one batched replay of every stepped parameter set
(identification.driving.forward_jacobian); it must be the Jacobian scipy's least_squares builds
itself with diff_step=1e-3 (optimize._numdiff.approx_derivative, one replay per column), so the
fits land where they did."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize._numdiff import approx_derivative

from agrobot.diagnosis.baseline import baseline_from_study
from agrobot.diagnosis.candidates import Replay, _fit
from agrobot.diagnosis.catalogue import UNCERTAIN
from agrobot.identification.driving import forward_jacobian
from harness.truth_tractor import make_log
from agrobot.orchestrator.study import load_study

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def replay():
    frame, _ = make_log(11, "tyre_saturation", duration=60.0)
    return Replay(frame, baseline_from_study(load_study(ROOT / "studies" / "figure8.toml")))


# scaled values: a negative one (scipy steps it down), one at zero (scipy's sqrt(eps) fallback),
# one a step below its upper bound (stepped back), the relaxation lengths per row of the batch
FREE = {"tyre_friction": (0.9, 0.1, 2.0, 0.3), "tyre_shape": (1.3, 1.0, 1.9, 1.0),
        "cornering_front_scale": (1.1, 0.4, 1.1005, 1.0), "relaxation_scale": (1.2, 0.3, 3.0, 1.0),
        "steer_angle_offset": (-0.4, -3.0, 3.0, 0.01), "yaw_rate_bias": (0.0, -2.0, 2.0, 0.01)}


def _problem(replay):
    base = dict(replay.baseline.values)
    names = list(FREE)
    x = np.array([FREE[k][0] for k in names])
    lo, hi = np.array([FREE[k][1] for k in names]), np.array([FREE[k][2] for k in names])

    def values_of(xi):
        return {**base, **{k: float(v) * FREE[k][3] for k, v in zip(names, xi)}}

    def fun(xi):
        return replay.residuals("yaw", values_of(xi), "fit")

    def many(points):
        return replay.residuals_many("yaw", [values_of(p) for p in points], "fit")

    return x, lo, hi, fun, many


def test_batched_jacobian_equals_scipys_own_finite_differences(replay):
    x, lo, hi, fun, many = _problem(replay)
    f0 = fun(x)
    J = forward_jacobian(many, x, lo, hi, rel_step=1e-3, f0=f0)
    reference = approx_derivative(fun, x, method="2-point", rel_step=1e-3, f0=f0, bounds=(lo, hi))
    assert J.shape == reference.shape == (len(f0), len(x))
    scale = np.linalg.norm(reference, axis=0)
    assert np.all(scale > 0)
    # a step of the other sign differs by 4e-7 of a column (the offset, nearly linear), of another size
    # by 1e-4 to 1e-3; the same steps agree to rounding (here exactly)
    assert np.max(np.linalg.norm(J - reference, axis=0) / scale) < 1e-9
    # laid out as scipy's (column-major): least_squares' products with it then sum in the same order (a
    # fit ending near a bound, where the steps are 1e-12, moved by 1e-8 with a row-major copy)
    assert J.flags.f_contiguous == reference.flags.f_contiguous and J.strides == reference.strides
    # without f0 the base point rides in the same batch
    assert np.max(np.linalg.norm(forward_jacobian(many, x, lo, hi) - reference, axis=0) / scale) < 1e-9


def test_one_batched_replay_equals_one_replay_per_set(replay):
    """Sets that differ in every kind of parameter, the saturated yaw rate and the linear one
    mixed: the batch gives each the residuals its own replay gives."""
    x, lo, hi, fun, many = _problem(replay)
    points = [x, x * np.array([1.2, 1, 1, 1, 1, 1]), x * np.array([1, 1, 0.9, 1.5, 1, 1]), x + 0.05]
    batched = many(points)
    for p, r in zip(points, batched):
        np.testing.assert_allclose(r, fun(p), rtol=0, atol=1e-12 * np.max(np.abs(fun(p))))
    linear = {**replay.baseline.values, "tyre_friction": math.inf}
    saturated = {**replay.baseline.values, "tyre_friction": 0.5}
    for v, r in zip((linear, saturated), replay.residuals_many("yaw", [linear, saturated], "fit", "test")):
        for a, b in zip(r, replay.residuals("yaw", v, "fit", "test")):
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)


def test_fit_with_the_batched_jacobian_lands_where_scipys_own_does(replay, monkeypatch):
    """The same fits with scipy's internal finite differences (jac dropped, diff_step=1e-3): the
    yaw stage's stiffnesses, and the steering's dead-band with its time constant."""
    import agrobot.diagnosis.weighted_search as search
    from agrobot.diagnosis.fit_memo import forget
    from agrobot.diagnosis.catalogue import CATALOGUE

    deadband = next(e for e in CATALOGUE if e.id == "steering_deadband").parameters
    problems = [(list(UNCERTAIN["yaw"][:2]), ("yaw",), {"yaw": 0.01}),
                (list(deadband) + list(UNCERTAIN["steering"]), ("steering",), {"steering": 0.002})]
    start = {**replay.baseline.values}
    ours = [_fit(replay, start, free, stages, [{}], sigma) for free, stages, sigma in problems]
    real = search.least_squares

    def scipy_own(fun, x0, jac=None, **kw):
        return real(fun, x0, diff_step=1e-3, **kw)

    monkeypatch.setattr(search, "least_squares", scipy_own)
    forget(replay)                                    # searched again, not recalled
    for fit, (free, stages, sigma) in zip(ours, problems):
        theirs = _fit(replay, start, free, stages, [{}], sigma)
        for p in free:
            assert fit.values[p.name] == pytest.approx(theirs.values[p.name], rel=1e-10, abs=1e-15)
            assert fit.std(p.name) == pytest.approx(theirs.std(p.name), rel=1e-8, nan_ok=True)
        assert fit.rss[stages[0]] == pytest.approx(theirs.rss[stages[0]], rel=1e-12)


def test_recursions_side_by_side_equal_each_alone():
    from agrobot.diagnosis.replay import blocked_recursion

    rng = np.random.default_rng(3)
    R, N, n, m = 3, 997, 3, 5
    A = 0.9 * np.eye(n) + 0.1 * rng.standard_normal((R, N, n, n)) / np.sqrt(n)
    b = rng.standard_normal((R, N, n, m))
    for row in (1, (1, 0)):
        together = blocked_recursion(A, b, row)
        for r in range(R):
            np.testing.assert_array_equal(together[r], blocked_recursion(A[r], b[r], row))


def test_linear_yaw_sets_replayed_together_equal_each_alone(replay):
    """The linear yaw model under sets that differ in the values it is nonlinear in, with the
    measured wheel angle and with a shifted one (the steering clock): one batched recursion."""
    base = {**replay.baseline.values, "tyre_friction": math.inf}
    sets = [{**base, "cornering_front_scale": 1.0 + 0.01 * i, "relaxation_scale": 1.0 + 0.02 * i,
             "steering_clock": 0.02 * (i % 2)} for i in range(4)]
    replay.yaw._cache.clear()
    together = replay.residuals_many("yaw", sets, "fit", "test")
    assert len(replay.yaw._cache) >= 2 * len(sets)
    for v, r in zip(sets, together):
        replay.yaw._cache.clear()
        for a, b in zip(r, replay.residuals("yaw", v, "fit", "test")):
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * np.max(np.abs(b)))
