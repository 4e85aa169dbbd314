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
  neighbours correlated, and its top band damped more than the rest:

      E |sum_j n_j exp(-i w j)|^2 / N = sigma^2 G(w),   G(w) = (1/N) sum_i |sum_j W_ji exp(-i w j)|^2

  (W_ji the weight of sample i in row j), so sigma = white_level / sqrt(mean_band G), and the floor
  the stage's residual is judged against is sigma sqrt(mean_j ((1 - f_j)^2 + f_j^2)); both read on
  the held-out rows (a noise that grows with speed is judged on the speeds it is compared at), on
  both parts when the held-out rows are too few for the spectrum; a yaw rate
  derived from a heading or course (identification.yaw_measurement): at least its noise read on
  the heading's own updates (the rows' top band holds only the interpolation);
- speed: the GPS chord speed against the dead-reckoned chord speed (the speed's and the positions'
  white levels read on their own updates, as above, but not corrected for an interpolation: the
  import keeps own stamps of the held channels and the gyro only); both are 1 s means, so the floor
  is propagated: var = 2 sigma_gps^2 / T^2 + sigma_v^2 / (T / h)   (T the chord span);
- position: the dead-reckoned track integrates the gyro's and the speed's noise, so the floor is the
  stage's residual (aligned, and whitened by that noise: candidates.Replay.track_residuals) of the
  same windows when only noise of the estimated levels is present (Monte Carlo through the same
  replay, seeded), with the GPS white level added.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.signal import welch

from agrobot.measurements.channel_updates import holding

from .replay import aligned_residuals, antenna_track

HIGH_BAND = (0.35, 0.5)          # share of the sampling frequency read as "noise only"
BAND_POINTS = 33                 # frequencies G(w) is averaged over in the high band
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


def interpolation_weights(t: np.ndarray, own_t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(i_j, f_j): the row at t_j lies at the fraction f_j of the way from own sample i_j to i_j + 1."""
    own_t = np.asarray(own_t, float)
    i = np.clip(np.searchsorted(own_t, t, side="right") - 1, 0, len(own_t) - 2)
    f = np.clip((t - own_t[i]) / np.maximum(own_t[i + 1] - own_t[i], 1e-12), 0.0, 1.0)
    return i, f


def interpolated_white(t: np.ndarray, own_t: np.ndarray) -> tuple[float, float]:
    """(sqrt(mean_band G), sqrt(mean_j ((1 - f_j)^2 + f_j^2))): what linear interpolation from the
    stamps ``own_t`` onto the rows ``t`` (in the order given) makes of unit white noise: its white
    level (as white_level reads it) and its RMS per row (module docstring)."""
    i, f = interpolation_weights(np.asarray(t, float), own_t)
    j, n = np.arange(len(i)), int(i.max()) + 2
    gains = []
    for w in 2 * np.pi * np.linspace(*HIGH_BAND, BAND_POINTS):
        phase = np.exp(-1j * w * j)
        a, b = (1 - f) * phase, f * phase
        re = np.bincount(i, a.real, n) + np.bincount(i + 1, b.real, n)
        im = np.bincount(i, a.imag, n) + np.bincount(i + 1, b.imag, n)
        gains.append(float(np.sum(re ** 2 + im ** 2)) / len(i))
    return math.sqrt(float(np.mean(gains))), math.sqrt(float(np.mean((1 - f) ** 2 + f ** 2)))


def interpolated_stamps(replay, stage: str, sensor: str) -> np.ndarray | None:
    """The own stamps of ``sensor`` (frame.attrs["own_samples"]) when the stage's measurement is their
    linear interpolation onto the rows, else None."""
    own = (replay.frame.attrs.get("own_samples") or {}).get(sensor)
    if not own or len(own[0]) < 2:
        return None
    tc, vc = (np.asarray(a, float) for a in own)
    x = replay.measured(stage)
    ok = np.isfinite(x)
    if not ok.any() or not np.allclose(np.interp(replay.t[ok], tc, vc), x[ok], rtol=1e-9, atol=1e-12):
        return None
    return tc


def stage_level(replay, stage: str, sensor: str, values: dict, fs: float) -> tuple[float, float]:
    """(the sensor's sigma, the floor of the stage's held-out residual): the residual's white level
    on the sensor's updates, on the held-out rows (both parts when they are too few), corrected for
    a linear interpolation from the sensor's own stamps (module docstring), whose median interval in
    rows is the m of a slower channel (read on every m-th row, G on those rows)."""
    res = replay.measured(stage) - replay.seen(stage, replay.predicted(stage, values))
    step = update_step(replay.frame, sensor, replay.h)
    stamps = interpolated_stamps(replay, stage, sensor) if step == 1 else None
    if stamps is not None:                       # a slower channel interpolated: read on its updates too
        step = max(1, int(round(float(np.median(np.diff(stamps))) / replay.h)))
    test = replay.masks[stage]["test"]
    rows = test if test.sum() >= HELD_OUT_ROWS * step else replay.scored(stage)
    level = level_on_updates(res[rows], fs, step)
    if stamps is None:
        return level, level
    t = replay.t[rows]
    band = interpolated_white(t[::step] if step > 1 and len(t) >= 16 * step else t, stamps)[0]
    sigma = level / band
    return sigma, sigma * interpolated_white(t, stamps)[1]


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
    # GPS white level: from the aligned position residual, window by window, each axis
    rows = np.concatenate([replay.windows["fit"], replay.windows["test"]])
    nominal = replay.predicted("position", values)
    res = aligned_residuals(nominal, replay.gps, rows)
    sigma_gps = level_on_updates(np.concatenate([res[..., 0], res[..., 1]]), fs, update_step(replay.frame, "gnss", replay.h))
    sigma_v = level_on_updates(replay.speed, fs, update_step(replay.frame, "v", replay.h))
    sigma_gyro = sensors.get("yaw_rate") or level_on_updates(   # no yaw stage: the gyro's own top band
        replay.gyro, fs, update_step(replay.frame, "yaw_rate", replay.h))
    span = replay.chord_span
    floors["speed"] = math.sqrt(2 * sigma_gps ** 2 / span ** 2 + sigma_v ** 2 * replay.h / span)
    rng = np.random.default_rng(seed)
    sq = []
    for _ in range(realisations):
        noisy = antenna_track(replay.t, replay.gyro + sigma_gyro * rng.standard_normal(len(replay.t)),
                              replay.speed + sigma_v * rng.standard_normal(len(replay.t)), values, replay.lateral(values))
        gps = nominal + sigma_gps * rng.standard_normal(nominal.shape)
        sq.append(np.mean(replay.track_residuals(noisy, rows, gps) ** 2))    # as the stage reads it (whitened)
    floors["position"] = math.sqrt(float(np.mean(sq)))
    floors["_sensors"] = {**sensors, "yaw_rate": sigma_gyro, "v": sigma_v, "gps": sigma_gps}
    return floors
