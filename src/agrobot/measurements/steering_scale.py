"""Whether a recorded steering angle is the road wheel's or the handwheel's, read from the log's turns.

A turn in the tyres' linear range has r = v delta / (L + K v^2) (Rajamani, Vehicle Dynamics, 3.3): the
yaw rate per kinematic turn rate, s = r / (v delta / L), is about 1 for a road-wheel angle (a little less
with understeer) and about 1 / ratio for a handwheel angle ``ratio`` times larger. The study's steering
ratio is divided into the angle only when the turns say it is the handwheel's; a ratio given on the
command line is taken as given.
"""
from __future__ import annotations

import math

import numpy as np

MOVING = 1.0          # m/s: turns read above this speed (forward)
LINEAR_AY = 4.0       # m/s2: turns read below this lateral acceleration (the tyres' linear range)
MIN_TURNING = 0.02    # rad/s: std of the yaw rate over them (the turns must move it)
MIN_CORRELATION = 0.5  # of r against v delta / L: below it the slope says nothing
MARGIN = math.log(2.0)  # the nearer reading must be this much nearer (log of the slope) to be decided


def _on_clock(t, signal):
    ts, vs = signal
    ok = np.isfinite(vs)
    return np.interp(t, np.asarray(ts, float)[ok], np.asarray(vs, float)[ok]) if ok.sum() > 1 else None


def turn_slope(signals: dict, gnss, wheelbase: float) -> tuple[float, float, int] | None:
    """(s, correlation, samples): the least-squares slope s of the yaw rate on v delta / L (with
    an offset) over the samples moving forward above MOVING with |v r| < LINEAR_AY, delta's clock;
    None without delta, a yaw rate and a speed (a signal v, else the receiver's), or turns."""
    if "delta" not in signals or "yaw_rate" not in signals:
        return None
    speed = signals.get("v")
    if speed is None and gnss is not None and "speed" in gnss and "utc" in gnss:
        speed = (gnss["utc"].to_numpy(float), gnss["speed"].to_numpy(float))
    if speed is None:
        return None
    t, delta = (np.asarray(x, float) for x in signals["delta"])
    r, v = _on_clock(t, signals["yaw_rate"]), _on_clock(t, speed)
    if r is None or v is None:
        return None
    use = np.isfinite(delta) & (v > MOVING) & (np.abs(v * r) < LINEAR_AY)
    if use.sum() < 20 or np.std(r[use]) < MIN_TURNING:
        return None
    x = v[use] * delta[use] / wheelbase
    A = np.c_[x, np.ones_like(x)]
    s = float(np.linalg.lstsq(A, r[use], rcond=None)[0][0])
    corr = float(np.corrcoef(x, r[use])[0, 1]) if np.std(x) > 0 else 0.0
    return s, corr, int(use.sum())


def road_wheel_or_handwheel(slope: tuple[float, float, int] | None, ratio: float) -> tuple[bool | None, str]:
    """(True: a handwheel angle, divide by ``ratio``; False: the road wheel's already; None: the turns
    cannot tell; why). Decided by the reading whose slope lies nearer 1 (log scale) by MARGIN."""
    if slope is None:
        return None, "the log has no turns to read it from (delta, a yaw rate and a speed over 1 m/s, " \
                     f"|a_y| < {LINEAR_AY:g} m/s2, the yaw rate moving {MIN_TURNING:g} rad/s or more)"
    s, corr, n = slope
    said = f"the turns' yaw rate is {s:.3g} x v delta / L (correlation {corr:.2f}, {n} samples, |a_y| < {LINEAR_AY:g} m/s2)"
    if s <= 0 or corr < MIN_CORRELATION:
        return None, f"{said}: not a turn's slope"
    road, hand = abs(math.log(s)), abs(math.log(s * ratio))
    if abs(road - hand) < MARGIN:
        return None, f"{said}: about as near 1 as {s * ratio:.3g} divided by {ratio:g}"
    if road < hand:
        return False, f"{said}, nearer 1 than {s * ratio:.3g} (x {ratio:g}): delta is the road-wheel angle"
    return True, f"{said}, {s * ratio:.3g} divided by {ratio:g}: delta is the handwheel's angle"
