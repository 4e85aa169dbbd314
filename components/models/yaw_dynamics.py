"""Linear yaw dynamics of the tractor, paper section III-A (equations of yaw motion).

Equations of motion (linear tyres F = -C*alpha, small angles, v_x a parameter)::

    m dv_y/dt   = -m v_x gamma - C_f alpha_f - C_r alpha_r
    I dgamma/dt = -l_f C_f alpha_f + l_r C_r alpha_r

Side-slip angles, static (traditional bicycle) or through relaxation lengths (RLF front only,
RLFR front and rear)::

    alpha_f = (v_y + l_f gamma)/v_x - delta        or  sigma_f dalpha_f/dt = v_y + l_f gamma - v_x (delta + alpha_f)
    alpha_r = (v_y - l_r gamma)/v_x                or  sigma_r dalpha_r/dt = v_y - l_r gamma - v_x alpha_r

State order: [v_y, gamma] (+ alpha_f for RLF) (+ alpha_r for RLFR); input delta; output gamma.

Model extensions (the diagnosis catalogue), shared by the plant and the diagnosis replay:

- speed-dependent cornering: C_f, C_r scaled by c(v) = max(0.2, 1 + k (v_x - v_ref));
- side slope: a field plane tilted by phi with its fall line at azimuth psi_d adds the lateral
  acceleration a_lat = g sin(phi) sin(psi_d - psi) to dv_y/dt (input column ``E``: [1, 0, ...]).

Imported where used: scipy.signal (start-up: 0.4 s of CPU, measured, that every run holding the yaw plant
would pay; only the transfer function uses it).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import math

import numpy as np
from scipy.linalg import expm

from .paper_models import DEFAULT_SET, PARAMETER_SETS

PHYSICAL_MODELS = ("bicycle", "rlf", "rlfr")


@dataclass(frozen=True)
class TractorParameters:
    """The paper's Table 'Numerical Values of the Parameters' (SI units)."""

    m: float = 700.0
    I: float = 280.0
    l_f: float = 1.0
    l_r: float = 0.4
    C_f: float = 8000.0
    C_r: float = 90000.0
    sigma_f: float = 0.1942
    sigma_r: float = 1.6657

    @classmethod
    def of(cls, parameters) -> "TractorParameters":
        """From a yaw plant's resolved parameters (SI; e.g. ``resolve(study).parameters(plant)``): values the
        study leaves unset (None) come from the named ``parameter_set`` (paper_models.PARAMETER_SETS;
        by default the model's, DEFAULT_SET, else the Table); ``cornering_scale_front/rear``
        multiply C_f and C_r (relative variations that hold for every set)."""
        name = parameters.get("parameter_set") or DEFAULT_SET.get(parameters.get("model", ""), "table")
        if name not in PARAMETER_SETS:
            raise ValueError(f"parameter_set {name!r}; expected one of {sorted(PARAMETER_SETS)}")
        named = PARAMETER_SETS[name]
        values = {}
        for k in ("m", "I", "l_f", "l_r", "C_f", "C_r", "sigma_f", "sigma_r"):
            v = parameters.get(k)
            values[k] = float(v) if v is not None else float(named.get(k, getattr(cls, k)))
        values["C_f"] *= float(parameters.get("cornering_scale_front", 1.0))
        values["C_r"] *= float(parameters.get("cornering_scale_rear", 1.0))
        return cls(**values)


GRAVITY = 9.81


def body_to_world(forward, left, cos_psi, sin_psi):
    """A body-frame offset (forward, left) in east/north at heading psi: the lever arm of a point
    (the GPS antenna) on the tractor, (f cos psi - l sin psi, f sin psi + l cos psi)."""
    return forward * cos_psi - left * sin_psi, forward * sin_psi + left * cos_psi


def cornering_scale(v_x: float, slope: float, reference_speed: float) -> float:
    """c(v) = max(0.2, 1 + slope (v_x - v_ref)): the factor on both cornering stiffnesses."""
    return max(0.2, 1.0 + slope * (v_x - reference_speed))


def with_cornering_scale(p: TractorParameters, scale: float, rear_scale: float | None = None) -> TractorParameters:
    """The parameters with C_f multiplied by ``scale`` and C_r by ``rear_scale`` (default: the same)."""
    return replace(p, C_f=p.C_f * scale, C_r=p.C_r * (scale if rear_scale is None else rear_scale))


def slope_lateral_acceleration(heading, slope_angle: float, downhill_heading: float):
    """a_lat = g sin(phi) sin(psi_d - psi): gravity along the body's left axis on a side slope."""
    return GRAVITY * np.sin(slope_angle) * np.sin(downhill_heading - heading)


def lateral_disturbance_column(n_states: int) -> np.ndarray:
    """E: a lateral acceleration at the CG enters dv_y/dt (state 0) with gain 1."""
    E = np.zeros(n_states)
    E[0] = 1.0
    return E


def state_space(model: str, p: TractorParameters, v_x: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A, B, C) of the yaw dynamics at longitudinal speed ``v_x`` (> 0 for bicycle and RLF)."""
    m, I, lf, lr, Cf, Cr, sf, sr = p.m, p.I, p.l_f, p.l_r, p.C_f, p.C_r, p.sigma_f, p.sigma_r
    v = float(v_x)
    if model == "bicycle":
        A = np.array([[-(Cf + Cr) / (m * v), -v - (Cf * lf - Cr * lr) / (m * v)],
                      [-(lf * Cf - lr * Cr) / (I * v), -(lf**2 * Cf + lr**2 * Cr) / (I * v)]])
        B = np.array([Cf / m, lf * Cf / I])
    elif model == "rlf":
        A = np.array([[-Cr / (m * v), -v + Cr * lr / (m * v), -Cf / m],
                      [lr * Cr / (I * v), -lr**2 * Cr / (I * v), -lf * Cf / I],
                      [1.0 / sf, lf / sf, -v / sf]])
        B = np.array([0.0, 0.0, -v / sf])
    elif model == "rlfr":
        A = np.array([[0.0, -v, -Cf / m, -Cr / m],
                      [0.0, 0.0, -lf * Cf / I, lr * Cr / I],
                      [1.0 / sf, lf / sf, -v / sf, 0.0],
                      [1.0 / sr, -lr / sr, 0.0, -v / sr]])
        B = np.array([0.0, 0.0, -v / sf, 0.0])
    else:
        raise ValueError(f"unknown yaw model {model!r}; expected one of {PHYSICAL_MODELS}")
    C = np.zeros(A.shape[0])
    C[1] = 1.0
    return A, B, C


def controllable_canonical(num: list[float], den: list[float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A, B, C) of a strictly proper transfer function num/den (highest power first)."""
    den = np.asarray(den, dtype=float)
    num = np.asarray(num, dtype=float)
    if den[0] == 0:
        raise ValueError("leading denominator coefficient is zero")
    num, den = num / den[0], den / den[0]
    n = len(den) - 1
    if n < 1 or len(num) > n:
        raise ValueError("transfer function must be strictly proper with order >= 1")
    A = np.zeros((n, n))
    A[0, :] = -den[1:]
    A[1:, :-1] = np.eye(n - 1)
    B = np.zeros(n)
    B[0] = 1.0
    C = np.zeros(n)
    C[n - len(num):] = num
    return A, B, C


def expm_batched(M: np.ndarray) -> np.ndarray:
    """exp of each matrix of a stack (k, n, n): scaling and squaring with a degree-12 Taylor
    polynomial, vectorised over the stack (scipy's expm loops over it in Python). The scaled norm
    is at most 1/4, so the truncation error is below 0.25^13 / 13! ~ 2e-18 relative."""
    norm = float(np.max(np.sum(np.abs(M), axis=-2))) if M.size else 0.0
    squarings = max(0, int(math.ceil(math.log2(norm / 0.25)))) if norm > 0.25 else 0
    X = M / 2.0 ** squarings
    E = np.broadcast_to(np.eye(M.shape[-1]), M.shape).copy()
    term = E.copy()
    for k in range(1, 13):
        term = term @ X / k
        E += term
    for _ in range(squarings):
        E = E @ E
    return E


def zoh_discretize(A: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact zero-order-hold discretisation: [Ad Bd; 0 I] = expm([A B; 0 0] dt).
    ``B`` is one input column (n,) or several (n, m); Bd has the same shape. A stack of systems
    (A: (k, n, n), B: (k, n, m)) is discretised in one batched call (expm_batched)."""
    n = A.shape[-1]
    Bm = B.reshape(*A.shape[:-2], n, -1)
    m = Bm.shape[-1]
    M = np.zeros((*A.shape[:-2], n + m, n + m))
    M[..., :n, :n] = A
    M[..., :n, n:] = Bm
    E = expm(M * dt) if A.ndim == 2 else expm_batched(M * dt)
    return E[..., :n, :n], E[..., :n, n:].reshape(B.shape)


def transfer_function(model: str, p: TractorParameters, v_x: float) -> tuple[np.ndarray, np.ndarray]:
    """(num, den) of gamma/delta, highest power first, den monic; numerator coefficients that
    are structurally zero (round-off only) are trimmed."""
    from scipy.signal import ss2tf

    A, B, C = state_space(model, p, v_x)
    num, den = ss2tf(A, B.reshape(-1, 1), C.reshape(1, -1), np.zeros((1, 1)))
    num = num[0] / den[0]
    num = num[np.argmax(np.abs(num) > 1e-9 * np.abs(num).max()):]
    return num, den / den[0]
