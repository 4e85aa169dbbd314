"""The position stage's residual against the dead reckoning's own noise: generated tracks with a
known noise, never the code's output, as the truth.

- A gyro's white noise, integrated into the track's heading, is a low-frequency drift of the
  track; whitened by its covariance (replay.TrackWhitening) the residual of a right model is the
  GPS's white noise again: level sigma_gps, no lag-1 correlation.
- A residual correlated in time (AR(1), coefficient rho, in east and north alike) has the
  effective size n (1 - rho) / (1 + rho) (estimation.effective_size), read on the stage's residual
  ordered by time along each axis (east, north interleaved would pair the two axes: rho ~ 0).
"""
from __future__ import annotations

import numpy as np

from agrobot.diagnosis.baseline import baseline_from_study
from agrobot.diagnosis.candidates import Replay
from agrobot.diagnosis.replay import TrackWhitening, aligned_residuals, antenna_track
from agrobot.estimation import effective_size
from agrobot.orchestrator.study import load_study
from harness.hidden_effects import BASELINES
from harness.truth_tractor import make_log

H, L = 0.05, 200                     # a 10 s window at 20 Hz


def _lag1(x: np.ndarray) -> float:
    x = x - x.mean(axis=-1, keepdims=True)
    return float(np.sum(x[..., 1:] * x[..., :-1]) / np.sum(x * x))


def test_whitened_track_residual_is_the_gps_noise():
    """A car at 30 m/s weaving (yaw rate 0.1 sin(0.8 t)): its track dead-reckoned from a gyro with
    0.002 rad/s of white noise and a speed with 0.02 m/s, read by a GPS with 0.02 m. Raw, the aligned
    residual carries the drift (lag-1 correlation well above 0.3, level above the GPS's); whitened it
    is white at the GPS's level."""
    values = baseline_from_study(load_study(BASELINES["car"])).values
    t = np.arange(L) * H
    rate, speed = 0.1 * np.sin(0.8 * t), np.full(L, 30.0)
    truth = antenna_track(t, rate, speed, values)
    s_gps, s_gyro, s_speed = 0.02, 0.002, 0.02
    T = TrackWhitening(truth, H, s_gps, s_gyro, s_speed)
    rng = np.random.default_rng(7)
    raw, white = [], []
    rows = np.arange(L)[None, :]
    for _ in range(200):
        track = antenna_track(t, rate + s_gyro * rng.standard_normal(L), speed + s_speed * rng.standard_normal(L), values)
        r = aligned_residuals(track, truth + s_gps * rng.standard_normal((L, 2)), rows)[0].T       # (2, L)
        raw.append(r)
        white.append(T(r.ravel()).reshape(2, L))
    raw, white = np.array(raw), np.array(white)
    assert _lag1(raw) > 0.3 and np.sqrt(np.mean(raw ** 2)) > 1.2 * s_gps
    assert abs(_lag1(white)) < 0.05
    assert abs(np.sqrt(np.mean(white ** 2)) / (s_gps * np.sqrt((2 * L - 3) / (2 * L))) - 1.0) < 0.05


def test_track_residual_effective_size_reads_time_order():
    """The replay's track residual on a GPS track of the model's own track plus AR(1) noise
    (rho 0.8, each axis its own draw; no dead-reckoning noise): effective_size within 20 % of
    n (1 - rho) / (1 + rho), n the residual's length."""
    frame, _ = make_log(1006, None, duration=120.0, vehicle="car")
    replay = Replay(frame, baseline_from_study(load_study(BASELINES["car"])))
    values = replay.baseline.values
    rho, n = 0.8, len(replay.t)
    rng = np.random.default_rng(3)
    e = rng.standard_normal((n, 2)) * 0.02
    for k in range(1, n):
        e[k] += rho * e[k - 1]
    replay.track_noise = (0.02, 0.0, 0.0)           # the GPS's noise alone: the whitening is the identity
    replay.gps = replay.predicted("position", values) + e
    r = replay.residuals("position", values, "fit")
    expected = len(r) * (1 - rho) / (1 + rho)
    assert abs(effective_size(r) / expected - 1.0) < 0.2
