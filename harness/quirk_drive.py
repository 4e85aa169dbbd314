"""The truth under a composed recording (harness.quirk_recordings): a kinematic Ackermann machine
driven on a fine grid, with the stretches some quirk classes need (reversing, hand driving, pauses).

Model (Kayacan et al. section III in its kinematic limit, small lateral acceleration): the wheels
follow the command ``STEER_DELAY`` s late through a first-order lag ``STEER_TAU``; the yaw rate is
r = v tan(delta) / L with the signed speed v; the heading psi (ENU, from east, anticlockwise) its
integral; the reference point (the antenna, at the rear axle) moves at v along psi. A machine
that backs up has v < 0: its course (the direction of its track) is psi + pi. While driven by hand
the wheels follow the driver, not the path follower's command; paused, v = 0 and the command is
held.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from harness.truth_tractor import SMALL_WHEELBASE

STEER_DELAY = 0.10      # s
STEER_TAU = 0.12        # s
H = 0.01                # s: the fine grid
EARTH = 6_371_000.0
LAT0, LON0 = 52.0, 5.0

# machines the recordings come from: wheelbase [m], cruising speeds [m/s], steering reach [rad]
MACHINES = {
    "mower": dict(wheelbase=SMALL_WHEELBASE, speeds=(0.5, 1.5), steer=0.35),     # truth_tractor's small Ackermann machine
    "utility": dict(wheelbase=1.9, speeds=(2.0, 5.0), steer=0.25),       # a by-wire utility vehicle
    "tractor": dict(wheelbase=2.6, speeds=(1.5, 3.0), steer=0.30),
}


@dataclass
class Drive:
    """The truth on the fine grid (t from 0, SI, ENU), and the stretches [(start, end)] in s."""

    t: np.ndarray
    delta_cmd: np.ndarray
    delta: np.ndarray
    v: np.ndarray
    yaw_rate: np.ndarray
    psi: np.ndarray
    east: np.ndarray
    north: np.ndarray
    wheelbase: float
    reversing: list
    manual: list
    paused: list

    def lat_lon(self) -> tuple[np.ndarray, np.ndarray]:
        """The track as WGS-84 degrees about (LAT0, LON0) (a sphere: metres-level exact here)."""
        lat = LAT0 + np.degrees(self.north / EARTH)
        return lat, LON0 + np.degrees(self.east / (EARTH * math.cos(math.radians(LAT0))))

    def at(self, name: str, t: np.ndarray) -> np.ndarray:
        """A truth channel at times ``t`` (linear)."""
        return np.interp(t, self.t, getattr(self, name))


def _smooth(rng: np.random.Generator, t: np.ndarray, knot: float, amplitude: float) -> np.ndarray:
    """A smooth random signal: cosine-interpolated knots every ``knot`` s, uniform in +-amplitude."""
    knots = np.arange(0.0, t[-1] + 2 * knot, knot)
    values = rng.uniform(-amplitude, amplitude, len(knots))
    k = np.minimum((t // knot).astype(int), len(knots) - 2)
    w = 0.5 - 0.5 * np.cos(math.pi * (t - knots[k]) / knot)
    return values[k] * (1 - w) + values[k + 1] * w


def _stretches(rng, duration: float, count: int, length: tuple[float, float], taken: list) -> list:
    """``count`` stretches of ``length`` s inside (10 s, duration - 10 s), apart from ``taken`` by 4 s."""
    out: list = []
    for _ in range(200):
        if len(out) == count:
            break
        span = rng.uniform(*length)
        a = rng.uniform(10.0, duration - 10.0 - span)
        if all(a > e + 4.0 or a + span < s - 4.0 for s, e in taken + out):
            out.append((float(a), float(a + span)))
    return sorted(out)


def _ramp(t: np.ndarray, stretches: list, rise: float = 1.0) -> np.ndarray:
    """1 inside each stretch, 0 outside, with cosine edges ``rise`` s long inside it."""
    w = np.zeros(len(t))
    for a, b in stretches:
        x = np.clip(np.minimum(t - a, b - t) / rise, 0.0, 1.0)
        w = np.maximum(w, 0.5 - 0.5 * np.cos(math.pi * x))
    return w


def make_drive(rng: np.random.Generator, machine: str, duration: float, reversing: int = 0,
               manual: int = 0, paused: int = 0) -> Drive:
    """The drive: ``reversing`` stretches of 8-12 s backing up at 0.4-0.8 of the cruising speed,
    ``manual`` stretches of 15-25 s driven by hand, ``paused`` stretches of 5-10 s standing."""
    m = MACHINES[machine]
    t = np.arange(0.0, duration, H)
    lo, hi = m["speeds"]
    cruise = 0.5 * (lo + hi) + _smooth(rng, t, 15.0, 0.5 * (hi - lo))
    start = np.clip(t / 3.0, 0.0, 1.0)
    back = _stretches(rng, duration, reversing, (8.0, 12.0), [])
    hand = _stretches(rng, duration, manual, (15.0, 25.0), back)
    rest = _stretches(rng, duration, paused, (5.0, 10.0), back + hand)
    v = cruise * start
    w = _ramp(t, back, 1.5)
    v = v * (1 - w) - w * rng.uniform(0.4, 0.8) * cruise
    v = v * (1 - _ramp(t, rest, 1.0))
    cmd = _smooth(rng, t, 2.5, m["steer"])
    driver = _smooth(rng, t, 1.8, m["steer"])
    hand_w = _ramp(t, hand, 0.5)
    lagged = np.interp(t - STEER_DELAY, t, cmd * (1 - hand_w) + driver * hand_w, left=0.0)
    for i in np.flatnonzero(_ramp(t, rest, 0.01) > 0.5):       # paused: the command held
        cmd[i] = cmd[i - 1]
    delta = np.empty(len(t))
    a = H / (STEER_TAU + H)
    delta[0] = 0.0
    for i in range(1, len(t)):
        delta[i] = delta[i - 1] + a * (lagged[i] - delta[i - 1])
    r = v * np.tan(delta) / m["wheelbase"]
    psi = rng.uniform(-math.pi, math.pi) + np.concatenate(([0.0], np.cumsum(0.5 * (r[1:] + r[:-1]) * H)))
    east = np.concatenate(([0.0], np.cumsum(0.5 * (v[1:] * np.cos(psi[1:]) + v[:-1] * np.cos(psi[:-1])) * H)))
    north = np.concatenate(([0.0], np.cumsum(0.5 * (v[1:] * np.sin(psi[1:]) + v[:-1] * np.sin(psi[:-1])) * H)))
    return Drive(t, cmd, delta, v, r, psi, east, north, m["wheelbase"], back, hand, rest)
