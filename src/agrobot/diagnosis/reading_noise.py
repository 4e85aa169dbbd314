"""The wheel-angle reading's noise in the yaw stage's fit (errors in variables).

The yaw stage is driven by the reading d = delta + n of the wheel angle (n white, level sigma_n on
the reading's own updates). Its output-error fit on y = G_theta(delta) + e minimises

    S(theta) = ||y - G_theta(d)||^2,    E_n S = ||y - G_theta(delta)||^2 + P(theta),
    P(theta) = E ||G_theta(n)||^2                          (the cross term has zero mean)

so the noise's passage through the model, P, penalises every model that passes the reading's
high frequencies: the fit shrinks the gain (and lengthens the relaxation, which filters them). For
a gain alone, G_theta = K G, it is the reliability ratio K_hat = K <Gd,Gd> / (<Gd,Gd> + <Gn,Gn>).
The corrected least squares minimises S - P instead, whose expectation is the fit on a noise-free
reading; for the gain alone K = K_hat <Gd_r,Gd_r> / (<Gd_r,Gd_r> - <Gn,Gn>) (d_r the reading).
P is taken by Monte Carlo: REALISATIONS of white noise at sigma_n (held over the reading's updates,
seeded: the same noise at every theta; interpolated from the reading's own samples where the import
did) through the stage's own dynamics under theta, through the
steering map (``passage``). Gauss-Newton on S - P, u_m = G_theta(n_m):

    step = -(J_r'J_r - mean_m J_u'J_u)^-1 (J_r'r - mean_m J_u'u_m),

J_r'J_r - mean J_u'J_u being the curvature on the noise-free reading (its inverse the interval's,
x the residual's variance and n / n_eff as estimation.covariance). Each stage of a block is weighed
by its own level (candidates._fit), the yaw stage's net of the passage, sqrt((RSS - P) / n_eff):
the level it would have on a noise-free reading, the fit being that one's.

The held-out RMS of the yaw stage carries the passage too (its mean square on the held-out part,
``passage_power``), which no model explains: a gain judged by how much of the held-out RMS it
removes is judged on the RMS net of it, sqrt(RMS^2 - P_test) (``net_rms``), as on a noise-free
reading (0.96 of the RMS becomes 0.93 of its explainable part at a passage of 42 %).

For a car the gain alone would hardly move (a reliability ratio of 0.997 at 0.05 deg on a quarter of
a degree: the yaw model passes little of white noise), but the passage is 40 % of the yaw stage's
RSS: least squares weighs the yaw rate 4.6 x less (its level 0.0045 rad/s against 0.0021 on a
noise-free reading) against the track stages of its block (the side-slip,
candidates.Replay.side_slip_block), whose own misfit then sets the gain (1.096 for 1.175
planted; 1.155 on the same log with a noise-free reading, 1.155 corrected). The command's replay
as an instrument (z = S(delta_cmd), J_z' r = 0) would need the steering model to carry the
reading's slow content: it does not carry an offset or a drift of the sensor, which the yaw
stage then reads as a side slope.

S - P is right in expectation only: the realisation's passage differs from P, and along the
direction the turns pin least, the gain against the front cornering stiffness (the data fix their
product; only the understeer's change with speed parts them), that difference moves the gain by
more than its interval (0.013 spread over 15 car logs; 1.162 +- 0.009 for 1.1305 planted, least
squares 1.147, 1.140 on the same log with a noise-free reading; with no gyro noise at all still
1.157 +- 0.004). So where the steering stage's replay carries the wheels (its RMS within EXPLAINED
x sigma_n) the yaw stage is driven by the reading denoised by it (``denoised_fit``): the command's
replay plus the reading's own slow content, the moving mean of their difference over SLOW_CONTENT
(an offset or a drift kept), fitted by least squares with each stage weighed by its level there
(1.145 on that log; 1.290 for 1.289 where corrected least squares gave 1.273); elsewhere (no
command, a steering effect not yet in the model) corrected least squares (``corrected_fit``).

A ratio curve c (the wheels turn g (1 + c g^2)) is read through the same reading, and least squares
shrinks it more than the gain (836 1/rad2 planted on a car log of 120 s: least squares 598 +- 68; on
the same log with a noise-free reading 792; corrected 773 +- 44): it is corrected as the gain is.

sigma_n is the white level of the steering stage's residual (the reading against the command's
replay: noise_floor.stage_floors), or, without a steering stage, of the reading itself. Corrected
only where the passage is at least INPUT_NOISE_SHARE of the yaw stage's RSS: a car's 0.05 deg on
a quarter of a degree (40 %), not a tractor's on 7 degrees.
"""
from __future__ import annotations

import copy
import math

import numpy as np

from agrobot.estimation import FitResult, effective_size, forward_jacobian

from .candidates import _fit
from .fit_memo import MEMO
from .noise_floor import HeldOutNoise, sampled_noise, sampling, sensor_level
from .replay import YawReplay, measured_yaw_rate, wheel_angle_input

INPUT_NOISE_SHARE = 0.05       # the passage's share of the yaw stage's RSS from which it is corrected
REALISATIONS = 6
ITERATIONS = (3, 3)            # reweightings x Gauss-Newton steps each
SLOW_CONTENT = 5.0             # s: the moving mean that keeps the reading's own slow content (denoised_reading)
# a replay's caches that read the wheel angle (candidates.Replay: tracks, saturated replay, fits, fits ahead)
DELTA_CACHES = ("_last_tracks", "_saturated", MEMO, "collecting", "collect_first", "fits_ahead")
EXPLAINED = 1.25               # the steering stage's RMS within this x sigma_n: its replay carries the wheels


def reading_level(replay, sensors: dict | None) -> float:
    """sigma_n [rad]: the white level of the reading's noise on its own samples (module docstring)."""
    level = (sensors or {}).get("delta")
    if level is not None and "steering" in replay.stages and math.isfinite(level):
        return float(level)
    return sensor_level(replay.delta, replay.t, 1.0 / replay.h, sampling(replay, "delta", x=replay.delta))[0]


def noise_draws(replay, sigma_n: float, seed: int = 0) -> list[np.ndarray]:
    """REALISATIONS of white noise at ``sigma_n`` as the reading's rows carry it (noise_floor.sampled_noise:
    held over its updates, or interpolated from its own samples)."""
    how, rng = sampling(replay, "delta", x=replay.delta), np.random.default_rng(seed)
    return [sampled_noise(how, replay.t, sigma_n, rng) for _ in range(REALISATIONS)]


def passage(replay, v: dict[str, float], noise: np.ndarray, part: str = "fit") -> np.ndarray:
    """G_theta(n): the yaw stage's prediction on the reading plus ``noise`` less that on the
    reading, under ``v`` (through the steering map; the linear yaw model, as the gyro sees it), on
    the yaw stage's ``part``."""
    def yaw(d):
        inp = wheel_angle_input(d, None, replay.t, v)
        rate = replay.yaw.yaw_rate(v, d if inp is None else inp)
        return replay.seen("yaw", measured_yaw_rate(rate, v, replay.h))
    return (yaw(replay.delta + noise) - yaw(replay.delta))[replay.masks["yaw"][part]]


def passage_power(replay, v: dict[str, float], sigma_n: float, part: str = "test") -> float:
    """E mean(G_theta(n)^2) on the yaw stage's ``part`` [(rad/s)^2]: what of its mean-square residual
    no model can explain (held out: what a held-out RMS is judged net of, net_rms)."""
    return float(np.mean([np.mean(u * u) for u in (passage(replay, v, n, part) for n in noise_draws(replay, sigma_n))]))


def net_rms(rms: float, power: float, noise: HeldOutNoise | None = None) -> float:
    """sqrt(rms^2 - power): an RMS net of the passage's mean square (at least a tenth of it); and of
    the measurement's realised ``noise`` (noise_floor.HeldOutNoise: sqrt(rms^2 - power - n^2), the
    tenth taken of rms^2 - n^2, at least sqrt(noise.least))."""
    if noise is None:
        return math.sqrt(max(rms * rms - power, 0.01 * rms * rms))
    return math.sqrt(max(rms * rms - power - noise.power, 0.01 * (rms * rms - noise.power), noise.least))


def held_out_gain(before: float, after: float, power: float = 0.0, noise: HeldOutNoise | None = None) -> float:
    """1 - net_rms(after) / net_rms(before): the share of the held-out RMS an effect removes of what
    no model's error leaves unexplained (the passage's ``power``, the measurement's ``noise``:
    noise_floor's module docstring, gain = 1 - sqrt((A - n^2) / (B - n^2))); 0 for a stage with no RMS."""
    return 1.0 - net_rms(after, power, noise) / net_rms(before, power, noise) if before > 0 else 0.0


def corrected_fit(replay, values: dict[str, float], free: list, stages: tuple[str, ...], sigma: dict[str, float],
                  sigma_n: float) -> tuple[FitResult, float] | None:
    """(``free`` refitted on ``stages`` by corrected least squares from ``values``, a least-squares
    fit's (module docstring), scored on those stages; the passage's share of the yaw stage's RSS),
    or None where the share is below INPUT_NOISE_SHARE or there is no yaw stage."""
    if "yaw" not in stages or not free or not sigma_n > 0:
        return None
    draws = noise_draws(replay, sigma_n)
    scale = np.array([p.scale for p in free])
    lo, hi = np.array([p.lower for p in free]) / scale, np.array([p.upper for p in free]) / scale

    def values_of(x):
        return {**values, **{p.name: float(xi) * p.scale for p, xi in zip(free, x)}}

    def residuals(xs):
        return [np.concatenate([replay.residuals(s, values_of(x), "fit") / sigma[s] for s in stages]) for x in xs]

    def passages(xs):
        return [np.concatenate([passage(replay, values_of(x), n) for n in draws]) / sigma["yaw"] for x in xs]

    sigma = dict(sigma)
    x = np.array([values[p.name] for p in free]) / scale
    share, H = 0.0, None
    for i in range(ITERATIONS[0]):
        sigma, now = _levels(replay, values_of(x), stages, draws, sigma)
        share = now if i == 0 else share
        if share < INPUT_NOISE_SHARE:
            return None
        for _ in range(ITERATIONS[1]):
            r, u = residuals([x])[0], passages([x])[0]
            Jr = forward_jacobian(residuals, x, lo, hi, rel_step=1e-3, f0=r)
            Ju = forward_jacobian(passages, x, lo, hi, rel_step=1e-3, f0=u)
            H = Jr.T @ Jr - Ju.T @ Ju / len(draws)
            x = np.clip(x - np.linalg.lstsq(H, Jr.T @ r - Ju.T @ u / len(draws), rcond=None)[0], lo, hi)
    return _result(replay, values_of(x), tuple(free), stages, H, scale, sigma), share


def _levels(replay, v: dict[str, float], stages, draws, sigma: dict[str, float]) -> tuple[dict[str, float], float]:
    """(each stage's level sqrt(RSS / n_eff) under ``v``, the yaw stage's net of the passage: its
    power c0 and lag-1 product c1 less the passages' mean ones, n_eff = n (1 - rho) / (1 + rho) at
    rho = c1 / c0 so net, as estimation.effective_size; the passage's share P / RSS of the yaw stage)."""
    out, share = dict(sigma), 0.0
    for s in stages:
        r = replay.residuals(s, v, "fit")
        rss, n_eff = float(r @ r), effective_size(r, updates=replay.updates(s))
        if s == "yaw" and draws:
            u = [passage(replay, v, n) for n in draws]
            P0, P1 = (float(np.mean([x @ x for x in u])), float(np.mean([x[1:] @ x[:-1] for x in u])))
            share = P0 / rss if rss > 0 else 0.0
            c = r - r.mean()
            net0, net1 = max(float(c @ c) - P0, 0.01 * rss), float(c[1:] @ c[:-1]) - P1
            rho = min(max(net1 / net0, 0.0), 0.98)
            rss, n_eff = max(rss - P0, 0.01 * rss), len(r) * (1 - rho) / (1 + rho)
            if replay.updates(s) is not None:
                n_eff = min(n_eff, float(replay.updates(s)))
        out[s] = math.sqrt(rss / max(n_eff, 1.0)) or sigma[s]
    return out, share


def _result(replay, values: dict[str, float], free: tuple, stages, H: np.ndarray, scale: np.ndarray,
            sigma: dict[str, float]) -> FitResult:
    """The corrected fit scored on ``stages``, its covariance from the corrected curvature ``H``
    (scaled parameters, residuals over ``sigma``: estimation.covariance's RSS / (n - k) x n / n_eff)."""
    rss, n, n_eff, rmse = {}, {}, {}, {}
    for s in stages:
        r, rt = replay.residuals(s, values, "fit", "test")
        rss[s], n[s], n_eff[s] = float(r @ r), len(r), effective_size(r, updates=replay.updates(s))
        rmse[s] = float(np.sqrt(np.mean(rt ** 2)))
    total = sum(rss[s] / sigma[s] ** 2 for s in stages)
    size, size_eff, k = sum(n.values()), sum(n_eff.values()), len(scale)
    cov = np.linalg.pinv(H) * total / max(size - k, 1) * size / max(size_eff, 1.0) * np.outer(scale, scale)
    return FitResult(values, free, cov, rss, n, n_eff, rmse)


def denoised_reading(replay, v: dict[str, float]) -> np.ndarray:
    """d_s = S_v(delta_cmd) + mean_W(d - S_v(delta_cmd)): the steering stage's replay of the command
    under ``v`` (through the steering map) carrying the reading d's own slow content, its moving mean
    over SLOW_CONTENT (a sensor's offset or drift); the white noise left is 1 / (W / h) of the
    reading's (a hundredth at 20 Hz)."""
    s = replay.predicted("steering", v)
    n = max(1, int(round(SLOW_CONTENT / replay.h)))
    miss = np.pad(replay.delta - s, (n // 2, n - 1 - n // 2), mode="edge")
    return s + np.convolve(miss, np.ones(n) / n, mode="valid")


def with_reading(replay, delta: np.ndarray):
    """``replay`` with its yaw stage driven by ``delta`` for the reading: the log's arrays and what does
    not read the wheel angle (the track's whitening, the steering replays) shared, the yaw replay
    built on it, the caches that read it (tracks, the saturated replay, remembered fits) left behind."""
    quiet = copy.copy(replay)
    for key in DELTA_CACHES:
        quiet.__dict__.pop(key, None)
    quiet.delta = delta
    b = replay.baseline
    quiet.yaw = YawReplay(b.yaw_model, b.tractor, replay.h, delta, replay.speed, replay.heading,
                          min_speed=replay.min_speed, kernel=replay.kernel, geometry=b.steering_geometry)
    return quiet


def denoised_fit(replay, values: dict[str, float], free: list, stages: tuple[str, ...], sigma_n: float,
                 share: float) -> tuple[FitResult, float] | None:
    """(``free`` refitted on ``stages`` from ``values`` by least squares with the yaw stage driven by
    the denoised reading (denoised_reading: the command as an instrument, the reading's slow content
    kept), each stage weighed by its level there; ``share``), or None where the steering stage is not
    replayed, is fitted too (it is judged on the reading itself) or its replay does not carry the
    wheels (its fit part's RMS above EXPLAINED x sigma_n: a steering effect the model does not hold yet)."""
    if "steering" not in replay.stages or "steering" in stages or not np.all(np.isfinite(replay.cmd)):
        return None
    miss = replay.residuals("steering", values, "fit")
    if not float(np.sqrt(np.mean(miss ** 2))) <= EXPLAINED * sigma_n:
        return None
    quiet = with_reading(replay, denoised_reading(replay, values))
    levels = {s: float(np.sqrt(np.mean(quiet.residuals(s, values, "fit") ** 2))) or 1.0 for s in stages}
    return _fit(quiet, values, free, stages, [{}], levels), share


def noise_free_fit(replay, values: dict[str, float], free: list, stages: tuple[str, ...], sigma: dict[str, float],
                   sigma_n: float) -> tuple[FitResult, float, str] | None:
    """(``free`` refitted on ``stages`` as on a noise-free reading, the passage's share of the yaw
    stage's RSS, how): denoised_fit where the steering stage's replay carries the wheels, else
    corrected_fit; None where the share is below INPUT_NOISE_SHARE or there is no yaw stage."""
    if "yaw" not in stages or not free or not sigma_n > 0:
        return None
    share = _levels(replay, values, stages, noise_draws(replay, sigma_n), sigma)[1]
    if share < INPUT_NOISE_SHARE:
        return None
    out = denoised_fit(replay, values, free, stages, sigma_n, share)
    if out is not None:
        return (*out, f"least squares on the reading denoised by the command's replay (its {SLOW_CONTENT:g} s "
                      f"moving mean kept)")
    out = corrected_fit(replay, values, free, stages, sigma, sigma_n)
    return None if out is None else (*out, "corrected least squares")
