"""A channel the import interpolated onto the log's rows from its own samples.

A recording's channels come on their own stamps (jittered, or at another rate than the rows); the
import interpolates each linearly onto the rows and keeps the samples (frame.attrs["own_samples"],
measurements.runs.OwnSamples). Row t_j, at the fraction f_j of the way from the channel's sample
i_j to i_j + 1, holds

    x(t_j) = (1 - f_j) x_{i_j} + f_j x_{i_j + 1}          (``interpolation``: a sparse matrix)

Whether a channel's rows are that interpolation (``interpolates``: identification and diagnosis
alike) is one rule: each row within the stamps' rounding times its own intervals' slopes.

so what the rows carry of a signal s on the rows is R (S s): s read at the stamps (S, linear between
rows), interpolated back (R) -- ``reading``: how a model's prediction is seen as the channel sees the
truth. Its white noise e (level sigma on the samples) reaches the rows as R e (noise_floor).
"""
from __future__ import annotations

import numpy as np
from scipy import sparse

STAMP_ROUNDING = 1e-6            # s: POSIX stamps (1.7e9 s) on the log's clock from its first row, rounded


def interpolation_weights(t_to: np.ndarray, t_from: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(i_j, f_j): the row at t_j lies at the fraction f_j of the way from sample i_j to i_j + 1 of
    ``t_from`` (increasing), held at the end samples beyond them (np.interp)."""
    t_from, t_to = np.asarray(t_from, float), np.asarray(t_to, float)
    i = np.clip(np.searchsorted(t_from, t_to, side="right") - 1, 0, len(t_from) - 2)
    f = np.clip((t_to - t_from[i]) / np.maximum(t_from[i + 1] - t_from[i], 1e-12), 0.0, 1.0)
    return i, f


def interpolation(t_from: np.ndarray, t_to: np.ndarray) -> sparse.csr_matrix:
    """R (len(t_to), len(t_from)): linear interpolation from samples at ``t_from`` (increasing)
    onto ``t_to``, held at the end samples beyond them (np.interp)."""
    i, f = interpolation_weights(t_to, t_from)
    rows = np.arange(len(t_to))
    return sparse.csr_matrix((np.r_[1.0 - f, f], (np.r_[rows, rows], np.r_[i, i + 1])),
                             shape=(len(t_to), len(t_from)))


def interpolates(t: np.ndarray, x: np.ndarray, tc: np.ndarray, vc: np.ndarray) -> bool:
    """Whether ``x`` on the rows ``t`` is the linear interpolation of the samples (tc, vc) (increasing
    stamps): each finite row within what rounding the stamps by STAMP_ROUNDING moves it, STAMP_ROUNDING
    times the steepest slope of its own interval and its two neighbours (a near-duplicate stamp's
    steep slope widens the rows beside it alone), plus 1e-9 of the values' size."""
    t, x, tc, vc = (np.asarray(a, float) for a in (t, x, tc, vc))
    ok = np.isfinite(x)
    if len(tc) < 2 or not ok.any() or np.any(np.diff(tc) <= 0) or not np.all(np.isfinite(vc)):
        return False
    slope = np.abs(np.diff(vc) / np.diff(tc))
    steep = np.maximum.reduce([slope, np.r_[slope[:1], slope[:-1]], np.r_[slope[1:], slope[-1:]]])
    i = interpolation_weights(t[ok], tc)[0]
    tolerance = STAMP_ROUNDING * steep[i] + 1e-9 * max(1.0, float(np.abs(vc).max()))
    return bool(np.all(np.abs(np.interp(t[ok], tc, vc) - x[ok]) <= tolerance))


def own_stamps(frame, column: str, x: np.ndarray | None = None) -> np.ndarray | None:
    """The own stamps of ``column`` (frame.attrs["own_samples"]) when ``x`` (default: the column)
    is their linear interpolation onto the rows (interpolates), else None (no samples kept, or the
    column changed since the import)."""
    own = (frame.attrs.get("own_samples") or {}).get(column)
    if not own or len(own[0]) < 2 or (x is None and column not in frame):
        return None
    tc, vc = (np.asarray(a, float) for a in own)
    x = frame[column].to_numpy(float) if x is None else x
    return tc if interpolates(frame["t"].to_numpy(float), x, tc, vc) else None


def reading(frame, column: str, x: np.ndarray | None = None) -> sparse.csr_matrix | None:
    """R S (rows x rows): a signal on the rows as the channel ``column`` sees it -- read at its own
    stamps (linear between rows) and interpolated back onto the rows; None where the rows are not
    its samples interpolated (own_stamps)."""
    stamps = own_stamps(frame, column, x)
    if stamps is None:
        return None
    t = frame["t"].to_numpy(float)
    return (interpolation(stamps, t) @ interpolation(t, stamps)).tocsr()
