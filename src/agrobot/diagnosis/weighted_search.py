"""The least-squares search of a candidate fit (candidates.fitted) over residuals weighed by each
stage's noise level, r_s / sigma_s, with the residuals and the Jacobian kept unweighed.

A fit on a side-slip block is searched again at the levels it leaves (sigma_s^2 = RSS_s / n_eff,s),
from where the last search ended, up to candidates.REWEIGHTS times. At that point the residuals and
the forward-difference Jacobian (estimation.forward_jacobian: its steps depend on x alone) differ
from the last search's only by the row scale 1 / sigma_s: kept unweighed, they are weighed again
instead of replayed, which saves each such search a replay of the residuals and of the n stepped
parameter sets (on a few-step refit, a third of its replays).

A search stops when a step lowers the cost by less than FTOL of it, or moves x by less than XTOL of
its size (scipy.optimize.least_squares' ftol and xtol, 1e-8 by default). The cost is the weighed sum
of squares, about n / 2 for n residuals, and a parameter's 95 % interval spans a change of it of
about 2 (times n / n_eff): a step that gains 1e-6 of n / 2 leaves the parameter a few hundredths of
its interval from the default's end, whose last steps only crawled (a racecar's lever arm took 150
evaluations to gain 1e-4 of its cost). Where the reweighting stops short of its fixed point (its
REWEIGHTS refits), the difference is carried on: on 120 s of a racecar's log the lever arm ended an
eighth of its interval's half-width from where the default tolerances put it.
"""
from __future__ import annotations

from typing import Callable

import numpy as np
from scipy.optimize import OptimizeResult, least_squares

from agrobot.estimation import forward_jacobian

FTOL = 1e-6          # a step gaining less than this fraction of the cost ends the search
XTOL = 1e-6          # as does a step shorter than this fraction of |x|
MAX_NFEV = 150       # evaluations of the residuals a search may take
REL_STEP = 1e-3      # the forward differences' relative step (scipy's diff_step)


class WeightedSearch:
    """Least squares of the stacked residuals of ``stages`` (``replay.residuals_many(stage, sets,
    "fit")``, the parameter sets ``values_of(x)``) over x in [lo, hi], each stage's residuals divided
    by its level; the last point's unweighed residuals and Jacobian are kept (``point``, ``slope``)."""

    def __init__(self, replay, stages: tuple[str, ...], values_of: Callable[[np.ndarray], dict],
                 lo: np.ndarray, hi: np.ndarray) -> None:
        self.replay, self.stages, self.values_of, self.lo, self.hi = replay, tuple(stages), values_of, lo, hi
        self.sizes: list[int] | None = None
        self.point: tuple[np.ndarray, np.ndarray] | None = None                 # (x, residuals)
        self.slope: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None     # (x, residuals, Jacobian)

    def raw_many(self, xs: list[np.ndarray]) -> list[np.ndarray]:
        """The unweighed residuals of each x, the stages stacked in order (one batched replay per stage)."""
        sets = [self.values_of(x) for x in xs]
        per_stage = [self.replay.residuals_many(s, sets, "fit") for s in self.stages]
        if self.sizes is None:
            self.sizes = [len(r[0]) for r in per_stage]
        return [np.concatenate([r[i] for r in per_stage]) for i in range(len(xs))]

    def raw(self, x: np.ndarray) -> np.ndarray:
        if self.point is None or not np.array_equal(self.point[0], x):
            self.point = (np.array(x, float), self.raw_many([x])[0])
        return self.point[1]

    def raw_jacobian(self, x: np.ndarray) -> np.ndarray:
        """scipy's forward differences (diff_step=REL_STEP), the n stepped sets in one batched replay."""
        if self.slope is None or not np.array_equal(self.slope[0], x):
            f0 = self.raw(x)
            self.slope = (np.array(x, float), f0,
                          forward_jacobian(self.raw_many, x, self.lo, self.hi, rel_step=REL_STEP, f0=f0))
        return self.slope[2]

    def by_stage(self, sol: OptimizeResult) -> dict[str, np.ndarray]:
        """Each stage's unweighed residuals where the search ``sol`` ended (kept: no replay)."""
        self._resume(sol)
        r = self.raw(sol.x)
        return dict(zip(self.stages, np.split(r, np.cumsum(self.sizes)[:-1])))

    def _resume(self, sol: OptimizeResult | None) -> None:
        kept = getattr(sol, "kept", None)
        if kept is not None and np.array_equal(kept[0], sol.x):
            self.point, self.slope = (kept[0], kept[1]), kept

    def search(self, x0: np.ndarray, sigma: dict[str, float], after: OptimizeResult | None = None) -> OptimizeResult:
        """least_squares from ``x0`` on the residuals weighed by ``sigma``; ``after``: the search that
        ended at ``x0``, whose residuals and Jacobian there are weighed again rather than replayed."""
        self._resume(after)
        self.raw(x0)                                    # the stages' sizes
        weight = np.concatenate([np.full(n, sigma[s]) for s, n in zip(self.stages, self.sizes)])
        sol = least_squares(lambda x: self.raw(x) / weight, x0, jac=lambda x: self.raw_jacobian(x) / weight[:, None],
                            bounds=(self.lo, self.hi), max_nfev=MAX_NFEV, x_scale=1.0, ftol=FTOL, xtol=XTOL)
        sol.kept = self.slope if self.slope is not None and np.array_equal(self.slope[0], sol.x) else None
        return sol
