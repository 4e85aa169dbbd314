"""The noise floor of each replay stage, estimated from the log itself.

A model that explains the data leaves a residual at the sensors' noise. Model errors live where the
tractor's dynamics live (below a few hertz); the sensors' white noise spreads evenly up to the
Nyquist frequency. So the white level of a signal is read from the top of its spectrum:

    sigma^2 = mean_{f in [0.35 fs, 0.5 fs]} S(f) * fs / 2     (S: one-sided Welch density)

- steering, yaw: the white level of the stage's residual (wheel-angle sensor, gyro), read on the
  sensor's own updates: a channel updated every m-th row (held, or interpolated between its
  updates) has 1/m of the rows' independent samples and its noise sits below fs / (2 m), so the
  residual is taken every m-th row at fs / m (m from the import's held_samples finding, else from
  the log's exact repeats, measurements.channel_updates.holding); a channel interpolated linearly
  onto the rows from its own stamps (jittered, or at another rate: the import's
  frame.attrs["own_samples"]), row j at the fraction f_j between its samples i_j and i_j + 1,
  carries n_j = (1 - f_j) e_{i_j} + f_j e_{i_j+1}: of variance ((1 - f_j)^2 + f_j^2) sigma^2, its
  neighbours correlated, and its top band damped more than the rest: the level read is sigma sqrt(G),
  G the power the same reading (the same rows, the same Welch segments) finds in unit white noise
  drawn on the stamps and interpolated alike (seeded draws: what the estimator makes of the
  interpolation, leakage included), so sigma = white_level / sqrt(G), and the floor
  the stage's residual is judged against is sigma sqrt(mean_j ((1 - f_j)^2 + f_j^2)); both read on
  the held-out rows (a noise that grows with speed is judged on the speeds it is compared at), on
  both parts when the held-out rows are too few for the spectrum; a yaw rate
  derived from a heading or course (identification.yaw_measurement): at least its noise read on
  the heading's own updates (the rows' top band holds only the interpolation);
- every channel alike (``Sampling``, ``sensor_level``: one rule for the wheel angle, the gyro, the
  speed and the positions): its sigma on its own samples, its noise on the rows R e (own_samples);
- speed: the GPS chord speed against the dead-reckoned chord speed (the speed's and the positions'
  white levels read on their own samples, as above); both are 1 s means, so the floor is
  propagated: var = 2 sigma_gps,row^2 / T^2 + sigma_v^2 P / T (T the chord span, sigma_gps,row
  the GPS noise's RMS on the rows, P the speed's ``mean_interval``: h sum w_i^2 / sum w_i, w_i the
  rows' weight on its sample i; h on every row, m h held over m rows, ~ its own interval when
  interpolated);
- position: the dead-reckoned track integrates the gyro's and the speed's noise, so the floor is the
  stage's residual (aligned, and whitened by that noise: candidates.Replay.track_residuals) of the
  same windows when only noise of the estimated levels is present (Monte Carlo through the same
  replay, seeded; each noise on its sensor's own samples, as the rows carry it: ``sampled_noise``),
  with the GPS white level added.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.signal import welch

from agrobot.measurements.channel_updates import holding

from agrobot.measurements.own_samples import interpolation, interpolation_weights, own_stamps
from .replay import aligned_residuals, antenna_track

HIGH_BAND = (0.35, 0.5)          # share of the sampling frequency read as "noise only"
BAND_DRAWS = 8                   # unit noises through the interpolation whose read level is its white power
HELD_OUT_ROWS = 512              # rows (per update): fewer held out, the floor is read on both parts


def white_level(x: np.ndarray, fs: float) -> float:
    """Standard deviation of the white part of ``x`` from the top of its Welch spectrum."""
    x = np.asarray(x, float)
    if x.ndim == 1:
        x = x[None, :]
    densities = []
    for row in x:
        f, p = welch(row - row.mean(), fs=fs, nperseg=min(len(row), 128))
        band = (f >= HIGH_BAND[0] * fs) & (f <= HIGH_BAND[1] * fs)
        densities.append(p[band].mean())
    return math.sqrt(float(np.mean(densities)) * fs / 2.0)


def update_step(frame, sensor: str, h: float) -> int:
    """Rows of the log per update of ``sensor`` (1: every row is one): the import's held_samples
    finding on it (its updates' rate), else its exact repeats in the log."""
    for f in frame.attrs.get("audit", []) or []:
        if f.get("kind") == "held_samples" and sensor in f.get("channels", []) and f.get("updates_hz"):
            return max(1, int(round(1.0 / (float(f["updates_hz"]) * h))))
    if sensor in frame:
        held = holding(frame["t"].to_numpy(float), frame[sensor].to_numpy(float))
        if held is not None:
            return max(1, int(round(held["held"])))
    return 1


def level_on_updates(x: np.ndarray, fs: float, step: int) -> float:
    """white_level of ``x`` (along its last axis) on every ``step``-th sample, at fs / step."""
    x = np.asarray(x, float)
    if step <= 1 or x.shape[-1] < 16 * step:
        return white_level(x, fs)
    return white_level(x[..., ::step], fs / step)


@dataclass(frozen=True)
class Sampling:
    """How a channel's rows carry the white noise of its own samples: each held over ``step`` rows,
    or (``stamps``) interpolated linearly from its own stamps, whose median interval is ``step`` rows."""

    step: int = 1
    stamps: np.ndarray | None = None


def sampling(replay, sensor: str, column: str | None = None, x: np.ndarray | None = None) -> Sampling:
    """The Sampling of ``sensor`` (update_step; its import finding's name): held, else interpolated
    from the own samples of ``column`` (default: ``sensor``) when ``x`` (default: the column) is their
    interpolation onto the rows (own_samples.own_stamps), else every row its own."""
    step = update_step(replay.frame, sensor, replay.h)
    stamps = own_stamps(replay.frame, column or sensor, x) if step == 1 else None
    if stamps is None:
        return Sampling(step)
    return Sampling(max(1, int(round(float(np.median(np.diff(stamps))) / replay.h))), stamps)


def track_samplings(replay) -> dict[str, Sampling]:
    """The Sampling of each channel a dead-reckoned track reads: the GPS (its fixes' x), the speed
    (its source column) and the gyro."""
    column = replay.speed_source if replay.speed_source in replay.frame else "v"
    return {"gps": sampling(replay, "gnss", "x", replay.gps[:, 0]), "v": sampling(replay, "v", column, replay.speed),
            "yaw_rate": sampling(replay, "yaw_rate", x=replay.gyro)}


def interpolated_power(t: np.ndarray, own_t: np.ndarray) -> float:
    """mean_j ((1 - f_j)^2 + f_j^2): the mean square linear interpolation from the stamps ``own_t``
    onto the rows ``t`` makes of unit white noise (module docstring)."""
    f = interpolation_weights(np.asarray(t, float), own_t)[1]
    return float(np.mean((1 - f) ** 2 + f ** 2))


def sensor_level(x: np.ndarray, t: np.ndarray, fs: float, how: Sampling) -> tuple[float, float]:
    """(sigma on the channel's own samples, the RMS its noise has on the rows ``t``) from ``x`` on
    those rows (a residual, or the signal; along its last axis, each leading row a stretch): the
    white level on the channel's updates (level_on_updates), corrected for an interpolation from its
    own stamps (module docstring: sigma = level / sqrt(G), G the power the same reading finds in
    unit noise drawn on the stamps and interpolated onto ``t``, BAND_DRAWS seeded draws; RMS
    sigma sqrt(mean_j ((1 - f_j)^2 + f_j^2)), averaged over the stretches)."""
    x, t = np.asarray(x, float), np.atleast_2d(np.asarray(t, float))
    level = level_on_updates(x, fs, how.step)
    if how.stamps is None:
        return level, level
    rows, rng = interpolation(how.stamps, t.ravel()), np.random.default_rng(0)   # unit noise on the samples, read alike
    band = np.mean([level_on_updates((rows @ rng.standard_normal(len(how.stamps))).reshape(x.shape), fs, how.step) ** 2
                    for _ in range(BAND_DRAWS)])
    per_row = np.mean([interpolated_power(row, how.stamps) for row in t])
    sigma = level / math.sqrt(band)
    return sigma, sigma * math.sqrt(per_row)


def mean_interval(how: Sampling, t: np.ndarray, h: float) -> float:
    """P [s]: a mean over T s of the channel's rows carries sigma^2 P / T of its noise: each own
    sample i weighs w_i = sum_j W_ji rows of it, so P = h sum w_i^2 / sum w_i (its interval on a
    steady clock; ``step`` h held; h on every row)."""
    if how.stamps is None:
        return how.step * h
    i, f = interpolation_weights(np.asarray(t, float), how.stamps)
    w = np.bincount(i, 1 - f, len(how.stamps)) + np.bincount(i + 1, f, len(how.stamps))
    return h * float(np.sum(w * w) / np.sum(w))


def track_level(replay, x: np.ndarray, t: np.ndarray, how: Sampling, integrated: bool) -> float:
    """The white level per row that stands for a channel's noise in a dead-reckoned track
    (replay.TrackWhitening), from ``x`` on the rows ``t`` (sensor_level): an integrated channel's
    random walk grows by sigma^2 P per second (mean_interval), a row's white level sigma sqrt(P / h);
    a position's noise is its RMS on the rows."""
    sigma, rms = sensor_level(x, t, 1.0 / replay.h, how)
    return sigma * math.sqrt(mean_interval(how, replay.t, replay.h) / replay.h) if integrated else rms


def sampled_noise(how: Sampling, t: np.ndarray, sigma: float, rng: np.random.Generator, shape: tuple = ()) -> np.ndarray:
    """White noise of ``sigma`` on the channel's own samples as its rows ``t`` carry it (len(t), *shape):
    interpolated from its stamps (own_samples.interpolation), else held over ``step`` rows."""
    if how.stamps is not None:
        return interpolation(how.stamps, t) @ (sigma * rng.standard_normal((len(how.stamps), *shape)))
    n = len(t)
    return np.repeat(sigma * rng.standard_normal((-(-n // how.step), *shape)), how.step, axis=0)[:n]


def stage_level(replay, stage: str, sensor: str, values: dict, fs: float) -> tuple[float, float]:
    """(the sensor's sigma, the floor of the stage's held-out residual): sensor_level of the
    residual on the held-out rows (both parts when they are too few)."""
    res = replay.measured(stage) - replay.seen(stage, replay.predicted(stage, values))
    how = sampling(replay, sensor, x=replay.measured(stage))
    test = replay.masks[stage]["test"]
    rows = test if test.sum() >= HELD_OUT_ROWS * how.step else replay.scored(stage)
    return sensor_level(res[rows], replay.t[rows], fs, how)


def stage_floors(replay, values: dict[str, float], seed: int = 0, realisations: int = 4) -> dict[str, float]:
    """The RMS a residual of each replayed stage would have if the model were right (same units
    as the stage's residual); ``values`` is the fitted model (its position track is perturbed)."""
    fs = 1.0 / replay.h
    floors: dict = {}
    sensors: dict = {}
    for stage, sensor in (("steering", "delta"), ("yaw", "yaw_rate")):
        if stage in replay.stages:
            sensors[sensor], floors[stage] = stage_level(replay, stage, sensor, values, fs)
    derived = replay.frame.attrs.get("yaw_measurement")
    if "yaw" in replay.stages and derived is not None and math.isfinite(derived.noise):
        # a yaw rate from a heading held between its updates: its noise from its own updates, not the rows'
        floors["yaw"] = sensors["yaw_rate"] = max(floors["yaw"], derived.noise)
    if not {"position", "speed"} & set(replay.stages):
        floors["_sensors"] = sensors
        return floors
    # each sensor's white level on its own samples (sensor_level), its noise drawn as its rows carry it
    t, rows = replay.t, np.concatenate([replay.windows["fit"], replay.windows["test"]])
    nominal = replay.predicted("position", values)
    res = aligned_residuals(nominal, replay.gps, rows)          # the GPS's: window by window, each axis
    on = track_samplings(replay)
    on_gps, on_v, on_gyro = on["gps"], on["v"], on["yaw_rate"]
    sigma_gps, gps_row = sensor_level(np.concatenate([res[..., 0], res[..., 1]]), np.concatenate([t[rows]] * 2), fs,
                                      on_gps)
    sigma_v = sensor_level(replay.speed, t, fs, on_v)[0]
    sigma_gyro = sensors.get("yaw_rate") or sensor_level(replay.gyro, t, fs, on_gyro)[0]   # no yaw stage: its top band
    span = replay.chord_span
    floors["speed"] = math.sqrt(2 * gps_row ** 2 / span ** 2 + sigma_v ** 2 * mean_interval(on_v, t, replay.h) / span)
    rng = np.random.default_rng(seed)
    sq = []
    for _ in range(realisations):
        noisy = antenna_track(t, replay.gyro + sampled_noise(on_gyro, t, sigma_gyro, rng),
                              replay.speed + sampled_noise(on_v, t, sigma_v, rng), values, replay.lateral(values))
        gps = nominal + sampled_noise(on_gps, t, sigma_gps, rng, (2,))
        sq.append(np.mean(replay.track_residuals(noisy, rows, gps) ** 2))    # as the stage reads it (whitened)
    floors["position"] = math.sqrt(float(np.mean(sq)))
    floors["_sensors"] = {**sensors, "yaw_rate": sigma_gyro, "v": sigma_v, "gps": sigma_gps}
    return floors
