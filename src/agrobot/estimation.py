"""The estimation rules that ``identify`` and ``diagnose`` share: one parameter type, one
effective sample size, one covariance rule, one forward-difference Jacobian.

Effective sample size of residuals (pooled over pieces, each about its own mean)::

    n_eff = n (1 - rho1) / (1 + rho1),   rho1 the pooled lag-1 autocorrelation, clipped to [0, 0.98]

and never more than the measurement's own updates in them (a 5 Hz heading held in 20 Hz rows
carries a quarter of the rows' information: ``updates``).

Covariance of a least-squares fit with Jacobian J (residuals r, n samples, k free parameters)::

    cov = (J' J)^+ RSS / (n - k) x n / n_eff

a parameter on its bound is held there: the covariance is that of the others (its own: nan).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

Z95 = 1.959964
AT_BOUND = 2e-3          # a value within this share of its range from a bound ends on it


@dataclass(frozen=True)
class Parameter:
    """A free parameter: its name (the model's value key), SI unit, typical magnitude (optimiser
    scaling), bounds searched, how a person reads it, the physical limit a bound widens toward."""

    name: str
    unit: str
    scale: float
    lower: float
    upper: float
    display_unit: str = ""
    display_factor: float = 1.0
    limit: tuple[float, float] | None = None   # None: the bounds are the physical limit
    meaning: str = ""

    def at_bound(self, value: float, share: float = AT_BOUND) -> str | None:
        """'lower' or 'upper' when ``value`` ends on that bound, else None."""
        span = self.upper - self.lower
        for side, b in (("lower", self.lower), ("upper", self.upper)):
            if abs(value - b) <= share * span:
                return side
        return None

    def widened(self, value: float) -> "Parameter | None":
        """This parameter with the bound ``value`` ended on moved to the physical limit, or None
        when that bound is the limit already (then the value is not identifiable from the log)."""
        lo, hi = self.limit or (self.lower, self.upper)
        side = self.at_bound(value, 5e-3)
        if side == "upper" and hi > self.upper:
            return replace(self, upper=hi)
        if side == "lower" and lo < self.lower:
            return replace(self, lower=lo)
        return None


def effective_size(residuals, updates: int | None = None) -> float:
    """n (1 - rho1) / (1 + rho1) of one residual array or a list of pieces (rho1 pooled, each
    piece about its own mean), at most ``updates`` (the measurement's own updates in them)."""
    pieces = [np.asarray(residuals, float)] if isinstance(residuals, np.ndarray) else [np.asarray(r, float)
                                                                                      for r in residuals]
    num = den = 0.0
    n = 0
    for r in pieces:
        if not len(r):
            continue
        r = r - r.mean()
        num += float(r[1:] @ r[:-1]) if len(r) > 1 else 0.0
        den += float(r @ r)
        n += len(r)
    rho = min(max(num / den, 0.0), 0.98) if den > 0 else 0.0
    size = n * (1 - rho) / (1 + rho)
    return min(size, float(updates)) if updates is not None else size


def covariance(J: np.ndarray, rss: float, n: int, n_eff: float, held: np.ndarray | None = None) -> np.ndarray:
    """(J'J)^+ RSS / (n - k) x n / n_eff on the parameters not ``held`` (on a bound: nan)."""
    k = J.shape[1]
    held = np.zeros(k, bool) if held is None else np.asarray(held, bool)
    cov = np.full((k, k), np.nan)
    inner = np.flatnonzero(~held)
    if len(inner):
        Ji = J[:, inner]
        dof = max(1, n - k)
        try:
            cov[np.ix_(inner, inner)] = np.linalg.pinv(Ji.T @ Ji) * (rss / dof) * (n / max(n_eff, 1.0))
        except np.linalg.LinAlgError:
            cov[np.ix_(inner, inner)] = np.inf
    return cov


def interval(value: float, std: float) -> tuple[float, float]:
    """The 95 % interval value +- 1.96 std."""
    return value - Z95 * std, value + Z95 * std


def compare(quantity: str, unit: str, a: tuple[str, float, float], b: tuple[str, float, float], why: str) -> dict:
    """Two estimates of one quantity side by side, {quantity, unit, estimates: {method: {value, std,
    interval}}, agree, suggests}: ``a``, ``b`` are (method, value, std); they agree when their 95 %
    intervals overlap (or a value is unknown; a value without a std, on its bound, counts as a
    point); ``why``: what a disagreement means, reported only then."""
    est = {}
    for method, value, sd in (a, b):
        w = Z95 * sd if math.isfinite(sd) else 0.0
        est[method] = {"value": value, "std": sd, "interval": [value - w, value + w]}
    ia, ib = est[a[0]]["interval"], est[b[0]]["interval"]
    known = all(math.isfinite(x) for x in ia + ib)
    same = (not known) or (ia[0] <= ib[1] and ib[0] <= ia[1])
    return {"quantity": quantity, "unit": unit, "estimates": est, "agree": bool(same), "suggests": "" if same else why}


def forward_jacobian(residuals_many, x: np.ndarray, lower: np.ndarray, upper: np.ndarray, rel_step: float = 1e-3,
                     f0: np.ndarray | None = None, floor: float = 0.0, signed: bool = True) -> np.ndarray:
    """J[:, i] = (f(x + h_i e_i) - f(x)) / h_i, every point in one call ``residuals_many(points)`` (a
    list of residual vectors, one per point): a batched simulation of n + 1 parameter sets costs
    little more than one. The steps are scipy's (optimize._numdiff.approx_derivative, which
    least_squares(diff_step=rel_step) calls): h = rel sign(x) max(|x|, floor), sign(0) = +1 (positive
    when not ``signed``); sqrt(eps) sign(x) max(1, |x|) where h rounds away; reversed where x + h
    leaves [lower, upper] and the reverse fits, else the longer side's distance; h = (x + h) - x,
    exactly representable; J column-major like scipy's. ``f0``: f(x) when known, else evaluated with the steps."""
    x = np.asarray(x, float)
    sign = np.where(x >= 0, 1.0, -1.0) if signed else np.ones_like(x)
    h = rel_step * sign * np.maximum(np.abs(x), floor)
    h = np.where((x + h) - x == 0, np.finfo(float).eps ** 0.5 * sign * np.maximum(1.0, np.abs(x)), h)
    below, above = x - lower, upper - x
    fits = np.abs(h) <= np.maximum(below, above)
    h = np.where(((x + h < lower) | (x + h > upper)) & fits, -h, h)
    h = np.where(fits, h, np.where(above >= below, above, -below))
    points = []
    for i in range(len(x)):
        xi = x.copy()
        xi[i] = x[i] + h[i]
        points.append(xi)
    out = residuals_many(points if f0 is not None else [x] + points)
    if f0 is None:
        f0, out = out[0], out[1:]
    f0 = np.asarray(f0, float)
    J = np.empty((len(x), len(f0)))
    for i, (f, p) in enumerate(zip(out, points)):
        J[i] = (np.asarray(f, float) - f0) / (p[i] - x[i])
    return J.T          # column-major, as scipy's: least_squares' products then sum in the same order
