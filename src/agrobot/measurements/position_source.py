"""Whose positions are x, y: a receiver's fixes or an estimate (a localisation filter, odometry)?

Read from the positions alone, in the track's frame (the course over a chord of about 2 s). A
fix's second difference is a h^2 plus its white noise (variance 6 sigma^2 per axis), and a
receiver knows nothing of the vehicle's course: its noise is the same across the track as along
it, whatever the rate or the noise level. An estimate's motion model holds it to the course (the
wheels do not slide sideways): what fix-to-fix scatter it has lies along the track (a clock's or
an odometry's error, proportional to the speed), or it has none (a dead-reckoned path: smooth in
both directions). Whiteness is read as MAD(third difference) / MAD(second difference): sqrt(20 / 6)
= 1.83 for white noise, far below 1 for a smooth path.

    measured  <=>  white both ways (whiteness >= WHITE), less than ALONG x as much along as across,
                   and above ROUNDING x the values' own rounding (rounding_sigma)
    estimate  <=>  not measured, and: white along the track and at least ALONG x the across-track
                   noise, or smooth both ways (each direction's whiteness under SMOOTH or its
                   white noise under FLOOR, below any receiver's)

Anything else (noise the same both ways; a low-rate fix whose turns outweigh its noise across the
track) is not called an estimate: a receiver's fixes of any rate and noise level are not, nor a
motion capture's (finer than FLOOR, but white and the same both ways). The rounding's sigma is the
smallest step between stored values / sqrt 12 (not measurements.log.resolution, a grid's step): a smooth path stored in
float32 a kilometre from its origin carries 0.02 mm of white rounding noise, no measurement's. A
scan-matching filter's poses can scatter like fixes; their source's name then tells (named_estimate:
a topic or file of odometry, a pose, a filter, unless it names a receiver too).
"""
from __future__ import annotations

import math
import re

import numpy as np

WHITE = 1.4          # whiteness at or above it: white noise dominates (white noise 1.83)
SMOOTH = 0.5         # whiteness below it: no white noise at all (a dead-reckoned or filtered path)
FLOOR = 0.5e-3       # m: white noise below it is no receiver's (an RTK fix's carrier-phase noise is millimetres)
ROUNDING = 3.0       # white noise within this many rounding sigmas is the stored values' rounding
ALONG = 2.0          # along-track noise this many times the across-track: held to the course by a model
CHORD = 1.0          # s either side: the course the frame is turned to
MOVING = 20.0        # a fix counts where the chord is this many noise sigmas long (the course is known)
MIN_FIXES = 30       # moving fixes needed to tell
ESTIMATOR = re.compile(r"odom|pose|locali[sz]|ekf|ukf|filter|fused|fusion|slam|amcl|estimat", re.IGNORECASE)
RECEIVER = re.compile(r"gps|gnss|navsat|nmea|rtk|gga|fix|receiver", re.IGNORECASE)


MAD_NORMAL = 0.6745  # the median |x| of zero-mean normal noise, in its sigmas


def _mad(a: np.ndarray) -> float:
    return float(np.median(np.abs(a))) / MAD_NORMAL if len(a) else math.nan


def white_noise_sigma(second_difference_sigma):
    """The sigma of white position noise from its second differences' (MAD / MAD_NORMAL): / sqrt 6,
    var(x[i+1] - 2 x[i] + x[i-1]) = 6 sigma^2."""
    return second_difference_sigma / math.sqrt(6.0)


def rounding_sigma(x: np.ndarray, y: np.ndarray) -> float:
    """The positions' rounding sigma [m]: their smallest nonzero step / sqrt 12 (0 with none)."""
    steps = np.abs(np.r_[np.diff(x), np.diff(y)])
    steps = steps[np.isfinite(steps) & (steps > 0)]
    return float(steps.min()) / math.sqrt(12.0) if len(steps) else 0.0


def track_noise(t: np.ndarray, x: np.ndarray, y: np.ndarray) -> dict | None:
    """{along, across [m], white_along, white_across, fixes, hz, rounding}: the white-noise sigma of the
    positions' updates (a held row is not one) along and across the course, from their second
    differences (MAD / 0.6745 / sqrt 6), and each direction's whiteness (module docstring). None
    under MIN_FIXES moving fixes."""
    ok = np.isfinite(t) & np.isfinite(x) & np.isfinite(y)
    t, x, y = t[ok], x[ok], y[ok]
    if len(t) < MIN_FIXES + 4:
        return None
    update = np.r_[True, (np.diff(x) != 0) | (np.diff(y) != 0)]
    t, x, y = t[update], x[update], y[update]
    n = len(t)
    h = float(np.median(np.diff(t))) if n > 1 else 0.0
    if n < MIN_FIXES + 4 or not h > 0:
        return None
    i = np.arange(n)
    k = max(2, int(round(CHORD / h)))
    lo, hi = np.clip(i - k, 0, n - 1), np.clip(i + k, 0, n - 1)
    cx, cy = x[hi] - x[lo], y[hi] - y[lo]
    chord = np.hypot(cx, cy)
    ux, uy = (np.divide(c, chord, out=np.zeros(n), where=chord > 0)[1:-2] for c in (cx, cy))
    d2x, d2y = np.diff(x, 2)[:-1], np.diff(y, 2)[:-1]
    d3x, d3y = np.diff(x, 3), np.diff(y, 3)
    sigma = white_noise_sigma(_mad(np.r_[d2x, d2y]))
    moving = chord[1:-2] > MOVING * max(sigma, 1e-6)
    if moving.sum() < MIN_FIXES:
        return None
    out = {"fixes": int(moving.sum()), "hz": 1.0 / h, "rounding": rounding_sigma(x, y)}
    for name, (ax, ay) in (("along", (ux, uy)), ("across", (-uy, ux))):
        d2, d3 = (dx * ax + dy * ay for dx, dy in ((d2x, d2y), (d3x, d3y)))
        spread = _mad(d2[moving])
        out[name] = white_noise_sigma(spread)
        out[f"white_{name}"] = _mad(d3[moving]) / spread if spread > 0 else 0.0
    return out


def estimate_evidence(noise: dict | None) -> str | None:
    """Why positions with this ``noise`` (track_noise) are an estimate, or None (a receiver's, or
    too few moving fixes to tell)."""
    if noise is None:
        return None
    said = (f"fix-to-fix noise {1000 * noise['along']:.3g} mm along the track, {1000 * noise['across']:.3g} mm "
            f"across (whiteness {noise['white_along']:.2f}, {noise['white_across']:.2f}; white noise 1.83) in "
            f"{noise['fixes']} moving fixes at {noise['hz']:.3g} Hz")
    if all(noise[f"white_{d}"] >= WHITE and noise[d] > ROUNDING * noise["rounding"] for d in ("along", "across")) \
            and noise["along"] < ALONG * noise["across"]:
        return None                 # a measurement's white noise, the same both ways
    if noise["white_along"] >= WHITE and noise["along"] >= ALONG * noise["across"]:
        return (f"{said}: a motion model holds them to the course (a receiver's noise is the same across the track "
                f"as along it)")
    if all(noise[f"white_{d}"] < SMOOTH or noise[d] < FLOOR for d in ("along", "across")):
        return (f"{said}: smooth both ways, no fix's own noise (a receiver's fixes carry white noise of "
                f"{1000 * FLOOR:g} mm or more)")
    return None


def named_estimate(source: str) -> str | None:
    """Why a position column whose source is ``source`` (its file, topic, field) is an estimate by
    its name (odometry, a pose, a filter; none that names a receiver too: a navsat transform's
    odometry is a receiver's fixes), or None."""
    word = ESTIMATOR.search(source or "")
    if word is None or RECEIVER.search(source):
        return None
    return f"its source {source.split(' ')[0]!r} names an estimator ({word.group(0)!r})"
