"""The candidate fits already computed on a replay, by their arguments (candidates.fit_key), so a
fit asked for again (the selection refits one model on its way to the verdict: a drop-one
judgement, a pair, the final model) is not searched again.

A fit is a pure function of its arguments and the replay (the premise of diagnosis.parallel_fits),
so the one remembered is the one a new search would find; each is handed out as a fresh copy (its
dictionaries and covariance), so what a caller changes in one is not in the next.
"""
from __future__ import annotations

from agrobot.estimation import FitResult

MEMO = "fits_done"      # the replay's attribute holding them


def _copy(fit: FitResult) -> FitResult:
    return FitResult(dict(fit.values), fit.free, fit.cov.copy(), dict(fit.rss), dict(fit.n), dict(fit.n_eff),
                     dict(fit.rmse_test))


def recalled(replay, key: tuple) -> FitResult | None:
    """The fit of ``key`` computed before on ``replay``, else None."""
    fit = replay.__dict__.get(MEMO, {}).get(key)
    return None if fit is None else _copy(fit)


def remembered(replay, key: tuple, fit: FitResult) -> FitResult:
    """``fit`` (of ``key``), kept on ``replay`` for the next time it is asked for."""
    replay.__dict__.setdefault(MEMO, {})[key] = _copy(fit)
    return fit


def forget(replay) -> None:
    """Drop the fits remembered on ``replay`` (a caller that changes how fits are searched)."""
    replay.__dict__.pop(MEMO, None)
