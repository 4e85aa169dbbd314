"""Parametric fits in the frequency domain (paper section IV): G(s) = B(s)/A(s) [e^{-s tau}],
A monic, to an FRF with variance var(G), by weighted nonlinear least squares

    V(theta) = sum_k |G_meas(k) - G(j w_k, theta)|^2 / var(k)

started from a linear solution: Levy (min sum |A G_meas - B|^2 / var) refined by
Sanathanan-Koerner iterations (weights 1/|A_prev|^2). Frequencies are scaled by w_max for
conditioning. With exact variances E[V] = F - n_theta/2 at the optimum (F lines, n_theta real
parameters); the covariance of theta is (J'J)^-1 of the residuals normalised to unit variance.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

# name -> (numerator order, denominator order); the paper's structures
STRUCTURES = {"second_order": (0, 2), "bicycle": (1, 2), "rlf": (1, 3), "rlfr": (2, 4)}


@dataclass
class Fit:
    model: str
    num: np.ndarray             # highest power first
    den: np.ndarray             # highest power first, monic
    num_std: np.ndarray
    den_std: np.ndarray         # std of den (0 for the leading 1)
    delay: float | None
    delay_std: float | None
    cost: float
    cost_expected: float
    lines: int
    extra: dict = field(default_factory=dict)

    @property
    def poles(self) -> np.ndarray:
        return np.roots(self.den)

    @property
    def zeros(self) -> np.ndarray:
        return np.roots(self.num) if len(self.num) > 1 else np.array([])

    def response(self, freq_hz: np.ndarray) -> np.ndarray:
        return evaluate(self.num, self.den, self.delay or 0.0, 2j * np.pi * np.asarray(freq_hz))

    def as_dict(self) -> dict:
        c = lambda z: [[float(v.real), float(v.imag)] for v in z]  # noqa: E731
        return {"num": self.num.tolist(), "num_std": self.num_std.tolist(), "den": self.den.tolist(),
                "den_std": self.den_std.tolist(), "delay_s": self.delay, "delay_std_s": self.delay_std,
                "poles": c(self.poles), "zeros": c(self.zeros), "cost": self.cost,
                "cost_expected": self.cost_expected, "lines": self.lines, **self.extra}


def evaluate(num, den, delay: float, s: np.ndarray) -> np.ndarray:
    return np.polyval(num, s) / np.polyval(den, s) * np.exp(-s * delay)


def _split(theta: np.ndarray, nb: int, na: int):
    b = theta[: nb + 1]                      # b_nb .. b_0 (scaled)
    a = np.concatenate([[1.0], theta[nb + 1: nb + 1 + na]])
    return b, a


def linear_start(G: np.ndarray, var: np.ndarray, w: np.ndarray, nb: int, na: int,
                 iterations: int = 10) -> np.ndarray:
    """Levy then Sanathanan-Koerner, on scaled s' = j w / w_max. Returns scaled [b.., a..]."""
    s = 1j * w / w.max()
    weight = 1.0 / np.sqrt(var)
    a_prev = np.ones_like(s)
    theta = None
    for _ in range(iterations + 1):
        wk = weight / np.abs(a_prev)
        # B(s) - G * sum_{i<na} a_i s^i = G s^na
        cols = [s ** i for i in range(nb, -1, -1)] + [-G * s ** i for i in range(na - 1, -1, -1)]
        X = np.array(cols).T * wk[:, None]
        rhs = G * s ** na * wk
        Xr = np.vstack([X.real, X.imag])
        yr = np.concatenate([rhs.real, rhs.imag])
        theta = np.linalg.lstsq(Xr, yr, rcond=None)[0]
        a_prev = np.polyval(_split(theta, nb, na)[1], s)
    return theta


def fit(model: str, freq_hz: np.ndarray, G: np.ndarray, var: np.ndarray, delay: bool = False,
        starts: list[tuple] = ()) -> Fit:
    """Weighted NLS fit of one structure (``STRUCTURES``), optionally with a pure delay.
    The NLS runs from the linear (Levy/SK) start and from each extra ``(num, den)`` start; the
    lowest cost among stable results wins (an over-parameterised structure can otherwise park a
    pole-zero pair in the right half plane at no cost)."""
    if model not in STRUCTURES:
        raise ValueError(f"unknown model structure {model!r}; expected one of {list(STRUCTURES)}")
    nb, na = STRUCTURES[model]
    var = np.maximum(np.asarray(var, float), 1e-30)
    w = 2 * np.pi * np.asarray(freq_hz, float)
    wmax = w.max()
    s = 1j * w / wmax
    candidates = [linear_start(G, var, w, nb, na)]
    for num0, den0 in starts:
        num0, den0 = np.asarray(num0, float) / den0[0], np.asarray(den0, float) / den0[0]
        if len(num0) == nb + 1 and len(den0) == na + 1:
            candidates.append(np.concatenate([num0 / wmax ** (na - np.arange(nb, -1, -1)),
                                              den0[1:] / wmax ** (na - np.arange(na - 1, -1, -1))]))
    scale = np.sqrt(2.0 / var)

    def residuals(theta):
        b, a = _split(theta, nb, na)
        tau = theta[-1] / wmax if delay else 0.0
        e = (G - evaluate(b, a, tau * wmax, s)) * scale
        return np.concatenate([e.real, e.imag])

    best = None
    for theta0 in candidates:
        if delay:
            theta0 = np.concatenate([theta0, [0.0]])
        sol = least_squares(residuals, theta0, method="lm", xtol=1e-12, ftol=1e-12, max_nfev=20000)
        stable = bool(np.all(np.roots(_split(sol.x, nb, na)[1]).real < 0))
        key = (not stable, sol.cost)
        if best is None or key < best[0]:
            best = (key, sol)
    sol = best[1]
    J = sol.jac
    cov = np.linalg.pinv(J.T @ J)
    std = np.sqrt(np.maximum(np.diag(cov), 0.0))
    theta = sol.x
    b, a = _split(theta, nb, na)
    # unscale: coefficient of s^i was multiplied by w_max^(i - na)
    num = b * wmax ** (na - np.arange(nb, -1, -1))
    den = a * wmax ** (na - np.arange(na, -1, -1))
    num_std = std[: nb + 1] * wmax ** (na - np.arange(nb, -1, -1))
    den_std = np.concatenate([[0.0], std[nb + 1: nb + 1 + na] * wmax ** (na - np.arange(na - 1, -1, -1))])
    tau = tau_std = None
    if delay:
        tau, tau_std = float(theta[-1] / wmax), float(std[-1] / wmax)
    F, n_theta = len(G), len(theta)
    cost = float(0.5 * np.sum(sol.fun ** 2))
    return Fit(model, num, den, num_std, den_std, tau, tau_std, cost, F - n_theta / 2.0, F,
               {"stable": not best[0][0], "starts": len(candidates)})
