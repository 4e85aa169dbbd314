"""Whether a recorded steering angle is the road wheel's or the handwheel's, read from the log's turns.

A turn in the tyres' linear range has r = v delta / (L + K v^2) (Rajamani, Vehicle Dynamics, 3.3): the
yaw rate per kinematic turn rate, s = r / (v delta / L), is about 1 for a road-wheel angle (a little less
with understeer) and about 1 / ratio for a handwheel angle ``ratio`` times larger. The study's steering
ratio is divided into the angle only when the turns say it is the handwheel's; a ratio given on the
command line is taken as given. An angle in degrees read as radians has 1 / 57.3 of its slope: a
road-wheel angle in degrees would look nearer a handwheel's than a road wheel's, so the degrees
readings are scored beside them and, nearest, refused with the unit to declare.
"""
from __future__ import annotations

import math

import numpy as np

from .log import LogError

MOVING = 1.0          # m/s: turns read above this speed (forward)
LINEAR_AY = 4.0       # m/s2: turns read below this lateral acceleration (the tyres' linear range)
MIN_TURNING = 0.02    # rad/s: std of the yaw rate over them (the turns must move it)
MIN_CORRELATION = 0.5  # of r against v delta / L: below it the slope says nothing
MARGIN = math.log(2.0)  # the nearer reading must be this much nearer (log of the slope) to be decided
DEGREE = 180 / math.pi  # an angle in degrees read as radians: its slope 1 / 57.3 of the truth's


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
    return slope_on_turns(v, delta, r, v > MOVING, wheelbase)


def slope_on_turns(v: np.ndarray, delta: np.ndarray, r: np.ndarray, use: np.ndarray, wheelbase: float
                   ) -> tuple[float, float, int] | None:
    """(s, correlation, samples): the least-squares slope s of the yaw rate ``r`` on v delta / L (with
    an offset) over the samples ``use`` with a finite delta and |v r| < LINEAR_AY; None under 20 of
    them or with the yaw rate moving less than MIN_TURNING (std) over them."""
    use = use & np.isfinite(delta) & np.isfinite(r) & (np.abs(v * r) < LINEAR_AY)
    if use.sum() < 20 or np.std(r[use]) < MIN_TURNING:
        return None
    x = v[use] * delta[use] / wheelbase
    A = np.c_[x, np.ones_like(x)]
    s = float(np.linalg.lstsq(A, r[use], rcond=None)[0][0])
    corr = float(np.corrcoef(x, r[use])[0, 1]) if np.std(x) > 0 else 0.0
    return s, corr, int(use.sum())


def road_wheel_or_handwheel(slope: tuple[float, float, int] | None, ratio: float,
                            where: str = "delta") -> tuple[bool | None, str]:
    """(True: a handwheel angle, divide by ``ratio``; False: the road wheel's already; None: the turns
    cannot tell; why). Decided by the reading whose slope lies nearer 1 (log scale) by MARGIN, of four:
    the road wheel's or the handwheel's, in radians or in degrees (57.3 s or 57.3 s ratio near 1);
    a degrees reading nearest raises LogError naming ``where`` (the file and column) and the unit to
    declare: no ratio is chosen for an angle in other units."""
    if slope is None:
        return None, "the log has no turns to read it from (delta, a yaw rate and a speed over 1 m/s, " \
                     f"|a_y| < {LINEAR_AY:g} m/s2, the yaw rate moving {MIN_TURNING:g} rad/s or more)"
    s, corr, n = slope
    said = f"the turns' yaw rate is {s:.3g} x v delta / L (correlation {corr:.2f}, {n} samples, |a_y| < {LINEAR_AY:g} m/s2)"
    if s <= 0 or corr < MIN_CORRELATION:
        return None, f"{said}: not a turn's slope"
    readings = sorted((abs(math.log(s * k * unit)), s * k * unit, part + (" in degrees" if unit != 1.0 else ""))
                      for k, part in ((1.0, "road wheel"), (ratio, "handwheel")) for unit in (1.0, DEGREE))
    (near, _, first), (second, _, other) = readings[0], readings[1]
    if second - near < MARGIN:
        return None, f"{said}: read as the {first} about as near 1 as read as the {other}"
    if first.endswith("in degrees"):
        raise LogError(f"{where}: {said}: nearest 1 read as the {first} ({readings[0][1]:.3g}), not as an angle in "
                       f"radians; expected radians: declare its unit with --signal delta=COLUMN[deg] (no steering "
                       f"ratio chosen)")
    if first == "road wheel":
        return False, f"{said}, nearer 1 than {s * ratio:.3g} (x {ratio:g}): delta is the road-wheel angle"
    return True, f"{said}, {s * ratio:.3g} divided by {ratio:g}: delta is the handwheel's angle"
