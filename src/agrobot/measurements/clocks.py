"""Clocks of a recording: the NMEA host clock against the receiver's UTC, and a CAN logger's clock
mapped onto UTC (measurements.recording's module docstring gives the model).

- NMEA host stamps: host = U0 + a + b (utc - U0), fitted as the lower envelope of the points (a
  linear programme: every stamp is at or after the line, the sum of distances least), because
  a sentence arrives after its epoch, never before. Drift is b - 1; the latency of each sentence
  beyond the envelope is named (median, 95 %, max). With |a| < ``SYNCED`` the host clock is taken
  to keep UTC and a is the least NMEA latency; otherwise a is mostly the clock's own offset, and
  the least latency cannot be told from it (taken as 0, said so).
- CAN timestamps on the same host clock (their span overlaps the NMEA host stamps): mapped by the
  same line. Otherwise the CAN clock is aligned by its content: the CAN speed against the GNSS
  speed, cross-correlated in windows (offset and drift from a line through the windows' lags).

Imported where used: scipy.signal (start-up: 0.35 s CPU on every command, which loads this module
through the reader registry).
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy.optimize import linprog

from .log import LogError
from .streams import gnss_speed, iso

SYNCED = 0.5          # s: a host clock this close to GPS time is taken to keep UTC


def lower_envelope(u: np.ndarray, h: np.ndarray) -> tuple[float, float]:
    """(a, b) of the line a + b u below every point (u_i, h_i) with the least summed distance."""
    if len(u) < 3 or np.ptp(u) <= 0:
        return float(np.min(h - u)), 1.0
    scale = float(np.ptp(u))
    x = (u - u[0]) / scale
    # maximise sum(a + b x_i) subject to a + b x_i <= h_i
    res = linprog(c=[-len(x), -float(x.sum())], A_ub=np.column_stack([np.ones_like(x), x]), b_ub=h,
                  bounds=[(None, None), (None, None)], method="highs")
    if not res.success:
        slope = 1.0
        return float(np.min(h - slope * (u - u[0]))), slope
    a, b = res.x
    return float(a - b * u[0] / scale), float(b / scale)


def content_lag(t_ref: np.ndarray, x_ref: np.ndarray, t_other: np.ndarray, x_other: np.ndarray,
                step: float = 0.02, window: tuple[float, float] | None = None, search: float | None = None) -> tuple[float, float]:
    """(tau, rho): x_other(t) follows x_ref(t + tau) best (cross-correlation of the mean-removed
    signals on a common ``step`` grid, refined by a parabola through the peak); ``window``
    limits the other signal's time span, ``search`` the lags around 0 (s)."""
    lo, hi = (t_other[0], t_other[-1]) if window is None else window
    grid_o = np.arange(lo, hi, step)
    if len(grid_o) < 20:
        return math.nan, 0.0
    xo = np.interp(grid_o, t_other, x_other)
    xo = xo - xo.mean()
    span = search if search is not None else (t_ref[-1] - t_ref[0]) + (hi - lo)
    grid_r = np.arange(lo - span, hi + span + step, step)
    xr = np.interp(grid_r, t_ref, x_ref, left=np.nan, right=np.nan)
    valid = np.isfinite(xr)
    xr = np.where(valid, xr - np.nanmean(xr), 0.0)
    from scipy.signal import correlate

    num = correlate(xr, xo, mode="valid", method="fft")
    count = correlate(valid.astype(float), np.ones_like(xo), mode="valid", method="fft")
    energy = correlate(xr ** 2, np.ones_like(xo), mode="valid", method="fft")
    ok = count > 0.5 * len(xo)
    rho = np.where(ok, num / np.sqrt(np.maximum(energy, 1e-12) * (xo @ xo)), -np.inf)
    peak, best = parabolic_peak(rho)
    return (float(grid_r[0] - lo + peak * step), best) if math.isfinite(peak) else (math.nan, 0.0)


def parabolic_peak(rho: np.ndarray) -> tuple[float, float]:
    """(index of the maximum refined by a parabola through it and its neighbours, the maximum);
    (nan, 0) when no value is finite."""
    k = int(np.argmax(rho))
    if not np.isfinite(rho[k]):
        return math.nan, 0.0
    frac = 0.0
    if 0 < k < len(rho) - 1 and np.isfinite(rho[k - 1]) and np.isfinite(rho[k + 1]):
        den = rho[k - 1] - 2 * rho[k] + rho[k + 1]
        frac = 0.5 * (rho[k - 1] - rho[k + 1]) / den if den < 0 else 0.0
    return k + frac, float(rho[k])


def align_clocks(epochs: pd.DataFrame, raw: dict, u0: float, gnss: pd.DataFrame):
    """The clocks' report and the map from CAN time to UTC."""
    out: dict = {"reference": "receiver UTC (NMEA GGA time and RMC/ZDA date)"}
    host = epochs["host"].to_numpy(float)
    utc = epochs["utc"].to_numpy(float)
    have_host = np.isfinite(host)
    can_lo = min(float(t[0]) for t, _ in raw.values())
    can_hi = max(float(t[-1]) for t, _ in raw.values())
    line = None
    if have_host.sum() >= 10:
        u, h = utc[have_host], host[have_host]
        a, b = lower_envelope(u - u0, h - u0)
        late = (h - u0) - (a + b * (u - u0))
        synced = abs(a) < SYNCED
        out["nmea_host_clock"] = {
            "offset_s": a, "drift_ppm": (b - 1.0) * 1e6,
            "interpretation": ("the host clock keeps GPS time (offset below 0.5 s): the offset is the least NMEA "
                               "latency" if synced else
                               "the host clock is off GPS time by the offset; the least NMEA latency cannot be told "
                               "from it and is taken as 0"),
            "nmea_latency_s": {"least": a if synced else 0.0, "median": float(np.median(late)) + (a if synced else 0.0),
                               "p95": float(np.percentile(late, 95)) + (a if synced else 0.0),
                               "max": float(late.max()) + (a if synced else 0.0)}}
        if can_hi > h.min() - 60 and can_lo < h.max() + 60:
            line = (0.0, 1.0) if synced else (a, b)
    if line is not None:
        a, b = line
        out["can_clock"] = {"method": "same host clock as the NMEA stamps", "offset_s": a, "drift_ppm": (b - 1.0) * 1e6}
        return out, (lambda t: u0 + (t - u0 - a) / b)
    # an independent clock: align the CAN speed on the GNSS speed
    if "v" not in raw:
        raise LogError("the CAN log's clock is not the NMEA host clock and the CAN log carries no speed to align it on "
                       "the GNSS speed: record NMEA with host timestamps on the CAN logger's clock, or a speed on CAN")
    t_can, v_can = raw["v"]
    speed = gnss_speed(gnss)
    t_ref = gnss["utc"].to_numpy(float)
    start = t_ref[0] - t_can[0]                   # both clocks started together, then the content decides
    tau, rho = content_lag(t_ref, speed, t_can + start, v_can)
    tau += start
    if not math.isfinite(tau) or rho < 0.5:
        raise LogError(f"the CAN log's clock ({iso(can_lo)} ...) is not the NMEA "
                       f"host clock and its speed does not match the GNSS speed (best correlation {rho:.2f}): cannot "
                       f"place the CAN data in time; record NMEA with host timestamps on the CAN logger's clock")
    windows, lags = [], []
    for lo in np.arange(t_can[0], t_can[-1] - 60.0, 60.0):
        lag, r = content_lag(t_ref, speed, t_can + tau, v_can, window=(lo + tau, lo + tau + 120.0), search=2.0)
        lag_abs = tau + lag if math.isfinite(lag) else math.nan
        if r > 0.8 and math.isfinite(lag_abs):
            windows.append(lo + 60.0)
            lags.append(lag_abs)
    drift = 0.0
    if len(windows) >= 5:          # a drift only where the windows' lags resolve it (slope > 3 standard errors)
        x = np.array(windows) - t_can[0]
        fit, cov = np.polyfit(x, lags, 1, cov=True)
        if abs(fit[0]) > 3.0 * math.sqrt(max(cov[0, 0], 0.0)):
            drift, tau = float(fit[0]), float(fit[1])
    t_start = float(t_can[0])

    def tau_at(t):
        return tau + drift * (t - t_start)
    out["can_clock"] = {"method": "independent clock, aligned by the CAN speed against the GNSS speed "
                                  "(a GPS latency cannot be told from this offset)",
                        "offset_s": float(tau), "drift_ppm": drift * 1e6, "correlation": rho, "windows": len(windows)}
    return out, (lambda t: t + tau_at(t))
