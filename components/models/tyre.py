"""Lateral tyre force beyond the linear range, and the single-track model that uses it.

Simplified Magic Formula (Pacejka; B, C, D with E = 0), one per axle::

    F_y(alpha) = D sin(C atan(B alpha)),   D = mu F_z,   B = C_alpha / (C D)

so that dF_y/dalpha = C_alpha at alpha = 0 (the linear model's cornering stiffness); ``mu`` is the
friction coefficient (peak force over load) and ``C`` the shape factor (1 < C < 2: the force peaks
at atan(B alpha) = pi / (2 C) and falls to D sin(C pi / 2) at large slip; Pacejka's lateral value
is about 1.3; C < 1: no peak, the force rises towards D sin(C pi / 2) and approaches it as
1 / alpha, as a rational saturation C_alpha alpha / (1 + |alpha| / alpha_s) does). F_z is the axle's static load, m g l_r / L front and m g l_f / L rear.

The single-track equations are those of models.yaw_dynamics with the axle forces C alpha replaced
by F_y(alpha)::

    m dv_y/dt = -m v_x gamma - F_f - F_r,     I dgamma/dt = -l_f F_f + l_r F_r

with alpha_f static ((v_y + l_f gamma)/v_x - delta, bicycle) or a relaxation state (rlf, rlfr;
sigma dalpha/dt = v_y +- l gamma - v_x (alpha [+ delta])). ``rates`` returns the state derivative
and its Jacobian, batched over any leading axes, for a stiff (Rosenbrock) integrator.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from .yaw_dynamics import GRAVITY


def magic_formula(alpha, stiffness, peak, shape):
    """(F_y, dF_y/dalpha) of the simplified Magic Formula; ``peak`` = mu F_z (inf: linear tyre);
    arguments broadcast."""
    alpha = np.asarray(alpha, float)
    linear = ~np.isfinite(peak)
    if np.all(linear):
        return stiffness * alpha, stiffness * np.ones_like(alpha)
    D = np.where(linear, 1.0, peak)
    B = stiffness / (shape * D)
    x = B * alpha
    phase = shape * np.arctan(x)
    F, k = D * np.sin(phase), D * np.cos(phase) * shape * B / (1.0 + x * x)
    if np.any(linear):
        F, k = np.where(linear, stiffness * alpha, F), np.where(linear, stiffness, k)
    return F, k


SHAPE_BOUNDS = (0.5, 1.95)      # the shape factors a fit may take (C < 1: a tyre without a peak)
# rear / front peak friction mu_r / mu_f: load transfer and tyre sizing keep a vehicle well inside
FRICTION_RATIO_BOUNDS = (0.5, 2.0)


def force_limit_share(shape: float) -> float:
    """The largest force over D the Magic Formula reaches: 1 at its peak (C >= 1), sin(C pi / 2)
    approached at large slip (C < 1); the friction a tyre shows is mu times this."""
    return 1.0 if shape >= 1.0 else float(np.sin(shape * np.pi / 2))


def axle_loads(m: float, l_f: float, l_r: float) -> tuple[float, float]:
    """Static axle loads (F_zf, F_zr) = m g (l_r, l_f) / L."""
    L = l_f + l_r
    return m * GRAVITY * l_r / L, m * GRAVITY * l_f / L


def linear_share_limit(shape: float, share: float = 0.95) -> float:
    """F/D of an axle where the Magic Formula's force has fallen to ``share`` of the linear tyre's
    C_alpha alpha: in steady cornering every axle carries F/F_z = a_y / g, so the linear model holds
    up to |a_y| = mu g times this number."""
    x_peak = min(float(np.tan(np.pi / (2 * shape))), 1e6) if shape > 1 else 1e6
    x = brentq(lambda x: np.sin(shape * np.arctan(x)) / (shape * x) - share, 1e-9, x_peak)
    return float(np.sin(shape * np.arctan(x)))


N_STATES = {"bicycle": 2, "rlf": 3, "rlfr": 4}


def rates(model: str, p, v, delta, z, mu=np.inf, shape=1.3, C_f=None, C_r=None, mu_r=None):
    """(dz/dt, d(dz/dt)/dz) of the single-track model ``model`` with state z (..., n) =
    [v_y, gamma (, alpha_f) (, alpha_r)], speed v and wheel angle delta (...,); ``p`` has m, I,
    l_f, l_r, sigma_f, sigma_r, and C_f, C_r unless given (arrays broadcast with v); ``mu_r``: the
    rear axle's friction where it differs from the front's ``mu`` (None: ``mu`` on both)."""
    m, I, lf, lr = p.m, p.I, p.l_f, p.l_r
    Cf = p.C_f if C_f is None else C_f
    Cr = p.C_r if C_r is None else C_r
    Fzf, Fzr = axle_loads(m, lf, lr)
    vy, g = z[..., 0], z[..., 1]
    n = z.shape[-1]
    if model == "bicycle":
        a_f = (vy + lf * g) / v - delta
    else:
        a_f = z[..., 2]
    a_r = z[..., 3] if model == "rlfr" else (vy - lr * g) / v
    Ff, kf = magic_formula(a_f, Cf, mu * Fzf, shape)
    Fr, kr = magic_formula(a_r, Cr, (mu if mu_r is None else mu_r) * Fzr, shape)
    f = np.empty(z.shape)
    J = np.zeros(z.shape + (n,))
    f[..., 0] = -v * g - (Ff + Fr) / m
    f[..., 1] = (-lf * Ff + lr * Fr) / I
    # d(F_f)/dz, d(F_r)/dz through the slip angles
    dFf, dFr = np.zeros(z.shape), np.zeros(z.shape)
    if model == "bicycle":
        dFf[..., 0], dFf[..., 1] = kf / v, kf * lf / v
    else:
        dFf[..., 2] = kf
    if model == "rlfr":
        dFr[..., 3] = kr
    else:
        dFr[..., 0], dFr[..., 1] = kr / v, -kr * lr / v
    J[..., 0, :] = -(dFf + dFr) / m
    J[..., 0, 1] -= v
    J[..., 1, :] = (-lf * dFf + lr * dFr) / I
    if model in ("rlf", "rlfr"):
        sf = p.sigma_f
        f[..., 2] = (vy + lf * g - v * (a_f + delta)) / sf
        J[..., 2, 0], J[..., 2, 1], J[..., 2, 2] = 1.0 / sf, lf / sf, -v / sf
    if model == "rlfr":
        sr = p.sigma_r
        f[..., 3] = (vy - lr * g - v * a_r) / sr
        J[..., 3, 0], J[..., 3, 1], J[..., 3, 3] = 1.0 / sr, -lr / sr, -v / sr
    return f, J


GAMMA_ROS2 = 1.0 + 1.0 / np.sqrt(2.0)


def ros2_step(model: str, p, z, h: float, v0, v1, d0, d1, **tyre):
    """One step of the L-stable second-order Rosenbrock method (Verwer's ROS2, gamma = 1 + 1/sqrt 2)
    from inputs (v0, d0) to (v1, d1)::

        (I - gamma h J) k1 = f(z, u0),  (I - gamma h J) k2 = f(z + h k1, u1) - 2 k1,
        z+ = z + h (3 k1 + k2) / 2

    exact at equilibria for any h and stable however stiff the slip dynamics get at low speed."""
    f0, J = rates(model, p, v0, d0, z, **tyre)
    n = z.shape[-1]
    M = np.linalg.inv(np.eye(n) - GAMMA_ROS2 * h * J)
    k1 = np.einsum("...ij,...j->...i", M, f0)
    f1, _ = rates(model, p, v1, d1, z + h * k1, **tyre)
    k2 = np.einsum("...ij,...j->...i", M, f1 - 2.0 * k1)
    return z + h * (1.5 * k1 + 0.5 * k2)
