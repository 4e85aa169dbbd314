"""Physical parameters (paper Table 'Numerical Values of the Parameters') from identified
coefficients, and the paper's Appendix A as printed.

Appendix A misprints, found by solving the equations of motion symbolically (tests/test_identification.py):
  1. RLF a2 is printed without its denominator: the right value is
     (I m v^2 + C_r l_r^2 m sigma_f + I C_r sigma_f) / (I m v sigma_f).
  2. RLFR a0 is printed as C_f C_r (l_f+l_r)^2 / (I m sigma_f sigma_r): it misses the speed term,
     the right value is (C_f C_r (l_f+l_r)^2 + m v^2 (C_r l_r - C_f l_f)) / (I m sigma_f sigma_r).
  3. RLFR a1 is printed with v_x multiplying only the m(...) bracket: v_x multiplies the whole
     numerator, v (I (C_f+C_r) + m (C_f l_f^2 + C_r l_r^2 - C_f l_f sigma_r + C_r l_r sigma_f)).
All other printed coefficients (RLF b0, b1, a0, a1; RLFR b0, b1, b2, a2, a3) are right.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.optimize import least_squares

from agrobot.components.models.yaw_dynamics import TractorParameters, transfer_function

MISPRINTS = {("rlf", "a2"): "denominator I m v_x sigma_f missing",
             ("rlfr", "a0"): "speed term m v_x^2 (C_r l_r - C_f l_f) missing from the numerator",
             ("rlfr", "a1"): "v_x multiplies the whole numerator, not only the m(...) bracket"}


def appendix_as_printed(model: str, p: TractorParameters, v: float) -> dict[str, float]:
    """The paper's Appendix A coefficients exactly as printed (misprints included)."""
    m, I, lf, lr, Cf, Cr, sf, sr = p.m, p.I, p.l_f, p.l_r, p.C_f, p.C_r, p.sigma_f, p.sigma_r
    if model == "rlf":
        return {"b0": Cf * Cr * (lf + lr) / (I * m * sf), "b1": Cf * lf * v / (I * sf),
                "a0": (m * v**2 * (-Cf * lf + Cr * lr) + Cf * Cr * (lf + lr) ** 2) / (I * m * v * sf),
                "a1": (I * (Cf + Cr) + m * (Cf * lf**2 + Cr * lr**2) + Cr * lr * m * sf) / (I * m * sf),
                "a2": I * m * v**2 + Cr * lr**2 * m * sf + I * Cr * sf, "a3": 1.0}
    if model == "rlfr":
        d = I * m * sf * sr
        return {"b0": Cf * Cr * (lf + lr) * v / d, "b1": Cf * lf * v**2 / (I * sf * sr), "b2": Cf * lf * v / (I * sf),
                "a0": Cf * Cr * (lf + lr) ** 2 / d,
                "a1": (I * (Cf + Cr) + m * v * (Cf * lf**2 + Cr * lr**2 - Cf * lf * sr + Cr * lr * sf)) / d,
                "a2": (I * (m * v**2 + Cf * sr + Cr * sf) + m * (Cf * lf**2 * sr + Cr * lr**2 * sf)) / d,
                "a3": (sf + sr) * v / (sf * sr), "a4": 1.0}
    raise ValueError(f"Appendix A gives only rlf and rlfr, not {model!r}")


def coefficients(model: str, p: TractorParameters, v: float) -> dict[str, float]:
    """b_i, a_i (monic denominator) from the equations of motion."""
    num, den = transfer_function(model, p, v)
    out = {f"b{i}": float(c) for i, c in enumerate(num[::-1])}
    out.update({f"a{i}": float(c) for i, c in enumerate(den[::-1])})
    return out


def rlfr_physical(num: np.ndarray, den: np.ndarray, v: float, m: float, l_f: float, l_r: float,
                  starts: int = 60, seed: int = 0) -> list[dict]:
    """Cornering stiffnesses and relaxation lengths reproducing identified RLFR coefficients, with
    m, l_f, l_r known and I = m l_f l_r. Multi-start least squares on relative coefficient errors
    in log-parameters; returns the distinct solutions, best first, each with its cost (the paper
    saw several solutions fit about equally); none when every start runs off to non-physical values."""
    target = np.concatenate([np.asarray(num, float), np.asarray(den, float)[1:]])
    base = TractorParameters(m=m, I=m * l_f * l_r, l_f=l_f, l_r=l_r)

    def residual(logp):
        if not np.all(np.abs(logp) < 50.0):               # a start diverging out of any physical range
            return np.full(len(target), 1e3)
        Cf, Cr, sf, sr = np.exp(logp)
        try:
            pn, pd = transfer_function("rlfr", replace(base, C_f=Cf, C_r=Cr, sigma_f=sf, sigma_r=sr), v)
        except np.linalg.LinAlgError:
            return np.full(len(target), 1e3)
        if len(pn) != len(num) or not (np.all(np.isfinite(pn)) and np.all(np.isfinite(pd))):
            return np.full(len(target), 1e3)
        return (np.concatenate([pn, pd[1:]]) - target) / np.abs(target)

    rng = np.random.default_rng(seed)
    lo, hi = np.log([1e3, 1e3, 0.02, 0.02]), np.log([1e6, 1e6, 10.0, 10.0])
    found: list[dict] = []
    for _ in range(starts):
        sol = least_squares(residual, rng.uniform(lo, hi), method="lm", xtol=1e-12, ftol=1e-12)
        if not np.all((sol.x > lo - 10.0) & (sol.x < hi + 10.0)):
            continue                                      # ran off to no physical tractor
        values = np.exp(sol.x)
        cost = float(np.sum(sol.fun ** 2))
        if any(np.allclose(values, f["values"], rtol=1e-3) for f in found):
            continue
        found.append({"values": values, "cost": cost})
    if not found:
        return []
    found.sort(key=lambda f: f["cost"])
    best = found[0]["cost"]
    return [{"C_f": f["values"][0], "C_r": f["values"][1], "sigma_f": f["values"][2], "sigma_r": f["values"][3],
             "cost": f["cost"], "equally_good": f["cost"] <= max(2 * best, best + 1e-6)} for f in found[:8]]
