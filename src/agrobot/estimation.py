"""The estimation rules that ``identify`` and ``diagnose`` share: one parameter type, one
effective sample size, one covariance rule, one forward-difference Jacobian.

Effective sample size of residuals (pooled over pieces, each about its own mean)::

    n_eff = n (1 - rho1) / (1 + rho1),   rho1 the pooled lag-1 autocorrelation, clipped to [0, 0.98]

and never more than the measurement's own updates in them (a 5 Hz heading held in 20 Hz rows
carries a quarter of the rows' information: ``updates``).

Covariance of a least-squares fit with Jacobian J (residuals r, n samples, k free parameters)::

    cov = (J' J)^+ RSS / (n - k) x n / n_eff

a parameter on its bound is held there: the covariance is that of the others (its own: nan).

One fit result (``FitResult``) for both tools: the values, the free parameters, their covariance
and, per signal scored (identify's one yaw rate; the diagnosis's steering, yaw, position and speed
stages), the residual sum of squares, samples and effective samples of the fit part.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

Z95 = 1.959964
AT_BOUND = 2e-3          # a value within this share of its range from a bound ends on it (held there)
REPORTED_AT_BOUND = 5e-3   # a reported value within this share of its range from a bound: no estimate


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
        side = self.at_bound(value, REPORTED_AT_BOUND)
        if side == "upper" and hi > self.upper:
            return replace(self, upper=hi)
        if side == "lower" and lo < self.lower:
            return replace(self, lower=lo)
        return None


@dataclass
class FitResult:
    """One least-squares fit: ``values`` (every value the model reads), the ``free`` parameters and
    their covariance ``cov`` (SI units; a parameter held on its bound: nan), and per signal scored
    the fit part's residual sum of squares ``rss``, samples ``n`` and effective samples ``n_eff``,
    and the held-out RMS ``rmse_test`` (where a part is held out); ``converged``: the solver met its
    tolerance (False: stopped by its evaluation budget)."""

    values: dict[str, float]
    free: tuple[Parameter, ...]
    cov: np.ndarray
    rss: dict[str, float]
    n: dict[str, int]
    n_eff: dict[str, float]
    rmse_test: dict[str, float] = field(default_factory=dict)
    converged: bool = True

    @property
    def names(self) -> tuple[str, ...]:
        """The free parameters' names."""
        return tuple(p.name for p in self.free)

    def std(self, name: str) -> float:
        """The standard deviation of a free parameter (nan: held on its bound, or not free)."""
        if name not in self.names:
            return math.nan
        i = self.names.index(name)
        c = float(self.cov[i, i])
        return math.nan if math.isnan(c) else float(math.sqrt(max(c, 0.0)))     # inf: not seen by the residuals

    def at_bound(self, p: Parameter) -> str | None:
        return p.at_bound(self.values[p.name])

    def interval_of(self, grad: dict[str, float]) -> float:
        """Standard deviation of a derived quantity with gradient ``grad`` (delta method; a
        parameter held on its bound contributes nothing)."""
        gvec = np.array([grad.get(n, 0.0) for n in self.names])
        cov = np.nan_to_num(self.cov, nan=0.0)
        return float(math.sqrt(max(gvec @ cov @ gvec, 0.0)))

    @property
    def rss_total(self) -> float:
        return float(sum(self.rss.values()))

    @property
    def n_total(self) -> int:
        return int(sum(self.n.values()))

    @property
    def n_eff_total(self) -> float:
        return float(sum(self.n_eff.values()))

    @property
    def bic(self) -> float:
        """n_eff ln(RSS / n) + k ln(n_eff), over every signal scored."""
        return self.bic_at(self.n_eff_total)

    def bic_at(self, n_eff: float) -> float:
        """The BIC at a given effective size: two nested fits of one log compared at one n_eff (the
        simpler one's). Each fit's own n_eff, from its residuals' autocorrelation, moves by a few
        samples between fits, and n_eff ln(RSS / n) with it by several times ln(n_eff)."""
        return n_eff * math.log(self.rss_total / self.n_total) + len(self.free) * math.log(n_eff)

    def merged(self, part: "FitResult", reset: dict[str, float] | None = None) -> "FitResult":
        """This fit with the signals ``part`` scored, and the parameters it moved, taken from ``part``
        (``reset``: further values, those of an effect that leaves the model); the covariance of
        the parameters only this fit moved and that of ``part``'s, side by side."""
        keep = [i for i, p in enumerate(self.free) if p.name not in part.names]
        free = tuple(self.free[i] for i in keep) + tuple(part.free)
        cov = np.full((len(free), len(free)), np.nan)
        cov[:len(keep), :len(keep)] = self.cov[np.ix_(keep, keep)]
        cov[len(keep):, len(keep):] = part.cov
        values = {**self.values, **{k: part.values[k] for k in part.names}, **(reset or {})}
        return FitResult(values, free, cov, {**self.rss, **part.rss}, {**self.n, **part.n},
                         {**self.n_eff, **part.n_eff}, {**self.rmse_test, **part.rmse_test})


def solution_covariance(jac: np.ndarray, cost: float, x: np.ndarray, free, n: int, n_eff: float) -> np.ndarray:
    """``covariance`` of a bounded least-squares solution in scaled parameters x = value / scale
    (scipy's ``jac`` and ``cost`` = RSS / 2), a parameter on its bound (Parameter.at_bound) held
    there, returned in SI units."""
    scale = np.array([p.scale for p in free], float)
    held = np.array([p.at_bound(float(xi) * p.scale) is not None for p, xi in zip(free, x)], bool)
    return covariance(jac, 2.0 * cost, n, n_eff, held) * np.outer(scale, scale)


def updates_on(update_times: np.ndarray | None, t: np.ndarray, h: float, rows: np.ndarray) -> int | None:
    """How many of a measurement's own updates (at ``update_times``) fall on ``rows`` (indices or a
    mask) of the times ``t`` (spacing ``h``); None when it updates on every row."""
    if update_times is None:
        return None
    lo = np.searchsorted(update_times, t - 0.5 * h)
    fresh = np.searchsorted(update_times, t + 0.5 * h) > lo
    return int(fresh[rows].sum())


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
    """(J'J)^+ RSS / (n - k) x n / n_eff on the parameters not ``held`` (on a bound: nan); one the
    residuals do not depend on (a zero column of J, which the pseudo-inverse would give a zero
    variance) has an infinite variance."""
    k = J.shape[1]
    held = np.zeros(k, bool) if held is None else np.asarray(held, bool)
    cov = np.full((k, k), np.nan)
    norms = np.linalg.norm(J, axis=0) if len(J) else np.zeros(k)
    blind = ~held & (norms <= 1e-12 * max(float(norms.max(initial=0.0)), 1e-300))
    cov[blind, blind] = np.inf
    held = held | blind
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
