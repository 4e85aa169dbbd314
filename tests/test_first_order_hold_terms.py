"""The exact first-order hold's terms (identification.driving.phi_steps, its C twin
identification/phi_step.h through diagnosis.replay_kernels.first_order_hold, and the replay's
diagnosis.replay.first_order_hold) against an independent method: scipy.linalg.expm of the augmented
generator, whose top block row is

    exp([[hA, B, 0], [0, 0, I], [0, 0, 0]]) = [e^{hA}, phi1(hA) B, phi2(hA) B],

so Phi = e^{hA}, Gamma0 = int_0^h e^{As} ds B = h phi1(hA) B, Gamma1 / h = (1/h) int_0^h e^{As} (h - s) ds B
= h phi2(hA) B (B unscaled in the generator keeps both blocks of order one however small h is), and
the replay's x+ = Phi x + G0 u_k + G1 u_k+1 has G1 = Gamma1 / h, G0 = Gamma0 - G1. Systems: random
stable ones, near-singular and singular ones (an integrator), complex eigenvalues (lightly damped
and undamped), repeated eigenvalues (Jordan blocks and a scalar matrix), stiff ones (many
squarings), steps from 1e-9 s to 2 s, several steps in one stack (uneven intervals). Each block is
held to 1e-14 of its own size times max(1, ||hA||_1). Then the yaw replay (bicycle, rlf, rlfr) with the hold replaced by the
augmented exponential gives the same yaw rates to 1e-10."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from agrobot.components.models.yaw_dynamics import TractorParameters
from agrobot.diagnosis import replay, replay_kernels
from agrobot.identification.driving import phi_steps

TOL = 1e-14
STEPS = (1e-9, 1e-6, 1e-3, 0.05, 2.0)


def augmented(A: np.ndarray, B: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(e^{hA}, h phi1(hA) B, h phi2(hA) B) from scipy's expm of [[hA, B, 0], [0, 0, I], [0, 0, 0]]."""
    n, p = B.shape
    M = np.zeros((n + 2 * p, n + 2 * p))
    M[:n, :n], M[:n, n:n + p], M[n:n + p, n + p:] = h * A, B, np.eye(p)
    E = expm(M)
    return E[:n, :n], h * E[:n, n:n + p], h * E[:n, n + p:]


def norm(A: np.ndarray, h: float) -> float:
    """||hA||_1."""
    return float(np.abs(h * A).sum(axis=0).max())


def similar(eigenvalues, rng) -> np.ndarray:
    """A real matrix with the given eigenvalues (complex ones in conjugate pairs as 2 x 2 blocks)."""
    blocks, i = [], 0
    while i < len(eigenvalues):
        lam = complex(eigenvalues[i])
        if lam.imag:
            blocks.append(np.array([[lam.real, -lam.imag], [lam.imag, lam.real]]))
            i += 2
        else:
            blocks.append(np.array([[lam.real]]))
            i += 1
    n = sum(len(b) for b in blocks)
    D = np.zeros((n, n))
    k = 0
    for b in blocks:
        D[k:k + len(b), k:k + len(b)] = b
        k += len(b)
    V = rng.standard_normal((n, n)) + 2 * np.eye(n)
    return V @ D @ np.linalg.inv(V)


def systems() -> list[tuple[str, np.ndarray]]:
    rng = np.random.default_rng(21)
    out = [(f"stable {n}", similar(-rng.uniform(0.1, 600.0, n), rng)) for n in (1, 2, 3, 4, 5)]
    out += [("near-singular", similar([-1e-10, -3.0, -40.0], rng)), ("singular", np.array([[0.0, 1.0], [0.0, -2.0]])),
            ("zero", np.zeros((2, 2))), ("integrator chain", np.diag([1.0, 1.0], 1)),
            ("complex", similar([-0.1 + 50j, -0.1 - 50j, -7.0], rng)), ("undamped", np.array([[0.0, -9.0], [9.0, 0.0]])),
            ("slightly unstable", similar([0.002 + 0.5j, 0.002 - 0.5j, -0.4 + 0.7j, -0.4 - 0.7j], rng)),
            ("jordan 2", np.array([[-4.0, 1.0], [0.0, -4.0]])), ("scalar", -4.0 * np.eye(3)),
            ("jordan 3", np.array([[-30.0, 1.0, 0.0], [0.0, -30.0, 1.0], [0.0, 0.0, -30.0]])),
            ("nearly repeated", np.array([[-4.0, 1.0], [1e-12, -4.0]])),
            ("stiff", similar([-5000.0, -0.5, -80.0 + 300j, -80.0 - 300j], rng))]
    return out


def held(got, want, label, norm):
    """Each block within TOL of its size, times max(1, ||hA||_1): the exponential's relative condition
    number grows with the norm (both methods square 2^s times)."""
    for name, g, w in zip(("Phi", "Gamma0", "Gamma1/h"), got, want):
        scale = float(np.max(np.abs(w))) * max(1.0, norm)
        assert float(np.max(np.abs(g - w))) <= TOL * scale, (label, name, g, w)     # e^{hA} may underflow to 0


@pytest.mark.parametrize("label, A", systems(), ids=[s[0] for s in systems()])
def test_hold_terms_equal_the_augmented_exponential(label, A):
    rng = np.random.default_rng(len(label))
    n = len(A)
    B = rng.standard_normal((n, 2))
    want = [augmented(A, B, h) for h in STEPS]
    stack, cols, steps = np.repeat(A[None], len(STEPS), axis=0), np.repeat(B[None], len(STEPS), axis=0), np.array(STEPS)
    order = rng.permutation(len(STEPS))              # uneven steps in one stack, in no particular order
    P, g1, g2 = phi_steps(stack[order], cols[order], steps[order])
    for i, k in enumerate(order):
        held((P[i], g1[i], g2[i]), want[k], (label, STEPS[k], "phi_steps"), norm(A, STEPS[k]))
    P1, g11, g21 = phi_steps(stack[order], cols[order][:, :, 0], steps[order])   # one input column
    for i, k in enumerate(order):
        held((P1[i], g11[i][:, None], g21[i][:, None]), [w[:, :1] if j else w for j, w in enumerate(want[k])],
             (label, STEPS[k], "phi_steps, one column"), norm(A, STEPS[k]))
    kernels = ["python"] + (["c"] if replay_kernels.choose("auto") == "c" else [])
    for kernel in kernels:
        for h, (P, G0, G1) in zip(STEPS, want):
            Phi, H0, H1 = (x[0] for x in replay.first_order_hold(A[None], B[None], h, kernel))
            held((Phi, H0 + H1, H1), (P, G0, G1), (label, h, kernel), norm(A, h))     # G0 = Gamma0 - G1, G1 = Gamma1 / h


def reference_hold(A, B, h, kernel="python"):
    """The replay's (Phi, G0, G1) from the augmented exponential, system by system."""
    terms = [augmented(a, b, h) for a, b in zip(A, B)]
    P, g1, g2 = (np.array(x) for x in zip(*terms))
    return P, g1 - g2, g2


@pytest.mark.parametrize("model", ["bicycle", "rlf", "rlfr"])
def test_yaw_replay_equals_the_replay_through_the_augmented_exponential(model, monkeypatch):
    rng = np.random.default_rng(11)
    n, h = 1200, 0.05
    t = np.arange(n) * h
    delta = 0.1 * np.sin(0.4 * t) + 0.02 * rng.standard_normal(n)
    speed = np.clip(2.0 + 2.5 * np.sin(0.05 * t), 0.0, None)      # standing still for a while too
    heading = np.cumsum(speed * delta / 1.4) * h
    v = dict(cornering_front_scale=1.2, cornering_rear_scale=0.9, cornering_speed_slope=0.1,
             cornering_reference_speed=2.0, relaxation_scale=1.3, steer_angle_offset=0.01, slope_north=0.3,
             slope_east=-0.2, yaw_rate_bias=0.02)
    kernels = ["python"] + (["c"] if replay_kernels.choose("auto") == "c" else [])
    got = {k: replay.YawReplay(model, TractorParameters(), h, delta, speed, heading, kernel=k).yaw_rate(v)
           for k in kernels}
    monkeypatch.setattr(replay, "first_order_hold", reference_hold)
    want = replay.YawReplay(model, TractorParameters(), h, delta, speed, heading, kernel="python").yaw_rate(v)
    assert np.std(want) > 0.01
    for kernel, rate in got.items():
        assert np.max(np.abs(rate - want)) <= 1e-10 * np.max(np.abs(want)), kernel
