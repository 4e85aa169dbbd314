"""The ground's lean under the turns: gravity's lateral share g sin(bank) [m/s2].

On a road banked by ``bank`` the tyres carry the lateral specific force v r - g sin(bank) (bank
towards the turn's inside positive), not v r: the steady turn is delta = L r / v + K (v r - g sin(bank))
(+ the offset). Where the lean moves with the turns (a banked oval, a crowned curve) the term
K g sin(bank) rises and falls with L r / v and v r: a scale of the turns k, a steering gain and K
take it up alike, so none of them is told from it by a fit that leaves the lean out.

The log tells the lean by a ``bank`` column (the road's cross slope, rad) or a ``roll`` column (the
body's roll, rad: the road's plus the body's own lean on its springs), both right side down
positive (the aerospace and ROS convention alike), so gravity's share towards the left (the side
v r > 0 turns to) is -g sin(roll); or by a measured lateral specific force ``a_y`` (an IMU's, m/s2,
left positive; a column of measurements.audit.LATERAL): v r - a_y (one that falls as v r rises is not taken: read the other
way round, or a bank carrying more than the whole turn, the log cannot say which). On level
ground the body rolls out of the turn and its lean's share is against v r; only a lean into the
turns (a positive slope of the share on v r) is a bank that carries part of them. turns_lean says why K is not concluded when that slope exceeds LEAN_SHARE
beyond its 95 % interval.
"""
from __future__ import annotations

import math

import numpy as np

from agrobot.components.models.yaw_dynamics import GRAVITY
from agrobot.estimation import Z95
from agrobot.measurements.audit import LATERAL     # m/s2: the columns of a measured lateral specific force

LEAN_COLUMNS = ("bank", "roll")      # rad: the road's cross slope, the body's roll
# a tenth of the turns' v r from gravity moves K's steady steer by a tenth of K a_y: as much as a
# declared wheelbase 1-2 % off moves L r / v on the turns of a racecar (K a_y ~ 10 % of L / R)
LEAN_SHARE = 0.1
DECORRELATION = 1.0                  # s: the lean and the turns counted as one draw a second
STEEPEST = math.radians(45.0)        # rad: no ground a wheeled machine drives across leans further


def lean_column(frame) -> str | None:
    """The first of LEAN_COLUMNS the log carries with two finite samples or more (None: neither)."""
    return next((c for c in LEAN_COLUMNS if c in frame.columns and np.isfinite(frame[c].to_numpy(float)).sum() > 1),
                None)


def ground_lean(frame, t: np.ndarray, v: np.ndarray, r: np.ndarray) -> tuple[np.ndarray | None, str | None]:
    """(gravity's lateral share towards the left on the samples ``t`` [m/s2], where it comes from):
    -g sin(bank) from the log's bank or roll column, else v r - a_y from its measured lateral
    specific force; (None, None) without either, (None, why) for a column no ground's lean fits."""
    tf = frame["t"].to_numpy(float)
    name = lean_column(frame)
    if name is not None:
        x = frame[name].to_numpy(float)
        ok = np.isfinite(x)
        top = float(np.percentile(np.abs(x[ok]), 99))
        if top > STEEPEST:
            return None, (f"the log's {name} column reaches {math.degrees(top):.0f} deg (99th percentile of its size), "
                          f"beyond any ground a wheeled machine drives across ({math.degrees(STEEPEST):.0f} deg): not "
                          f"taken for the ground's lean (a column in degrees: --signal {name}={name}[deg])")
        return -GRAVITY * np.sin(np.interp(t, tf[ok], x[ok])), (f"the ground's lean from the log's {name} column [rad, "
                                                                f"right side down positive]")
    for name in LATERAL:
        if name in frame.columns and np.isfinite(frame[name].to_numpy(float)).sum() > 1:
            x = frame[name].to_numpy(float)
            ok = np.isfinite(x)
            a_y, turn = np.interp(t, tf[ok], x[ok]), v * r
            if not np.ptp(turn) > 0:
                return None, f"the log's {name}: no turns to read its sign against (v r constant); not taken for the ground's lean"
            slope = float(np.polyfit(turn, a_y, 1)[0])
            if slope <= 0:
                return None, (f"the log's {name} runs against v r ({slope:+.2g} m/s2 per m/s2): read right side "
                              f"positive (--signal {name}=-COLUMN turns it round), or a bank carrying more than the "
                              f"whole turn; not taken for the ground's lean")
            return turn - a_y, f"the ground's lean from v r less the log's {name} [m/s2, left positive]"
    return None, None


def lean_of_log(frame, log) -> np.ndarray | None:
    """ground_lean on a DrivingLog's samples, where it comes from (or why not) added to its notes."""
    lean, said = ground_lean(frame, log.t, log.v, log.r)
    log.notes.extend([said] if said else [])
    return lean


def turns_lean(lean: np.ndarray | None, v: np.ndarray, r: np.ndarray, h: float, moving: np.ndarray) -> str | None:
    """Why K (and a scale of the turns or a steering gain) is not concluded, or None: the lean's
    least-squares slope on v r over the ``moving`` samples (into the turns: positive) exceeds
    LEAN_SHARE beyond Z95 standard errors (one draw per DECORRELATION seconds), the banks of the top and bottom third of |v r| told."""
    if lean is None or moving.sum() < 10:
        return None
    a, g_lat = (v * r)[moving], lean[moving]
    var = float(np.var(a))
    if var <= 0:
        return None
    slope = float(np.mean((a - a.mean()) * (g_lat - g_lat.mean())) / var)
    resid = g_lat - g_lat.mean() - slope * (a - a.mean())
    n_eff = max(3.0, len(a) * h / DECORRELATION)
    se = float(np.std(resid) / math.sqrt(var * n_eff))
    if slope - Z95 * se <= LEAN_SHARE:
        return None
    lo, hi = np.percentile(np.abs(a), [100 / 3, 200 / 3])
    bank = [math.degrees(math.asin(float(np.clip(np.mean(x) / GRAVITY, -1, 1))))
            for x in ((np.sign(a) * g_lat)[np.abs(a) >= hi], np.abs(g_lat[np.abs(a) <= lo]))]
    return (f"the turns lean on a bank of {bank[0]:.1f} deg into them, the straights on {bank[1]:.1f} deg (mean over the "
            f"top and bottom third of |v r|): gravity's lateral share g sin(bank) moves with v r by {slope:+.2g} "
            f"+- {Z95 * se:.2g} m/s2 per m/s2 (more than {LEAN_SHARE:g}), and the steer it saves, K g sin(bank), "
            f"rises and falls with the turns as a scale of the turns or a steering gain would; K not concluded, no "
            f"scale of the turns fitted (the bank, roll or a_y column left out of the log, they are fitted as on "
            f"level ground)")
