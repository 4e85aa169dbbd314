"""Where a log turns, on the vehicle's own scale: the path curvature kappa = (r - b) / v (gyro yaw
rate r less its bias b, speed v), averaged over 1 s, against the log's own turns and its noise.

A fixed steering angle cannot say it for every machine: a racecar's oval turn of 330 m radius asks
0.009 rad of road wheel at 2.97 m of wheelbase, a tractor's 5 m headland turn 0.5 rad at 2.5 m,
and its weave along a row 0.02-0.03 rad. Curvature is the turn itself, whatever the wheelbase, the
steering's scale or unit, and the gyro gives it without the steering's offset. A sample turns where

    |kappa| > max(TURN_SHARE x the 95th percentile of |kappa| while moving,
                   TURN_NOISE x sigma_r / (v sqrt(n)))

the first, a quarter of the log's tight turns (the racecar's straights, 2e-4 1/m of weave, stay out
of its 0.003 1/m turns, a tractor's row weave out of its headland turns); the second, clear of the
noise the 1 s mean of n samples keeps of the gyro's white noise sigma_r (1.4826 median |r_i -
r_(i-1)| / sqrt 2, the differences' robust spread), which decides on a log without turns.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.ndimage import uniform_filter1d

TURN_SHARE = 0.25     # of the log's tight turns' curvature (95th percentile of |kappa|)
TURN_NOISE = 5.0      # x the 1 s mean curvature's noise level
AVERAGE = 1.0         # s


def turning(t_step: float, v: np.ndarray, r: np.ndarray, moving: np.ndarray, bias: float = 0.0) -> tuple[np.ndarray, float]:
    """(where the log turns, the threshold on |kappa| from the log's turns [1/m]) as the module says;
    ``moving``: the samples with a speed and a measured yaw rate; ``t_step``: the sample step [s]."""
    n = max(1, int(round(AVERAGE / t_step)))
    ok = moving & np.isfinite(r) & (v > 0)
    if ok.sum() < 10:
        return np.zeros(len(v), bool), math.nan
    kappa = uniform_filter1d(np.where(ok, (r - bias) / np.where(ok, v, 1.0), 0.0), n, mode="nearest")
    share = TURN_SHARE * float(np.percentile(np.abs(kappa[ok]), 95))
    rr = r[ok]
    sigma_r = 1.4826 * float(np.median(np.abs(np.diff(rr)))) / math.sqrt(2) if len(rr) > 1 else 0.0
    noise = TURN_NOISE * sigma_r / (np.where(ok, v, 1.0) * math.sqrt(n))
    return ok & (np.abs(kappa) > np.maximum(share, noise)), share
