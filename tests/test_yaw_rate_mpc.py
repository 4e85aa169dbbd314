"""Yaw-rate MPC: the condensed prediction against a direct simulation, the QP against an exact
enumeration of active sets (and the other solver), constraints and offset-free tracking."""
from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from agrobot.components.models.condensed_mpc import CondensedTrackingMPC
from agrobot.components.models.yaw_dynamics import controllable_canonical, zoh_discretize, state_space, TractorParameters

DEG = math.pi / 180
DT = 0.05


def paper_mpc(solver="daqp"):
    return CondensedTrackingMPC([291.0], [1.0, 10.9, 242.0], DT, 8, 3, 0.5, 1.0, 45 * DEG, 55 * DEG * DT, solver)


def exact_qp(H, g, A, lower, upper, box):
    """Minimise 0.5 x'Hx + g'x s.t. lower <= A x <= upper, |x| <= box by enumerating active sets
    and keeping the feasible KKT point with non-negative multipliers (exact for small n)."""
    n = len(g)
    rows = [(np.eye(n)[i], box[i], 1.0) for i in range(n)] + [(-np.eye(n)[i], box[i], 1.0) for i in range(n)]
    rows += [(A[i], upper[i], 1.0) for i in range(len(upper))] + [(-A[i], -lower[i], 1.0) for i in range(len(lower))]
    G = np.array([r[0] for r in rows])
    h = np.array([r[1] for r in rows])
    best, best_val = None, math.inf
    for k in range(n + 1):
        for act in itertools.combinations(range(len(rows)), k):
            Ga = G[list(act)]
            if k and np.linalg.matrix_rank(Ga) < k:
                continue
            kkt = np.block([[H, Ga.T], [Ga, np.zeros((k, k))]]) if k else H
            rhs = np.concatenate([-g, h[list(act)]]) if k else -g
            sol = np.linalg.solve(kkt, rhs)
            x, lam = sol[:n], sol[n:]
            if np.all(G @ x <= h + 1e-9) and np.all(lam >= -1e-9):
                val = 0.5 * x @ H @ x + g @ x
                if val < best_val - 1e-12:
                    best, best_val = x, val
    return best


_EXACT: dict[bytes, np.ndarray] = {}


def exact_answer(qp) -> np.ndarray:
    """exact_qp of the instance, enumerated once for both solvers' tests (their instances are the same
    draws; an instance that differs in any entry is enumerated again)."""
    parts = (qp.H, qp.g, qp.A, qp.lower, qp.upper, qp.box)
    key = repr([np.shape(a) for a in parts]).encode() + b"".join(np.asarray(a, dtype=float).tobytes() for a in parts)
    if key not in _EXACT:
        _EXACT[key] = exact_qp(qp.H, qp.g, qp.A, qp.lower, qp.upper, qp.box)
    return _EXACT[key]


def test_prediction_matrices_equal_a_direct_simulation():
    mpc = paper_mpc()
    rng = np.random.default_rng(0)
    for _ in range(20):
        mpc.x = rng.normal(size=2) * 0.01
        mpc.u_prev = rng.uniform(-0.3, 0.3)
        du = rng.uniform(-0.05, 0.05, 3)
        # predicted outputs from the condensed form
        free = mpc.CApow @ mpc.x + mpc.step_response[1:] * mpc.u_prev
        Y = free + mpc.Phi @ du
        # direct simulation of the discrete model with u_{k+j} = u_prev + cumulative moves
        x, ys, u = mpc.x.copy(), [], mpc.u_prev
        for j in range(8):
            if j < 3:
                u += du[j]
            x = mpc.A @ x + mpc.B * u
            ys.append(float(mpc.C @ x))
        np.testing.assert_allclose(Y, ys, atol=1e-12)


def test_discretisation_matches_scipy_cont2discrete():
    from scipy.signal import cont2discrete

    A, B, C = controllable_canonical([291.0], [1.0, 10.9, 242.0])
    Ad, Bd = zoh_discretize(A, B, DT)
    Ad2, Bd2, *_ = cont2discrete((A, B.reshape(-1, 1), C.reshape(1, -1), np.zeros((1, 1))), DT, "zoh")
    np.testing.assert_allclose(Ad, Ad2, atol=1e-12)
    np.testing.assert_allclose(Bd, Bd2.ravel(), atol=1e-12)


@pytest.mark.parametrize("solver", ["daqp", "proxsuite"])
def test_qp_answers_match_exact_enumeration_on_random_instances(solver):
    rng = np.random.default_rng(42)
    mpc = paper_mpc(solver)
    worst, active = 0.0, 0
    for i in range(300):
        mpc.x = rng.normal(size=2) * rng.choice([0.001, 0.01, 0.05])
        mpc.u_prev = rng.uniform(-45, 45) * DEG
        r, y = rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5)
        qp = mpc.qp(r, y)
        x_solver, status = mpc._solve(qp)
        assert status > 0
        x_exact = exact_answer(qp)
        worst = max(worst, np.abs(x_solver - x_exact).max())
        active += np.any(np.isclose(np.abs(x_exact), qp.box)) or np.any(
            np.isclose(qp.A @ x_exact, qp.upper)) or np.any(np.isclose(qp.A @ x_exact, qp.lower))
    assert worst < 1e-6
    assert active > 150          # the instances really exercise the constraints


def test_closed_loop_honours_both_constraints():
    mpc = paper_mpc()
    A, B = zoh_discretize(*controllable_canonical([291.0], [1.0, 10.9, 242.0])[:2], DT)
    C = controllable_canonical([291.0], [1.0, 10.9, 242.0])[2]
    x, us = np.zeros(2), []
    for k in range(200):
        r = 2.5 if (k // 50) % 2 == 0 else -2.5        # far beyond what 45 deg can give
        u, status = mpc.step(r, float(C @ x))
        assert status > 0
        us.append(u)
        x = A @ x + B * u
    us = np.array(us)
    assert np.abs(us).max() <= 45 * DEG + 1e-9
    assert np.abs(np.diff(np.concatenate([[0.0], us]))).max() <= 55 * DEG * DT + 1e-9
    assert np.isclose(np.abs(us).max(), 45 * DEG)       # the bound is reached
    assert np.isclose(np.abs(np.diff(us)).max(), 55 * DEG * DT)


@pytest.mark.parametrize("speed", [1.0, 2.0, 3.0])
def test_no_steady_state_error_on_a_mismatched_plant(speed):
    """MPC built on G_2nd controlling the RLF physical model at another speed."""
    mpc = paper_mpc()
    A, B, C = state_space("rlf", TractorParameters(), speed)
    Ad, Bd = zoh_discretize(A, B, DT)
    x = np.zeros(3)
    for _ in range(200):
        u, _ = mpc.step(0.15, float(C @ x))
        x = Ad @ x + Bd * u
    assert float(C @ x) == pytest.approx(0.15, abs=1e-6)


def test_unconstrained_solution_equals_the_normal_equations():
    mpc = paper_mpc()
    mpc.x, mpc.u_prev = np.array([0.0001, 0.0002]), 0.05
    qp = mpc.qp(0.01, 0.02)
    du, _ = mpc._solve(qp)
    np.testing.assert_allclose(du, np.linalg.solve(qp.H, -qp.g), atol=1e-10)
    assert np.all(np.abs(du) < qp.box)


def test_folded_gradient_equals_the_prediction_form():
    """g = 2 Q Phi'(f - r) with f = CApow x + s u_prev + (y - C x), computed term by term."""
    mpc = paper_mpc()
    rng = np.random.default_rng(3)
    for _ in range(20):
        mpc.x, mpc.u_prev = rng.normal(size=2) * 0.01, rng.uniform(-0.5, 0.5)
        r, y = rng.uniform(-1, 1), rng.uniform(-1, 1)
        d = y - float(mpc.C @ mpc.x)
        f = mpc.CApow @ mpc.x + mpc.step_response[1:] * mpc.u_prev + d
        np.testing.assert_allclose(mpc.qp(r, y).g, 2 * mpc.Q * mpc.Phi.T @ (f - r), atol=1e-12)


def test_step_applies_the_solution_of_its_own_qp_and_advances_the_model():
    """The in-place fast path of step() against qp() + an independent solve + the model."""
    mpc, ref = paper_mpc(), paper_mpc("proxsuite")
    rng = np.random.default_rng(4)
    for k in range(100):
        r, y = rng.uniform(-1, 1), rng.uniform(-1, 1)
        applied = rng.uniform(-0.5, 0.5) if k else None
        if applied is not None:
            ref.x = x_pred + ref.B * applied  # noqa: F821 (the previous pass set it)
        qp = ref.qp(r, y)
        du = exact_qp(qp.H, qp.g, qp.A, qp.lower, qp.upper, qp.box)
        u_expected = ref.u_prev + du[0]
        u, status = mpc.step(r, y, applied)
        assert status > 0 and u == pytest.approx(u_expected, abs=1e-9)
        x_pred = ref.A @ ref.x
        ref.x, ref.u_prev = x_pred + ref.B * u_expected, u_expected
        np.testing.assert_allclose(mpc.x, ref.x, atol=1e-9)
