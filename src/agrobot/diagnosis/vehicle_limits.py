"""What a study's vehicle can do and what the log shows its vehicle doing, on the same scales: the
tightest turn (the study's L / tan(delta_max), the log's v / |r| on steady stretches), the wheels'
rate (the study's actuator at full rate, the log's delta moved over WINDOW s), the wheel angle
(the study's lock), the speed (the study's drivetrain at full pedal) and the lateral acceleration
(its class's tyre friction times g). plausibility.beyond_limits compares them.

Each log figure is the one the log shows held, not a single sample: a turn's radius from its
stretch's means, with its noise allowed for (the radius the stretch's yaw rate reaches at
mean - 2 standard errors); a rate or an angle the RANKth largest of the log's; a speed or a lateral
acceleration the 99.5th percentile.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from agrobot.identification.steady_state import held_input
from agrobot.measurements.position_source import MAD_NORMAL, white_noise_sigma
from agrobot.orchestrator.study import load_study
from agrobot.studies import shipped

from .baseline import baseline_from_study
from .study_fit import STEADY, driving

WINDOW = 0.25        # s over which the wheels' rate is read (several samples: one sample's noise is spread)
RANK = 3             # (wheel_angle_third_largest) the 3rd largest window's rate or angle: a rate held over three windows, not one glitch
MIN_STRETCH = 1.0    # s of steady turning that give one radius


@dataclass(frozen=True)
class StudyLimits:
    """The study's vehicle's limits (None: the study does not declare it): wheelbase [m], lock
    |delta_max| [rad], wheel rate [rad/s], top speed [m/s], tyre friction (the class's highest)."""

    wheelbase: float
    lock: float | None
    rate: float | None
    top_speed: float | None
    friction: float | None

    @classmethod
    def of(cls, baseline) -> "StudyLimits":
        """From a diagnosis.baseline.Baseline: the steering's angle_limit and full rate
        (steering_rate_limit: the valve's Q_max / V_rad or its rate_limit), the drivetrain's
        max_speed, the class's friction (identification.vehicle.CLASSES) or the study's lower one."""
        p, view = baseline.tractor, baseline.study
        steering = view.parameters("steering", {}) if view is not None else {}
        top = None
        if view is not None:
            drive = view.model.find(role="drivetrain")
            top = view.model.parameters(drive[0]).get("max_speed") if drive else None
        mu = [x for x in (baseline.vehicle.friction_range[1] if baseline.vehicle.kind else None,
                          baseline.values.get("tyre_friction")) if x is not None and math.isfinite(x)]
        lock = steering.get("angle_limit")
        return cls(p.l_f + p.l_r, float(lock) if lock else None, baseline.values.get("steering_rate_limit"),
                   float(top) if top else None, min(mu) if mu else None)

    @property
    def min_radius(self) -> float | None:
        """L / tan(delta_max) [m]: the tightest turn at full lock (no slip)."""
        return self.wheelbase / math.tan(self.lock) if self.lock and self.lock < math.pi / 2 else None


@lru_cache(maxsize=None)
def shipped_limits(name: str) -> StudyLimits:
    """The limits of the vehicle of shipped study ``name`` (studies/NAME)."""
    return StudyLimits.of(baseline_from_study(load_study(shipped(name))))


def reading_noise(x: np.ndarray) -> float:
    """The white noise sigma of a channel [its unit]: its second differences' MAD / MAD_NORMAL / sqrt 6
    (measurements.position_source.white_noise_sigma)."""
    d2 = np.diff(x[np.isfinite(x)], 2)
    return white_noise_sigma(float(np.median(np.abs(d2))) / MAD_NORMAL) if len(d2) else 0.0


def _ranked(x: np.ndarray) -> float | None:
    x = np.sort(x[np.isfinite(x)])
    return float(x[-RANK]) if len(x) >= RANK else None


def wheel_motion(t: np.ndarray, delta: np.ndarray) -> dict:
    """{steering_rate, wheel_angle_third_largest, angle_noise}: the RANKth largest |delta(t + WINDOW) - delta(t)|
    / WINDOW [rad/s] and |delta| [rad] of the measured wheel angle, and its reading noise [rad]."""
    h = float(np.median(np.diff(t)))
    k = max(1, int(round(WINDOW / h)))
    rate = np.abs(delta[k:] - delta[:-k]) / (t[k:] - t[:-k]) if len(t) > k else np.zeros(0)
    return {"steering_rate": _ranked(rate), "rate_window": k * h, "wheel_angle_third_largest": _ranked(np.abs(delta)),
            "angle_noise": reading_noise(delta)}


def tightest_turn(t, v, r, steer, moving) -> dict:
    """{min_radius, radius_at, stretches}: the tightest of the log's steady stretches (the steering
    input ``steer`` held STEADY s, moving, at least MIN_STRETCH s long), each R = mean v / (|mean r|
    - 2 std(r) / sqrt(n)) (the widest radius its yaw rate allows), with its time [s]."""
    h = float(np.median(np.diff(t)))
    held = held_input(steer, np.zeros(len(t), int), max(2, int(round(STEADY / h)))) & moving & np.isfinite(r)
    edges = np.flatnonzero(np.diff(np.concatenate(([0], held.astype(int), [0]))))
    best, at, count = math.inf, math.nan, 0
    for a, b in zip(edges[::2], edges[1::2]):
        if (b - a) * h < MIN_STRETCH:
            continue
        count += 1
        turn = abs(float(np.mean(r[a:b]))) - 2 * float(np.std(r[a:b])) / math.sqrt(b - a)
        radius = float(np.mean(v[a:b])) / turn if turn > 0 else math.inf
        if radius < best:
            best, at = radius, float(t[a])
    return {"min_radius": best if math.isfinite(best) else None, "radius_at": at, "stretches": count}


def log_extremes(frame) -> dict | None:
    """What the log's vehicle does (None: no t and v, or under 50 moving samples): the tightest
    steady turn (with yaw_rate and delta or delta_cmd), the wheels' rate and angle (with a measured
    delta), the top speed and the lateral acceleration |v r| (99.5th percentiles while moving:
    lateral_acceleration_p995, the limits' figure, beside study_fit.log_vehicle's 99th percentile, the
    tyres' range a fit reads; a limit is passed only past the rarer one)."""
    if "t" not in frame or "v" not in frame:
        return None
    t, v = frame["t"].to_numpy(float), frame["v"].to_numpy(float)
    moving = driving(v, np.isfinite(v))
    if moving.sum() < 50:
        return None
    out: dict = {"speed": float(np.percentile(v[moving], 99.5))}
    steer = "delta" if "delta" in frame else "delta_cmd" if "delta_cmd" in frame else None
    if "yaw_rate" in frame:
        r = frame["yaw_rate"].to_numpy(float)
        lateral = np.abs(v * r)[moving & np.isfinite(r)]
        out["lateral_acceleration_p995"] = float(np.percentile(lateral, 99.5)) if len(lateral) else None
        if steer:
            out |= tightest_turn(t, v, r, frame[steer].to_numpy(float), moving)
    if "delta" in frame:
        out |= wheel_motion(t, frame["delta"].to_numpy(float))
    return out
