"""What the Brain Corp tricycle's yaw-rate misfit is made of, numpy only on its derived log
(``python3 benchmarks/tricycle_yaw_lag.py [--corpus DIR] [--log N]``).

The kinematic yaw rate of the rear axle r = v tan(delta) / L (v = v_front cos(delta): the same as
v_front sin(delta) / L) against the logged gyro ("filtered", dataset.txt), each candidate fitted on
the first 60 % (t < 112.7 s in dataset1, diagnose's split) and judged on the rest:
a gain g, a first-order gyro filter tau (tau y' = g r - y), a pure delay, and their pairs; and the
residual's white level (the top 0.35-0.5 fs of its spectrum, diagnosis.noise_floor.white_level)
on the rows as logged and after linear interpolation onto an even grid (what the import does with
jittered stamps), against the held-out RMS; and the same two on unit white noise stamped with a
known jitter (the interpolation's own effect on the floor).
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
from scipy.optimize import minimize
from scipy.signal import lfilter

from agrobot.diagnosis.noise_floor import white_level

WHEELBASE = 0.964          # m, dataset.txt
SPLIT = 0.6                # share of the log fitted (diagnose holds out the last 40 %)
SPIKE = 2.5                # m/s: a front-wheel speed above it is a near-duplicate stamp's difference
CANDIDATES = {"gain": (0,), "gyro first-order filter": (1,), "pure delay": (2,), "filter + gain": (0, 1),
              "delay + gain": (0, 2)}


def load(path: Path) -> dict[str, np.ndarray]:
    t, d, _, r, vf = np.genfromtxt(path, delimiter=",", skip_header=1).T
    bad = np.abs(vf) > SPIKE
    vf[bad] = np.interp(t[bad], t[~bad], vf[~bad])
    return {"t": t, "delta": d, "v": vf * np.cos(d), "v_front": vf, "r": r, "h": float(np.median(np.diff(t)))}


def predicted(log: dict, gain: float, tau: float, lag: float) -> np.ndarray:
    """g x the kinematic yaw rate lag s late, through a first-order filter of tau."""
    t, h = log["t"], log["h"]
    x = gain * np.interp(t - lag, t, log["v"] * np.tan(log["delta"]) / WHEELBASE)
    if tau <= 1e-4:
        return x
    a = math.exp(-h / tau)
    return lfilter([1 - a], [1, -a], x, zi=[a * x[0]])[0]


def fitted(log: dict, free: tuple[int, ...], fit: np.ndarray) -> np.ndarray:
    """(gain, tau, lag) least-squares on ``fit`` over the ``free`` ones (the rest 1, 0, 0)."""
    def values(q):
        p = np.array([1.0, 0.0, 0.0])
        p[list(free)] = q
        return p[0], abs(p[1]), abs(p[2])

    def cost(q):
        return float(np.mean((log["r"] - predicted(log, *values(q)))[fit] ** 2))
    start = np.array([1.0, 0.05, 0.05])[list(free)]
    return np.array(values(minimize(cost, start, method="Nelder-Mead").x))


def deg(x: np.ndarray, m: np.ndarray) -> float:
    return math.degrees(math.sqrt(float(np.mean(x[m] ** 2))))


def interpolated_white(jitter: float, h: float, n: int = 6000, seed: int = 0) -> tuple[float, float]:
    """(white level, RMS) of unit white noise on rows stamped h (1 + jitter N(0, 1)) apart, put on an
    even grid of their median step by linear interpolation (truth: 1, 1)."""
    rng = np.random.default_rng(seed)
    dt = h * (1 + jitter * rng.standard_normal(n))
    t, x = np.cumsum(dt), rng.standard_normal(n)
    y = np.interp(np.arange(t[0], t[-1], np.median(dt)), t, x)
    return white_level(y, 1 / h), float(y.std())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--corpus", type=Path, default=Path("/work/corpus_data"))
    ap.add_argument("--log", type=int, default=1, help="dataset number (0-5; diagnose's benchmark reads 1)")
    a = ap.parse_args()
    log = load(a.corpus / "braincorp_tricycle_pose_estimator" / "derived" / f"dataset{a.log}_log.csv")
    t, r, h = log["t"], log["r"], log["h"]
    fit = t < t[0] + SPLIT * (t[-1] - t[0])
    test = ~fit
    base = deg(r - predicted(log, 1.0, 0.0, 0.0), test)
    front = deg(r - log["v_front"] * np.tan(log["delta"]) / WHEELBASE, test)
    print(f"dataset{a.log}: held-out RMS of r = v tan(delta)/L: {base:.2f} deg/s "
          f"(v_front tan(delta)/L, the front wheel taken as the rear axle's speed: {front:.2f})")
    for name, free in CANDIDATES.items():
        p = fitted(log, free, fit)
        e = deg(r - predicted(log, *p), test)
        print(f"  {name:24s} g {p[0]:.3f}  tau {p[1]:.3f} s  lag {p[2]:.3f} s: {e:.2f} deg/s "
              f"({100 * (1 - e / base):.0f} % off)")
    e = r - predicted(log, *fitted(log, (0, 1), fit))
    even = np.arange(t[0], t[-1], h)
    e_even = np.interp(even, t, e)
    standing = np.abs(log["v_front"]) < 0.02
    lv = {k: math.degrees(white_level(x, 1 / h)) for k, x in
          (("rows", e), ("fit", e[fit]), ("test", e[test]), ("even", e_even), ("standing", r[standing]))}
    print(f"filter + gain residual, white level [deg/s]: rows as logged {lv['rows']:.2f} (fit part {lv['fit']:.2f}, "
          f"held-out {lv['test']:.2f}; the gyro standing still {lv['standing']:.2f}); on an even grid "
          f"{lv['even']:.2f}; stamp jitter std(dt)/h {np.std(np.diff(t)) / h:.2f}")
    print(f"held-out RMS / white level: rows as logged {deg(e, test) / lv['rows']:.2f}; "
          f"even grid {deg(e_even, even >= t[test][0]) / lv['even']:.2f}")
    for jitter in (0.0, 0.01, 0.05):
        level, rms = interpolated_white(jitter, h)
        print(f"unit white noise, stamp jitter {jitter:g} h, interpolated onto an even grid: white level {level:.2f}, "
              f"RMS {rms:.2f}")
    print(f"mean front-wheel speed: fit part {log['v_front'][fit].mean():.2f} m/s, held-out "
          f"{log['v_front'][test].mean():.2f} m/s")


if __name__ == "__main__":
    main()
