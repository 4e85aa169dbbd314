"""A steering-ratio curve or tyre saturation: the variable the yaw gain bends with, and whether the
log's turns can tell the two apart.

In a steady turn the linear single-track model turns at

    r = v delta_w / (L + K v^2),    K = m (l_r / C_f - l_f / C_r) / L    [rad/(m/s2)],

so it carries the lateral acceleration a_ss = v^2 delta_w / (L + K v^2). A ratio curve bends the
wheel angle, delta_w = delta (1 + c delta^2): the relative yaw gain r (L + K v^2) / (v delta) is
1 + c delta^2, a function of the reading delta alone, at every speed and lateral acceleration. Tyre
saturation bends each axle's force below C alpha as its slip grows, and an axle's steady slip is set
by the force it carries (m l_r a_y / L at the front): the gain falls with a_y = v r, whatever delta.

Turns driven at one speed have a_ss = delta x one constant: the two bends are then one function of
delta, and no fit can tell them apart (any bend with delta is some tyre curve's bend with a_y).
Turns at several speeds put one delta at several a_y: the more the speeds spread, the less delta and
a_ss go together. ``turn_collinearity`` measures it by the correlation of |delta| and a_ss over the
log's hard turns (moving, |v r| at least HARD_TURN of its 99th percentile). a_ss, not the measured
v r: the yaw rate lags the steering by the yaw dynamics, which spreads the measured pair on any log,
one speed or several, without telling the steady bends apart.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .plausibility import study_understeer

COLLINEAR = 0.99     # |delta| and a_ss correlated at least this much in the hard turns: one function of each other
HARD_TURN = 0.5      # the hard turns: |v r| at least this share of the log's 99th percentile (where the bends act)
MIN_TURNS = 20       # fewer hard-turn samples: no measure


@dataclass(frozen=True)
class Collinearity:
    """The correlation of |delta| and a_ss over the hard turns, their number and their speeds [m/s]
    (10th and 90th percentiles)."""

    correlation: float
    samples: int
    speeds: tuple[float, float]

    @property
    def collinear(self) -> bool:
        return self.correlation >= COLLINEAR

    def text(self) -> str:
        return (f"|delta| and the steady lateral acceleration v^2 delta / (L + K v^2) correlate at "
                f"{self.correlation:.3f} over the {self.samples} samples of its hard turns (|v r| >= "
                f"{HARD_TURN:g} x its 99th percentile), driven at {self.speeds[0]:.3g}-{self.speeds[1]:.3g} m/s "
                f"(10th-90th percentile)")


def turn_collinearity(replay) -> Collinearity | None:
    """The hard turns' Collinearity on ``replay`` (its baseline's m, l_f, l_r, C_f, C_r give K), or None
    with fewer than MIN_TURNS such samples or no spread of the steering in them."""
    v, r, delta = (np.nan_to_num(np.asarray(x, float)) for x in (replay.speed, replay.gyro, replay.delta))
    moving = v > replay.min_speed
    if moving.sum() < MIN_TURNS:
        return None
    a_y = np.abs(v * r)
    turns = moving & (a_y >= HARD_TURN * np.percentile(a_y[moving], 99))
    p = replay.baseline.tractor
    wheelbase = p.l_f + p.l_r
    understeer = study_understeer(p)
    steady = v[turns] ** 2 * np.abs(delta[turns]) / (wheelbase + understeer * v[turns] ** 2)
    if turns.sum() < MIN_TURNS or np.std(delta[turns]) == 0 or np.std(steady) == 0:
        return None
    rho = float(np.corrcoef(np.abs(delta[turns]), steady)[0, 1])
    lo, hi = np.percentile(v[turns], [10, 90])
    return Collinearity(rho, int(turns.sum()), (float(lo), float(hi)))
