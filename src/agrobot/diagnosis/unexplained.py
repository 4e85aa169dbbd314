"""What the best catalogued model leaves unexplained.

Per stage, the held-out residual of the final model is compared with the stage's noise floor
(noise_floor.py). A stage is *misfit* when both

    rms_test / floor > RATIO                        (the residual is not just sensor noise), and
    excess = sqrt(rms_test^2 - floor^2) >= MATERIAL[stage]   (the misfit matters physically).

For a misfit stage the residual is tested further:

- whiteness: lag-1 autocorrelation and the Ljung-Box statistic over 20 lags (a misfit is coloured);
- the signal it correlates with: the largest |cross-correlation| over lags -2..2 s with the inputs
  and states of the stage (evidence.cross_correlation); for the position stage, the correlation of
  the residual with the change a 1% scale error of each dead-reckoning input would make;
- a data-driven extension of the stage, fitted on the training part and scored on the held-out
  part: for a time-series stage the best of an FIR correction (10 taps over 1 s), a static
  piecewise-linear map, or both, of one signal, added to the stage's output and chosen by BIC on
  the training part; for the position stage, a gain on each input of the dead reckoning (speed, yaw
  rate), fitted by least squares.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import chi2

from .evidence import cross_correlation
from .replay import aligned_residuals, antenna_track

DEG = math.pi / 180
RATIO = 1.5
MATERIAL = {"steering": 0.25 * DEG, "yaw": 0.005, "position": 0.03, "speed": 0.03}
UNITS = {"steering": "rad", "yaw": "rad/s", "position": "m", "speed": "m/s"}


def stage_signals(replay, stage: str, values: dict) -> dict[str, np.ndarray]:
    """The inputs and states a stage's residual is tested against (whole-log arrays; a signal
    the log does not have is left out)."""
    h = replay.h
    if stage == "steering":
        out = {"delta_cmd": replay.cmd, "delta_cmd_rate": np.gradient(replay.cmd, h),
               "delta_predicted": replay.predicted("steering", values)}
    elif stage == "yaw":
        predicted = replay.predicted("yaw", values)
        out = {"delta": replay.delta, "v": replay.speed, "delta*v": replay.delta * replay.speed,
               "yaw_rate_predicted": predicted, "lateral_acceleration": replay.speed * predicted, "t": replay.t}
        if {"x", "y"} <= set(replay.frame.columns):        # a heading from the GPS course
            out.update(cos_heading=np.cos(replay.heading), sin_heading=np.sin(replay.heading))
    elif stage == "speed":
        out = {"v": replay.speed, "abs_yaw_rate": np.abs(replay.gyro), "dv_dt": np.gradient(replay.speed, h),
               "abs_delta": np.abs(replay.delta), "t": replay.t}
    else:
        raise KeyError(stage)
    return {k: v for k, v in out.items() if np.isfinite(v).all()}


def whiteness(res: np.ndarray, lags: int = 20) -> dict:
    r = res - res.mean()
    d = float(r @ r) or 1.0
    rho = np.array([float(r[k:] @ r[:-k]) / d for k in range(1, lags + 1)])
    n = len(r)
    q = n * (n + 2) * float(np.sum(rho ** 2 / (n - np.arange(1, lags + 1))))
    return {"lag1_autocorrelation": float(rho[0]), "ljung_box_q": q, "p_value": float(chi2.sf(q, lags)),
            "white": bool(chi2.sf(q, lags) > 0.01)}


def _lagged(x: np.ndarray, taps: int = 10, spacing: int = 2) -> np.ndarray:
    cols = []
    for j in range(taps):
        k = j * spacing
        cols.append(np.concatenate([np.full(k, x[0]), x[:len(x) - k]]) if k else x)
    return np.column_stack(cols)


def _hats(x: np.ndarray, knots: np.ndarray) -> np.ndarray:
    """Piecewise-linear (hat) basis on ``knots``: a static map of x, continued linearly beyond the
    end knots (the end segments' slopes), so that a map fitted on part of the range extrapolates
    like a straight line instead of going flat."""
    k = np.asarray(knots, float)
    if len(k) < 2:                                     # a signal on one value: no map to fit
        return np.zeros((len(x), 1))
    i = np.clip(np.searchsorted(k, x, side="right") - 1, 0, len(k) - 2)
    w = (x - k[i]) / (k[i + 1] - k[i])                 # < 0 left of the range, > 1 right of it
    out = np.zeros((len(x), len(k)))
    rows = np.arange(len(x))
    out[rows, i] = 1.0 - w
    out[rows, i + 1] = w
    return out


def _time_series_extension(replay, stage: str, values: dict, signals: dict, only: tuple | None = None) -> dict:
    res = replay.measured(stage) - replay.predicted(stage, values)
    fit, test = replay.masks[stage]["fit"], replay.masks[stage]["test"]
    best = None
    for name, x in signals.items():
        if name == "t" or (only and only[1] != name):
            continue
        xs = (x - x[fit].mean()) / (x[fit].std() or 1.0)
        knots = np.quantile(xs[fit], np.linspace(0.02, 0.98, 7))
        fir, static = _lagged(xs), _hats(xs, np.unique(knots))
        for kind, X in (("fir", fir), ("static_map", static), ("static_map+fir", np.column_stack([static, fir[:, 1:]]))):
            if only and only[0] != kind:
                continue
            X = np.column_stack([np.ones(len(xs)), X])
            if not (np.all(np.isfinite(X[fit])) and np.all(np.isfinite(res[fit]))):
                continue
            coef, *_ = np.linalg.lstsq(X[fit], res[fit], rcond=None)
            rss = float(np.sum((res[fit] - X[fit] @ coef) ** 2))
            n = int(fit.sum())
            bic = n * math.log(max(rss / n, 1e-300)) + X.shape[1] * math.log(n)
            if best is None or bic < best[0]:
                best = (bic, name, kind, X, coef)
    if stage == "yaw" and (not only or only[0] == "input_map"):
        bic, X, coef = _yaw_input_map(replay, values)
        if best is None or bic < best[0]:
            best = (bic, "delta", "input_map", X, coef)
    _, name, kind, X, coef = best
    before = float(np.sqrt(np.mean(res[test] ** 2)))
    after = float(np.sqrt(np.mean((res[test] - X[test] @ coef) ** 2)))
    what = {"fir": "FIR correction on {s}: 10 taps over 1 s of the standardised signal",
            "static_map": "static map of {s}: piecewise-linear in the standardised signal, 7 knots at its quantiles",
            "static_map+fir": "static map (7 knots) plus FIR (9 delayed taps over 1 s) of the standardised {s}",
            "input_map": "static map of {s} (9 knots at its quantiles) feeding the yaw dynamics in its place, "
                         "cornering and relaxation scales refitted with it"}[kind].format(s=name)
    return {"kind": kind, "signal": name, "description": f"{what}; plus a constant, added to the stage's output",
            "coefficients": [float(c) for c in coef], "rms_before": before, "rms_after": after,
            "held_out_gain": 1.0 - after / before if before > 0 else 0.0}


def _yaw_input_map(replay, values: dict) -> tuple[float, np.ndarray, np.ndarray]:
    """Hammerstein extension of the yaw stage: the steering angle through a static map (hat basis,
    9 knots at its quantiles) into the yaw dynamics, with the cornering scales refitted together
    (variable projection: the map's weights by linear least squares inside a nonlinear fit of the
    stage's three uncertain scales). Returns (BIC on the fit part, regressors whose fit reproduces the correction, coef);
    the regressors are expressed on the final model's residual so that res - X c is the new residual."""
    fit = replay.masks["yaw"]["fit"]
    d = replay.delta
    knots = np.unique(np.quantile(d[fit], np.linspace(0.01, 0.99, 9)))
    hats = _hats(d, knots)
    linear_part = replay.yaw.response_to(d[:, None], values)[:, 0]
    target = replay.gyro - (replay.predicted("yaw", values) - linear_part)     # what the delta path must give

    names = ("cornering_front_scale", "cornering_rear_scale", "relaxation_scale")

    def design(x):
        v = {**values, **dict(zip(names, x))}
        return np.column_stack([np.ones(len(d)), replay.yaw.response_to(hats, v, through_geometry=False)])

    def fun(x):
        X = design(x)
        coef, *_ = np.linalg.lstsq(X[fit], target[fit], rcond=None)
        return target[fit] - X[fit] @ coef

    lo, hi = np.array([0.4, 0.4, 0.3]), np.array([2.5, 2.5, 3.0])
    x0 = np.clip([values[k] for k in names], lo + 1e-3, hi - 1e-3)
    sol = least_squares(fun, x0, bounds=(lo, hi), diff_step=1e-3, max_nfev=60)
    X = design(sol.x)
    coef, *_ = np.linalg.lstsq(X[fit], target[fit], rcond=None)
    n = int(fit.sum())
    rss = float(sol.fun @ sol.fun)
    bic = n * math.log(max(rss / n, 1e-300)) + (X.shape[1] + len(names)) * math.log(n)
    # res - X' c = target - X c  with  X' c = X c - linear_part  (res = target - linear_part)
    X_res = np.column_stack([X, -linear_part])
    return bic, X_res, np.append(coef, 1.0)


def _track_with_gains(replay, values: dict, gains) -> np.ndarray:
    return antenna_track(replay.t, gains[1] * replay.gyro, gains[0] * replay.speed, values, replay.lateral(values))


def _position_analysis(replay, values: dict) -> tuple[dict, dict]:
    """(correlation, extension) of the position stage: gains on the dead reckoning's inputs."""
    def res(gains, part):
        return aligned_residuals(_track_with_gains(replay, values, gains), replay.gps, replay.windows[part]).ravel()

    r0 = res((1.0, 1.0), "fit")
    corr = {}
    for i, name in enumerate(("v", "yaw_rate")):
        g = [1.0, 1.0]
        g[i] = 1.01
        direction = r0 - res(g, "fit")
        corr[name] = float(np.corrcoef(r0, direction)[0, 1]) if np.std(direction) > 0 else 0.0
    name = max(corr, key=lambda k: abs(corr[k]))
    sol = least_squares(lambda g: res(g, "fit"), [1.0, 1.0], bounds=([0.5, 0.5], [1.5, 1.5]), diff_step=1e-4)
    before = float(np.sqrt(np.mean(res((1.0, 1.0), "test") ** 2)))
    after = float(np.sqrt(np.mean(res(sol.x, "test") ** 2)))
    extension = {"kind": "input_gains", "signal": "v, yaw_rate",
                 "description": "gains on the dead reckoning's inputs: speed x g_v, yaw rate x g_yaw_rate",
                 "coefficients": {"g_v": float(sol.x[0]), "g_yaw_rate": float(sol.x[1])},
                 "rms_before": before, "rms_after": after, "held_out_gain": 1.0 - after / before if before > 0 else 0.0}
    return {"signal": name, "rho": corr[name], "lag_s": 0.0, "all": corr}, extension


def extension(replay, stage: str, values: dict, like: dict | None = None) -> dict:
    """The stage's best data-driven extension under ``values`` (fitted on the training part);
    ``like``: an extension whose kind and signal are reused (to compare two models fairly)."""
    if stage == "position":
        return _position_analysis(replay, values)[1]
    only = (like["kind"], like["signal"]) if like else None
    return _time_series_extension(replay, stage, values, stage_signals(replay, stage, values), only)


def materiality(stage: str, floors: dict) -> float:
    """MATERIAL, and for the steering stage at least half the wheel-angle sensor's resolution: a
    servo closed on a sensor of step q holds the wheel anywhere within about q/2 of its command,
    so a smaller misfit says where each hold ended, not what the model lacks."""
    q = floors.get("_healthy", {}).get("delta_resolution", 0.0)
    return max(MATERIAL[stage], 0.5 * q) if stage == "steering" else MATERIAL[stage]


def is_misfit(stage: str, rms_test: float, floors: dict) -> bool:
    """Above the noise floor by RATIO, and above what a healthy tractor leaves (the baseline's
    simplifications, simplification.healthy_levels) by a material amount: above
    max(RATIO floor, hypot(healthy, materiality)), the ``misfit_level`` of stage_check."""
    floor = floors[stage]
    healthy = floors.get("_healthy", {}).get(stage, floor)
    return floor > 0 and rms_test / floor > RATIO and rms_test ** 2 - healthy ** 2 >= materiality(stage, floors) ** 2


def stage_check(replay, stage: str, values: dict, floors: dict, rms_fit: float, rms_test: float) -> dict:
    """The floor comparison of one stage; the correlation and the extension when it is misfit."""
    floor = floors[stage]
    healthy = floors.get("_healthy", {}).get(stage, floor)
    excess = math.sqrt(max(rms_test ** 2 - floor ** 2, 0.0))
    out = {"stage": stage, "unit": UNITS[stage], "floor": floor, "rms_fit": rms_fit, "rms_test": rms_test,
           "ratio": rms_test / floor if floor > 0 else math.inf, "excess": excess, "materiality": materiality(stage, floors),
           "healthy_level": healthy, "excess_over_healthy": math.sqrt(max(rms_test ** 2 - healthy ** 2, 0.0)),
           "misfit_level": max(RATIO * floor, math.hypot(healthy, materiality(stage, floors))),
           "healthy_how": floors.get("_healthy", {}).get("how", {}).get(stage, "the noise floor")}
    out["misfit"] = is_misfit(stage, rms_test, floors)
    if not out["misfit"]:
        return out
    if stage == "position":
        out["correlates_with"], out["extension"] = _position_analysis(replay, values)
        return out
    signals = stage_signals(replay, stage, values)
    t, res = replay.residual_series(stage, values)
    sel = replay.scored(stage)
    out["whiteness"] = whiteness(res)
    best = None
    for name, x in signals.items():
        lags, rho, bound = cross_correlation(res, x[sel], 1.0 / replay.h)
        i = int(np.argmax(np.abs(rho)))
        if best is None or abs(rho[i]) > abs(best["rho"]):
            best = {"signal": name, "rho": float(rho[i]), "lag_s": float(lags[i]), "bound": float(bound)}
    out["correlates_with"] = best
    out["extension"] = _time_series_extension(replay, stage, values, signals)
    return out


# what a data-driven extension's form says in physical terms, and the run that would tell
SIGNATURES = {
    "lateral": ("a static function of lateral acceleration: the tyres (a lateral force that falls behind C alpha, "
                "or grows faster than it)",
                "steady turns at rising speed up to the highest lateral acceleration of the log (a ramp steer)"),
    "angle": ("a static function of the wheel angle: the steering geometry (a ratio varying with the angle, "
              "Ackermann read at one wheel, a linkage's play)",
              "steady circles at walking speed at several wheel angles up to full lock, both ways"),
    "speed": ("a function of speed: a cornering stiffness or a sensor scale that changes with speed",
              "the same steering sequence driven at three speeds"),
    "lag": ("a dynamic lag: the residual follows {s} over a second (a delay, a lag or a mode the model lacks)",
            "steering steps of a few degrees at two speeds: a delay shifts every step, a lag rounds it, a mode rings"),
    "drift": ("a drift with time or heading: a bias that wanders, a slope, or a heading-dependent disturbance",
              "the same loop driven clockwise and anticlockwise, and a minute standing still at the start and end"),
    "gains": ("gains on the dead reckoning's inputs: a speed scale (wheel radius, slip) or a gyro scale",
              "a straight run of known length and a full circle at constant speed"),
}


def signature(extension: dict) -> dict:
    """{form, physical, experiment}: the extension that carries over, read as an engineer reads it."""
    kind, sig = extension["kind"], extension["signal"]
    if kind == "input_gains":
        key = "gains"
    elif sig in ("t", "cos_heading", "sin_heading"):
        key = "drift"
    elif kind == "fir":
        key = "lag"
    elif sig in ("lateral_acceleration", "yaw_rate_predicted"):
        key = "lateral"
    elif sig in ("delta", "abs_delta", "delta_cmd", "delta_predicted"):
        key = "angle"
    else:
        key = "speed"
    physical, experiment = SIGNATURES[key]
    return {"form": key, "physical": physical.format(s=sig), "experiment": experiment}
