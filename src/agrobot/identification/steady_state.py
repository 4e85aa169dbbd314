"""Steady-state cornering from the log, by ordinary least squares: a check on the dynamic fit that
shares none of its machinery (no simulation, no delay or lag model).

In steady cornering the wheel angle is delta = L / R + K a_y with R = v / r and a_y = v r; with the
steering input u (command or measured angle) seen as g u + delta_0 by the tyres and a gyro reading
r_m = r + b::

    L r_m = g (u v) + delta_0 v - K (v^2 r_m) + L b      (+ K v^2 b, negligible)

so L r_m regressed on [u v, v, v^2 r_m, 1] gives g, delta_0, -K and L b. Steady windows: the input
held (held_input: within HELD_TOLERANCE + HELD_RELATIVE |u|) for ``settle`` s (plus the delay)
before and during a window of ``window`` s (the yaw dynamics settle in a few tenths of a second), the speed within
10 %, moving; each window contributes its means. Only windows with |a_y| below
``max_lateral`` enter (the linear tyre's range).

The linear range in steady turns (linear_limit): the regression fitted where |a_y| is small (tyres
on any ground are linear below 0.15 g) predicts every window's yaw rate; going up in |a_y|, bins of
windows whose measured steady yaw gain stays within three standard errors of that prediction (the
bin's scatter and the prediction's own) are linear; the first bin beyond it ends the range (tyres past their bend, or a steering map bending
with the angle). The regression in the linear range (in_linear_range) uses the windows below that.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view


@dataclass
class SteadyState:
    windows: dict[str, np.ndarray]         # u, v, r (means per window), a_y
    gain: float
    gain_std: float
    offset: float
    offset_std: float
    K: float
    K_std: float
    bias: float
    used: int
    max_lateral: float
    limit_how: str = ""
    limit_derived: bool = True             # False: too few windows where the tyres are surely linear to read it
    limit_bent: bool = False               # the range ends where a bin of windows turns off the reference's gain
    passed_over: int = 0
    fixed_gain: float | None = None        # a measured wheel angle: g = 1, not fitted

    def as_dict(self) -> dict:
        return {"method": "ordinary least squares on steady windows: L r = g (u v) + delta_0 v - K v^2 r + L b",
                "windows": self.used, "max_lateral_acceleration": self.max_lateral,
                "linear_limit": self.limit_how, "windows_passed_over": self.passed_over,
                "understeer_gradient": {"value": self.K, "std": self.K_std,
                                        "interval": [self.K - 1.96 * self.K_std, self.K + 1.96 * self.K_std]},
                "steer_gain": {"value": self.gain, "std": self.gain_std},
                "steer_offset": {"value": self.offset, "std": self.offset_std}, "gyro_bias": self.bias}


HELD_TOLERANCE = 0.01        # rad: a steady input moves less than this ...
HELD_RELATIVE = 0.05         # ... plus this share of its own level


def held_input(u: np.ndarray, run: np.ndarray, width: int) -> np.ndarray:
    """Per sample j: whether the input has been held over the ``width`` samples ending at j, in one
    run: max - min <= HELD_TOLERANCE + HELD_RELATIVE max |u| over them (nan: not held). The one rule
    of a steady input, for the steady-state regression's windows (steady_windows) and the log's
    steady turns of the study check (diagnosis.study_fit.steady_turns)."""
    n = len(u)
    out = np.zeros(n, bool)
    if width < 1 or n < width:
        return out
    win = sliding_window_view(np.asarray(u, float), width)
    hi, lo = win.max(axis=1), win.min(axis=1)
    with np.errstate(invalid="ignore"):
        ok = (hi - lo) <= HELD_TOLERANCE + HELD_RELATIVE * np.maximum(np.abs(hi), np.abs(lo))
    out[width - 1:] = ok & (run[width - 1:] == run[: n - width + 1])
    return out


def steady_windows(t, u, v, r, run, min_speed: float, delay: float = 0.0, window: float = 0.3,
                   settle: float = 0.4) -> dict[str, np.ndarray]:
    """Means of (u, v, r) over non-overlapping steady windows (see the module's docstring; the input
    held by held_input); u is taken ``delay`` s earlier than v and r."""
    h = float(np.median(np.diff(t)))
    nw, ns = max(2, int(round(window / h))), int(round((settle + delay) / h))
    n = len(t)
    if n < nw + ns + 1:
        return {k: np.zeros(0) for k in ("u", "v", "r", "a_y")}

    def window_stats(x, width):
        c = np.concatenate([[0.0], np.cumsum(x)])
        mean = (c[width:] - c[:-width]) / width                     # mean over [k, k + width)
        win = sliding_window_view(x, width)
        return mean, win.max(axis=1), win.min(axis=1)

    lag = int(round(delay / h))
    u_width = ns + nw - lag                                         # input held over [k - ns, k + nw - lag)
    held = held_input(u, run, u_width)
    v_mean, v_hi, v_lo = window_stats(v, nw)
    r_mean, _, _ = window_stats(r, nw)
    u_mean, _, _ = window_stats(u, nw)
    run_same = run[: n - nw + 1] == run[nw - 1:]
    ks = np.arange(ns, n - nw + 1)
    ok = held[ks - ns + u_width - 1] & (v_lo[ks] >= min_speed) & \
        ((v_hi[ks] - v_lo[ks]) <= 0.1 * v_mean[ks]) & run_same[ks] & (run[ks - ns] == run[ks])
    rows, next_free = [], 0
    for k in ks[ok]:
        if k - ns >= next_free:
            rows.append((u_mean[k - lag], v_mean[k], r_mean[k]))
            next_free = k + nw
    arr = np.array(rows) if rows else np.zeros((0, 3))
    return {"u": arr[:, 0], "v": arr[:, 1], "r": arr[:, 2], "a_y": arr[:, 1] * arr[:, 2]}


def regression(w: dict[str, np.ndarray], L: float, max_lateral: float = math.inf,
               fixed_gain: float | None = None) -> SteadyState | None:
    """The least-squares fit of the module's equation on windows with |a_y| <= max_lateral
    (``fixed_gain``: a measured wheel angle, g = 1, not fitted). None: fewer than 7 windows, no
    turning, or (a command input) speeds too alike (10th to 90th percentile less than 1.5 x)."""
    keep = np.abs(w["a_y"]) <= max_lateral
    u, v, r = w["u"][keep], w["v"][keep], w["r"][keep]
    if len(v) and fixed_gain is None and np.percentile(v, 90) < 1.5 * np.percentile(v, 10):
        return None             # one speed: the gain and K are not told apart
    if len(u) and np.std(u) < 1e-3:
        return None             # straight driving only
    cols = [v, -(v ** 2) * r, np.ones_like(v)]
    y = L * r
    if fixed_gain is None:
        cols = [u * v] + cols
    else:
        y = y - fixed_gain * u * v
    X = np.column_stack(cols)
    if len(y) < X.shape[1] + 3:
        return None
    beta, *_ = np.linalg.lstsq(X, y, rcond=None)
    res = y - X @ beta
    s2 = float(res @ res) / (len(y) - X.shape[1])
    cov = s2 * np.linalg.pinv(X.T @ X)
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    if fixed_gain is None:
        g, g_sd, (d0, K, Lb), (d0_sd, K_sd, _) = beta[0], sd[0], beta[1:], sd[1:]
    else:
        g, g_sd, (d0, K, Lb), (d0_sd, K_sd, _) = fixed_gain, 0.0, beta, sd
    return SteadyState({k: x[keep] for k, x in w.items()}, float(g), float(g_sd), float(d0), float(d0_sd),
                       float(K), float(K_sd), float(Lb / L), int(len(y)), float(max_lateral), fixed_gain=fixed_gain)


def same_regression(fit: SteadyState, w: dict[str, np.ndarray], L: float) -> SteadyState | None:
    """``fit``'s regression (its |a_y| limit, its gain fixed or fitted) on windows ``w`` (give them
    ``fit``'s windows' |a_y|, so that the same windows are kept)."""
    return regression(w, L, max_lateral=fit.max_lateral, fixed_gain=fit.fixed_gain)


def yaw_gain_ratio(fit: SteadyState, w: dict[str, np.ndarray], L: float) -> np.ndarray:
    """Each window's measured steady yaw rate over the one ``fit`` predicts, (r - b) / ((g u +
    delta_0) v / (L + K v^2)); NaN where the prediction is under 0.02 rad/s (no turn to compare)."""
    pred = (fit.gain * w["u"] + fit.offset) * w["v"] / (L + fit.K * w["v"] ** 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.abs(pred) >= 0.02, (w["r"] - fit.bias) / pred, np.nan)


def linear_limit(w: dict[str, np.ndarray], L: float, small: float, cap: float, fixed_gain: float | None = None,
                 per_bin: int = 8) -> tuple[float, str, bool, bool]:
    """(|a_y| limit [m/s2], how it was found, whether it was derived, whether a bin bent off): the regression on the windows with |a_y| <= ``small``
    is the reference; the windows above it, in bins of ``per_bin`` by |a_y|, stay linear while the
    median of yaw_gain_ratio lies within 3 standard errors of 1: the median's (1.25 sd / sqrt(n))
    and the reference's prediction's (delta method on its K and gain: v^2 sd_K / (L + K v^2),
    sd_g / g) combined; the limit is the top |a_y| of the last such bin (at most ``cap``). Without a
    reference fit the limit is ``cap``, said so, not derived."""
    ref = regression(w, L, max_lateral=small, fixed_gain=fixed_gain)
    if ref is None:
        return cap, (f"not derived (fewer than 7 steady windows with |a_y| <= {small:.3g} m/s2, or turns there at "
                     f"one speed): the windows up to {cap:.3g} m/s2 are used"), False, False
    a = np.abs(w["a_y"])
    ratio = yaw_gain_ratio(ref, w, L)
    v2 = w["v"] ** 2
    ref_sd = np.hypot(v2 * ref.K_std / (L + ref.K * v2), ref.gain_std / ref.gain)
    order = [k for k in np.argsort(a) if a[k] > small and a[k] <= cap and np.isfinite(ratio[k])]
    limit = min(small, cap)
    for start in range(0, len(order) - per_bin + 1, per_bin):
        chunk = order[start:start + per_bin] if len(order) - start >= 2 * per_bin else order[start:]
        med = float(np.median(ratio[chunk]))
        allowed = 3 * math.hypot(1.25 * float(np.std(ratio[chunk])) / math.sqrt(len(chunk)), float(np.median(ref_sd[chunk])))
        if abs(med - 1.0) > allowed:
            return limit, (f"where the steady yaw gain stays within 3 standard errors of the regression's on the "
                           f"{ref.used} windows with |a_y| <= {small:.3g} m/s2: the {len(chunk)} windows at "
                           f"{a[chunk[0]]:.3g}-{a[chunk[-1]]:.3g} m/s2 turn {100 * (med - 1):+.1f} % (3 standard errors: "
                           f"{100 * allowed:.1f} %; tyres past their bend, or a steering map bending with the angle)"), True, True
        limit = float(a[chunk[-1]])
        if len(chunk) > per_bin:
            break
    limit = max(limit, min(small, cap))
    return limit, (f"every steady window up to {limit:.3g} m/s2 turns within 3 standard errors of the regression's on "
                   f"the {ref.used} windows with |a_y| <= {small:.3g} m/s2"), True, False


def in_linear_range(w: dict[str, np.ndarray], L: float, small: float, cap: float,
                    fixed_gain: float | None = None) -> SteadyState | None:
    """The regression on the windows inside linear_limit's range (None: regression's reasons)."""
    limit, how, derived, bent = linear_limit(w, L, small, cap, fixed_gain)
    fit = regression(w, L, max_lateral=limit, fixed_gain=fixed_gain)
    if fit is not None:
        fit.limit_how, fit.limit_derived, fit.limit_bent = how, derived, bent
        fit.passed_over = int((np.abs(w["a_y"]) > limit).sum())
    return fit
