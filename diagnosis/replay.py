"""Replaying a log through the baseline model, one subsystem at a time (issue 6, step 1).

- steering: delta_cmd -> delta (the closed-loop first-order equivalent, components.models.steering_equivalent);
- yaw: measured delta and speed -> yaw rate (the study's LPV yaw model);
- position: measured yaw rate and speed -> antenna track, dead-reckoned and aligned to the GPS
  track window by window (a rigid 2-D fit per window removes the unknown start pose).

Every function takes the parameter values (SI units) as a mapping and returns arrays on the log's
sample times. Inputs are taken as the mean of the two samples around each step (first-order hold
in the integral sense), so a 20 Hz log replays without half-a-sample lag.
"""
from __future__ import annotations

from typing import Mapping

import numpy as np

from components.models import steering_equivalent
from components.models.yaw_dynamics import (TractorParameters, body_to_world, cornering_scale, lateral_disturbance_column,
                                            state_space, with_cornering_scale, zoh_discretize)


def steering_replay(cmd: np.ndarray, h: float, v: Mapping[str, float], delta0: float) -> np.ndarray:
    """The steering's first-order equivalent (components.models.steering_equivalent) with the
    replay's values."""
    return steering_equivalent.simulate(cmd, h, v["steering_time_constant"], v["steering_deadband"],
                                        v["steering_rate_limit"], v["command_delay"], delta0)


def midpoints(x: np.ndarray) -> np.ndarray:
    """Mean of consecutive samples; the last sample repeats."""
    return np.append(0.5 * (x[1:] + x[:-1]), x[-1])


class YawReplay:
    """Responses of the yaw model to the four inputs that enter it linearly:
    [measured delta, a unit steering offset, a_lat = cos(psi), a_lat = -sin(psi)], so that

        gamma = R0 + offset R1 + s_north R2 + s_east R3 + bias

    (a side slope with fall line psi_d and angle phi: s_east, s_north = g sin(phi) (cos, sin)(psi_d)).
    Simulations are cached on the parameters that enter nonlinearly."""

    def __init__(self, model: str, params: TractorParameters, h: float, delta: np.ndarray, v: np.ndarray,
                 heading: np.ndarray, speed_grid: float = 0.02, min_speed: float = 0.3):
        self.model, self.params, self.h = model, params, h
        psi = midpoints(heading)
        self.inputs = np.column_stack([midpoints(delta), np.ones(len(delta)), np.cos(psi), -np.sin(psi)])
        self.bins = np.round(np.maximum(midpoints(v), min_speed) / speed_grid).astype(int)
        self.grid = speed_grid
        self._cache: dict[tuple, np.ndarray] = {}

    def responses(self, front_scale: float, rear_scale: float, speed_slope: float, v_ref: float) -> np.ndarray:
        key = (round(front_scale, 12), round(rear_scale, 12), round(speed_slope, 12), v_ref)
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        p = with_cornering_scale(self.params, front_scale, rear_scale)
        mats = {}
        for b in np.unique(self.bins):
            speed = b * self.grid
            A, B, _ = state_space(self.model, with_cornering_scale(p, cornering_scale(speed, speed_slope, v_ref)), speed)
            Ad, Bd = zoh_discretize(A, np.column_stack([B, lateral_disturbance_column(A.shape[0])]), self.h)
            mats[b] = (Ad, Bd[:, [0, 0, 1, 1]])
        n = next(iter(mats.values()))[0].shape[0]
        Z = np.zeros((n, 4))
        out = np.empty((len(self.bins), 4))
        for k, (b, u) in enumerate(zip(self.bins.tolist(), self.inputs)):
            out[k] = Z[1]
            Ad, Bsel = mats[b]
            Z = Ad @ Z + Bsel * u
        if len(self._cache) > 64:
            self._cache.clear()
        self._cache[key] = out
        return out

    def yaw_rate(self, v: Mapping[str, float]) -> np.ndarray:
        R = self.responses(v["cornering_front_scale"], v["cornering_rear_scale"], v["cornering_speed_slope"],
                           v["cornering_reference_speed"])
        return R[:, 0] + v["steer_angle_offset"] * R[:, 1] + v["slope_north"] * R[:, 2] + \
            v["slope_east"] * R[:, 3] + v["yaw_rate_bias"]


def integrate(x: np.ndarray, h: float) -> np.ndarray:
    """Cumulative trapezoid from 0 (scipy), on the log's even step ``h``."""
    from scipy.integrate import cumulative_trapezoid

    return cumulative_trapezoid(x, dx=h, initial=0.0)


def chords(gps: np.ndarray, h: float, span: float = 1.0) -> tuple[int, np.ndarray]:
    """(k, d): the GPS displacement over ``span`` seconds centred on sample i + k, d[i] =
    gps[i + 2k] - gps[i]. Chords average the 2 cm noise that point-to-point differences amplify."""
    k = max(1, int(round(0.5 * span / h)))
    return k, gps[2 * k:] - gps[:-2 * k]


def antenna_track(t: np.ndarray, yaw_rate: np.ndarray, speed: np.ndarray, v: Mapping[str, float]) -> np.ndarray:
    """Dead-reckoned GPS reading (N, 2) in an arbitrary frame: psi = int(gamma_measured - bias),
    dR/dt = v (cos psi, sin psi), antenna = R + Rot(psi) (a_forward, a_left), read ``gps_latency`` late."""
    h = float(t[1] - t[0])
    psi = integrate(yaw_rate - v["yaw_rate_bias"], h)
    psi_mid = 0.5 * (psi[1:] + psi[:-1])
    v_mid = 0.5 * (speed[1:] + speed[:-1])
    x = np.concatenate([[0.0], np.cumsum(h * v_mid * np.cos(psi_mid))])
    y = np.concatenate([[0.0], np.cumsum(h * v_mid * np.sin(psi_mid))])
    dx, dy = body_to_world(v["antenna_forward"], v["antenna_left"], np.cos(psi), np.sin(psi))
    ax, ay = x + dx, y + dy
    lat = v["gps_latency"]
    if lat:
        ax, ay = np.interp(t - lat, t, ax), np.interp(t - lat, t, ay)
    return np.column_stack([ax, ay])


def aligned_residuals(predicted: np.ndarray, measured: np.ndarray, windows: np.ndarray) -> np.ndarray:
    """Per window (rows of sample indices, shape (W, L)): the rigid motion (rotation + translation)
    that best maps the predicted track onto the measured one, in closed form; returns the
    residuals measured - aligned, shape (W, L, 2)."""
    P, M = predicted[windows], measured[windows]
    P = P - P.mean(axis=1, keepdims=True)
    M = M - M.mean(axis=1, keepdims=True)
    cross = np.sum(P[..., 0] * M[..., 1] - P[..., 1] * M[..., 0], axis=1)
    dot = np.sum(P[..., 0] * M[..., 0] + P[..., 1] * M[..., 1], axis=1)
    th = np.arctan2(cross, dot)[:, None]
    c, s = np.cos(th), np.sin(th)
    return np.stack([M[..., 0] - (c * P[..., 0] - s * P[..., 1]), M[..., 1] - (s * P[..., 0] + c * P[..., 1])], axis=-1)


def heading_estimate(t: np.ndarray, gps: np.ndarray, yaw_rate: np.ndarray, speed: np.ndarray,
                     span: float = 10.0, min_speed: float = 0.3) -> np.ndarray:
    """Absolute heading: the integrated gyro, its offset taken from the GPS course over 1 s chords
    (circular mean over ``span`` seconds of moving samples). Good to a degree or two: enough to
    resolve the direction of a side slope."""
    h = float(t[1] - t[0])
    psi = integrate(yaw_rate, h)
    k, d = chords(gps, h)
    moving = (np.hypot(d[:, 0], d[:, 1]) > min_speed * 2 * k * h) & (speed[k:-k] > min_speed)
    z = np.zeros(len(t), dtype=complex)
    z[k:-k] = np.exp(1j * (np.arctan2(d[:, 1], d[:, 0]) - psi[k:-k])) * moving
    w = max(1, int(round(span / h)))
    zs = np.convolve(z, np.ones(w), "same")
    good = np.abs(zs) > 1e-9
    if not np.any(good):
        return psi
    offset = np.interp(np.arange(len(t)), np.flatnonzero(good), np.unwrap(np.angle(zs[good])))
    return psi + offset
