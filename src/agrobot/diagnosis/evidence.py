"""What the baseline gets wrong, stage by stage: residual statistics that point
at a cause before any extension is fitted.

- spectrum: Welch estimate of the residual's power spectral density;
- cross-correlation with each input, lags -2..2 s, with the 95% bound 1.96/sqrt(N) of white
  residuals (a delay shows as a peak at a positive lag; a missing input as a peak at zero);
- binned: residual mean and RMS (with the standard error of the mean) by speed and by steering
  amplitude (a bias is flat in speed, a steering offset grows with it, a dead-band lives at
  small amplitudes).
"""
from __future__ import annotations

import numpy as np
from scipy.signal import welch

SPEED_BINS = (0.0, 0.75, 1.5, 2.5, 3.5, 10.0)
AMPLITUDE_BINS_DEG = (0.0, 2.0, 5.0, 10.0, 20.0, 90.0)


def spectrum(res: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    f, p = welch(res - res.mean(), fs=fs, nperseg=min(len(res), 256))
    return f, p


def cross_correlation(res: np.ndarray, x: np.ndarray, fs: float, max_lag: float = 2.0):
    """(lags [s], rho, bound): rho[l] = corr(res[k], x[k - l]); positive lag = residual after input."""
    r = (res - res.mean()) / (res.std() or 1.0)
    u = (x - x.mean()) / (x.std() or 1.0)
    n = len(r)
    L = int(round(max_lag * fs))
    lags = np.arange(-L, L + 1)
    rho = np.array([np.mean(r[max(l, 0):n + min(l, 0)] * u[max(-l, 0):n - max(l, 0)]) for l in lags])
    return lags / fs, rho, 1.96 / np.sqrt(n)


def binned(res: np.ndarray, by: np.ndarray, edges) -> list[dict]:
    rows = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = (by >= lo) & (by < hi)
        if sel.sum() < 10:
            continue
        r = res[sel]
        rows.append({"from": lo, "to": hi, "n": int(sel.sum()), "mean": float(r.mean()),
                     "rms": float(np.sqrt(np.mean(r ** 2))), "sem": float(r.std() / np.sqrt(sel.sum()))})
    return rows


def stage_evidence(replay, stage: str, values: dict[str, float]) -> dict:
    """The residual analysis of one stage under ``values`` (both parts of the log)."""
    fs = 1.0 / replay.h
    if stage == "position":
        out = {f"rms_{part}": float(np.sqrt(np.mean(r ** 2)))
               for part, r in zip(("fit", "test"), replay.residuals(stage, values, "fit", "test"))}
        t, r = replay.residual_series(stage, values)
        out["worst_windows"] = [{"t_start": float(t[i]), "error": float(r[i])} for i in np.argsort(r)[-3:][::-1]]
        return out
    sel = replay.scored(stage)
    _, res = replay.residual_series(stage, values)
    inputs = {"delta_cmd": replay.cmd[sel]} if stage == "steering" else \
        {"delta": replay.delta[sel], "v": replay.speed[sel]}
    out = {f"rms_{part}": float(np.sqrt(np.mean(r ** 2)))
           for part, r in zip(("fit", "test"), replay.residuals(stage, values, "fit", "test"))}
    out["mean"] = float(res.mean())
    f, p = spectrum(res, fs)
    out["spectrum_peak_hz"] = float(f[1:][np.argmax(p[1:])])
    xc = {}
    for name, x in inputs.items():
        lags, rho, bound = cross_correlation(res, x, fs)
        i = int(np.argmax(np.abs(rho)))
        xc[name] = {"peak": float(rho[i]), "lag_s": float(lags[i]), "bound": float(bound),
                    "outside_bound": bool(abs(rho[i]) > bound)}
    out["cross_correlation"] = xc
    out["by_speed"] = binned(res, replay.speed[sel], SPEED_BINS)
    steer = replay.cmd if "steering" in replay.stages else replay.delta      # a log without a command: the angle
    out["by_steering_amplitude_deg"] = binned(res, np.degrees(np.abs(steer[sel])), AMPLITUDE_BINS_DEG)
    return out
