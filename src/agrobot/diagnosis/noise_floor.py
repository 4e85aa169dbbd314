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

The held-out gain of a stage whose measurement noise is most of its residual (a yaw rate derived
from a heading: the differencing makes its noise 0.05 rad/s where a steering map's signal is a few
thousandths) is judged on the part of the error a model can explain (``HeldOutNoise``). The
held-out residual is e = s + w (s the model's error, w the measurement's noise, independent of the
model); its mean square B = |s|^2 + |w|^2 + 2 <s, w>, and an effect changes only s: B - A = |s_b|^2
- |s_a|^2 + 2 <s_b - s_a, w>. A gain judged on the RMS is 1 - sqrt(A / B): of a few thousandths
when |w|^2 is 99 % of B, however much of |s_b|^2 the effect removes. Net of the noise's realised
power n^2 = |w|^2 (the same in both: one measurement), the gain on the RMS the models can explain is

    gain = 1 - sqrt((A - n^2) / (B - n^2))                (reading_noise.held_out_gain)

n^2 must be the realisation's, not its expectation: |w|^2 spreads by sqrt(2 / n_eff) of itself
(5 % on 48 s at 20 Hz, ten times a map's |s|^2), so it is read on the residual itself where the
model has nothing: above f_c, where the baseline's yaw rate (as the measurement sees it) has
1 - MODEL_BAND of its power (mean removed; on the held-out rows), the residual is taken as noise
(``held_out_noise``: B_H, its power above f_c); below f_c the noise's expected power N_L is added,
from the derivation's own noise model (identification.yaw_measurement: an angle of white noise
sigma on updates dt_u apart, differenced over m of them, nu = sigma / (m dt_u) its rate noise), of
one-sided density

    S(f) = 8 nu^2 dt_u sin^2(pi f m dt_u)       (2 nu^2 in all; ~ f^2: blue, little of it at low f)

Each band is read on the sine transform (DST-I, orthonormal: the bins' powers sum to the mean
square) of each stretch of consecutive held-out rows (``sine_bins``; a stretch of m rows has bins
k / (2 (m + 1) h)): a differenced noise's record keeps its end samples' noise (its sum telescopes),
which a Fourier transform spreads flat over every low bin, ~2 K nu^2 / n^2 on K bins, moving them
together (at 0.3 Hz on 48 s of a 20 Hz heading it doubles N_L, and every gap in the held-out rows,
a slow stretch left out, is two more ends); the sine basis vanishes at a stretch's ends. N_L is
read as the residual is: NOISE_DRAWS seeded draws of the noise as the rows carry it
(``differenced_noise``: white noise of sigma on the updates, differenced over m at the rate
samples' own times, a gap starting a new chain, interpolated linearly onto the rows; a course's
chords taken as independent), their power below f_c on the same bins: N_L their mean. MODEL_BAND
is 90 %, not all of it: the noise below f_c grows as f_c^3, and the last tenth of the model's
power (its steps' edges, the reading's noise passed through it) lies where the noise is most of
the residual. So n^2 = B_H + N_L and B - n^2 = B_L - N_L, the baseline's error below f_c;
A - n^2 = A_L - N_L + (A_H - B_H): whatever the effect changes above f_c counts for or against it.
The low band's realisation is the estimate's error: an explainable part below what the draws
exceed N_L by in 1 - LEAST_QUANTILE of them is not told from the noise: B - n^2 and A - n^2 are
taken at least that (``least``), and a log whose baseline leaves no more gives no effect a gain. A
gyro's white noise is not netted (its floor is not most of its residual).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.fft import dst
from scipy.signal import welch

from agrobot.measurements.channel_updates import holding

from agrobot.measurements.own_samples import interpolation, interpolation_weights, own_stamps
from .replay import aligned_residuals, antenna_track

HIGH_BAND = (0.35, 0.5)          # share of the sampling frequency read as "noise only"
BAND_DRAWS = 8                   # unit noises through the interpolation whose read level is its white power
HELD_OUT_ROWS = 512              # rows (per update): fewer held out, the floor is read on both parts
MODEL_BAND = 0.90                # share of the model's yaw-rate power below f_c (HeldOutNoise)
LEAST_QUANTILE = 0.975           # an explainable part the noise's low band exceeds its mean by this often is none
BAND_BINS = 8                    # fewer sine bins below f_c: the held-out noise is not netted
NOISE_DRAWS = 256                # seeded draws of a derived rate's noise: its low band N_L and least


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
    floors["_held_out"] = held_out_noise(replay, values, seed)
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


@dataclass(frozen=True)
class HeldOutNoise:
    """The measurement noise's realised mean square in a stage's held-out residual (module
    docstring): ``power`` n^2 = B_H + N_L, ``least`` the least explainable mean square told from the
    noise (N_L's LEAST_QUANTILE less its mean), ``band`` f_c [Hz], ``low`` N_L, ``gross`` the
    residual's own mean square B (the baseline's)."""

    power: float
    least: float
    band: float
    low: float
    gross: float

    def text(self, unit: str = "rad/s") -> str:
        return (f"held-out yaw-rate gains are net of the derived yaw rate's noise, {math.sqrt(self.power):.3g} {unit} "
                f"of its {math.sqrt(self.gross):.3g} {unit} RMS (above {self.band:.3g} Hz, where the baseline's yaw "
                f"rate has {100 * (1 - MODEL_BAND):.0f} % of its power, read on the baseline's residual; below it the "
                f"differencing's expected {math.sqrt(self.low):.2g} {unit}): the models can explain "
                f"{math.sqrt(max(self.gross - self.power, 0.0)):.2g} {unit} (at least {math.sqrt(self.least):.2g}); "
                f"passed over: the gross RMS, whose noise no model removes (a gyro's gains are gross)")


def differenced_noise(derived, t: np.ndarray, rng: np.random.Generator, draws: int) -> np.ndarray:
    """(draws, len(t)): the noise of a rate derived as ``derived`` (yaw_measurement.YawMeasurement) as
    its rows ``t`` carry it: white noise of sigma = nu m dt_u on the angle's updates, differenced over
    m of them at the rate samples' own times (a gap longer than 1.5 dt_u starts a new chain),
    interpolated linearly onto the rows (module docstring)."""
    tr, m = np.asarray(derived.update_times, float), max(1, int(derived.chord_updates))
    dt = 1.0 / derived.update_hz
    starts = np.flatnonzero(np.r_[True, np.diff(tr) > 1.5 * dt, True])
    rates = np.empty((draws, len(tr)))
    for a, b in zip(starts[:-1], starts[1:]):
        angle = derived.noise * m * dt * rng.standard_normal((draws, b - a + m))
        rates[:, a:b] = (angle[:, m:] - angle[:, :-m]) / (m * dt)
    return np.stack([np.interp(t, tr, x) for x in rates])


def sine_bins(x: np.ndarray, t: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """(f [Hz], p): the power of ``x`` (along its last axis, on the rows ``t``, ``h`` s apart) in each
    bin of the sine transform (DST-I, orthonormal) of each stretch of consecutive rows, bin k of a
    stretch of m rows at k / (2 (m + 1) h); p sums to mean(x^2) along its last axis."""
    x = np.asarray(x, float)
    cuts = np.flatnonzero(np.diff(t) > 1.5 * h) + 1
    f, p = [], []
    for a, b in zip(np.r_[0, cuts], np.r_[cuts, len(t)]):
        f.append(np.arange(1, b - a + 1) / (2.0 * (b - a + 1) * h))
        p.append(dst(x[..., a:b], type=1, norm="ortho", axis=-1) ** 2)
    return np.concatenate(f), np.concatenate(p, axis=-1) / x.shape[-1]


def held_out_noise(replay, values: dict[str, float], seed: int = 0) -> dict[str, HeldOutNoise]:
    """{"yaw": residual_noise} of the held-out yaw residual under ``values`` (the baseline) for a yaw
    rate derived from a heading or a course (its noise known, identification.yaw_measurement); {}
    for a gyro, an unknown noise, or a band of fewer than BAND_BINS bins."""
    derived = replay.frame.attrs.get("yaw_measurement")
    if "yaw" not in replay.stages or derived is None or derived.kind == "gyro":
        return {}
    seen = replay.seen("yaw", replay.predicted("yaw", values))
    keep = replay.masks["yaw"]["test"] & np.isfinite(seen) & np.isfinite(replay.gyro)
    found = residual_noise(replay.gyro[keep] - seen[keep], seen[keep], replay.t[keep], replay.h, derived, seed)
    return {} if found is None else {"yaw": found}


def residual_noise(r: np.ndarray, y: np.ndarray, t: np.ndarray, h: float, derived, seed: int = 0
                   ) -> HeldOutNoise | None:
    """HeldOutNoise of the residual ``r`` on the rows ``t`` (``h`` s apart) of a model whose output
    (as the measurement sees it) is ``y``, the measurement a derived yaw rate (``derived``:
    yaw_measurement.YawMeasurement): n^2 = B_H + N_L, each read on the sine bins of the rows'
    stretches (sine_bins), f_c the bin below which ``y`` has MODEL_BAND of its power, N_L and the
    least explainable part from NOISE_DRAWS seeded draws of its noise (differenced_noise) read alike
    (module docstring); None when its noise is unknown or fewer than BAND_BINS bins lie below f_c."""
    if not (math.isfinite(derived.noise) and math.isfinite(derived.update_hz)) or derived.update_times is None \
            or len(derived.update_times) < 2 or len(r) < 2 * BAND_BINS:
        return None
    f, model = sine_bins(y - y.mean(), t, h)
    order = np.argsort(f, kind="stable")
    share = np.cumsum(model[order]) / max(float(model.sum()), 1e-300)
    f_c = float(f[order][min(int(np.searchsorted(share, MODEL_BAND)), len(f) - 1)])
    low = f <= f_c
    if low.sum() < BAND_BINS:
        return None
    noise = sine_bins(differenced_noise(derived, t, np.random.default_rng(seed), NOISE_DRAWS), t, h)[1][:, low].sum(-1)
    gross = float(np.mean(r * r))
    n2 = gross - float(sine_bins(r, t, h)[1][low].sum()) + float(noise.mean())
    return HeldOutNoise(n2, float(np.quantile(noise, LEAST_QUANTILE) - noise.mean()), f_c, float(noise.mean()), gross)
