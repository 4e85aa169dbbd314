"""The speed profile: working speed on swaths and headland passes, turn speed in turns and
transits, changing at most at the acceleration a, from a crawl at the start to one at the end.

The highest such speed is, on segment k from s = a_k to b_k with target T_k,

    v(s) = min(T_k, sqrt(F_k^2 + 2 a (s - a_k)), sqrt(V_k^2 + 2 a (b_k - s)))

F_k the speed the forward pass (v^2 <= v0^2 + 2 a ds from behind) brings into the segment and
V_k the speed the backward pass lets it leave with: both passes over the segment ends only, so
the profile costs nothing per metre and is exact at any s.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .settings import Settings
from .types import WORKING

CRAWL = 0.3         # m/s at the route's ends (a reference that moves off)


@dataclass(frozen=True, eq=False)
class SpeedProfile:
    starts: np.ndarray          # a_k [m]
    ends: np.ndarray            # b_k [m]
    target: np.ndarray          # T_k [m/s]
    entry: np.ndarray           # F_k [m/s]
    exit: np.ndarray            # V_k [m/s]
    acceleration: float         # a [m/s^2]

    def at(self, k: np.ndarray, s: np.ndarray) -> np.ndarray:
        """v at arc lengths s on segments k."""
        a2 = 2.0 * self.acceleration
        up = np.sqrt(self.entry[k] ** 2 + a2 * np.maximum(s - self.starts[k], 0.0))
        down = np.sqrt(self.exit[k] ** 2 + a2 * np.maximum(self.ends[k] - s, 0.0))
        return np.minimum(self.target[k], np.minimum(up, down))

    def ramps(self, k: int) -> tuple[tuple[float, float], tuple[float, float]]:
        """((a, where the speed-up ends), (where the slow-down starts, b)) of segment k."""
        a2 = 2.0 * self.acceleration
        a, b, T = self.starts[k], self.ends[k], self.target[k]
        up = min(b, a + max(T ** 2 - self.entry[k] ** 2, 0.0) / a2)
        down = max(a, b - max(T ** 2 - self.exit[k] ** 2, 0.0) / a2)
        return (a, up), (down, b)

    def time(self) -> float:
        """The time [s] the profile takes: int ds / v, on each piece in closed form (int ds /
        sqrt(c + 2 a s) = sqrt(c + 2 a s) / a)."""
        acc, a2, total = self.acceleration, 2.0 * self.acceleration, 0.0
        for k in range(len(self.starts)):
            a, b, T, F, V = self.starts[k], self.ends[k], self.target[k], self.entry[k], self.exit[k]
            # up and down meet where F^2 + 2a (s - a) = V^2 + 2a (b - s)
            meet = 0.5 * (a + b) + (V ** 2 - F ** 2) / (2 * a2)
            up_end = min(a + max(T ** 2 - F ** 2, 0.0) / a2, meet, b)
            down_start = max(b - max(T ** 2 - V ** 2, 0.0) / a2, meet, a)
            up_end = max(up_end, a)
            down_start = min(down_start, b)
            total += (np.sqrt(F ** 2 + a2 * (up_end - a)) - F) / acc
            total += max(down_start - up_end, 0.0) / T
            total += (np.sqrt(V ** 2 + a2 * (b - down_start)) - V) / acc
        return float(total)


def speed_profile(starts: np.ndarray, ends: np.ndarray, kinds: np.ndarray, settings: Settings) -> SpeedProfile:
    """The profile over segments from ``starts`` to ``ends`` [m] of these kinds."""
    starts, ends = np.asarray(starts, float), np.asarray(ends, float)
    lengths = ends - starts
    target = np.where(np.isin(kinds, WORKING), settings.work_speed, settings.turn_speed).astype(float)
    v0 = min(CRAWL, float(target.min()))
    a2 = 2.0 * settings.acceleration
    n = len(lengths)
    entry, exit_ = np.empty(n), np.empty(n)
    arriving = v0                                    # forward: the speed brought to each segment's start
    for k in range(n):
        entry[k] = min(target[k], arriving)
        arriving = min(target[k], np.sqrt(entry[k] ** 2 + a2 * lengths[k]))
    leaving = v0                                     # backward: the speed each segment may end with
    for k in range(n - 1, -1, -1):
        exit_[k] = min(leaving, arriving if k == n - 1 else min(target[k], np.sqrt(entry[k] ** 2 + a2 * lengths[k])))
        leaving = min(entry[k], np.sqrt(exit_[k] ** 2 + a2 * lengths[k]))
    return SpeedProfile(starts, ends, target, entry, exit_, settings.acceleration)
