"""Diagnosis on logs with a hidden effect from the independent truth tractor
(harness.truth_tractor): one runner for the tests and the benchmark, and the stated
tolerances of each effect's headline parameter."""
from __future__ import annotations

import math
import multiprocessing
import os
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from scipy.signal import lfilter

from agrobot.components.models.tyre import force_limit_share
from agrobot.diagnosis import pipeline
from agrobot.diagnosis.parallel_fits import default_workers
from agrobot.diagnosis.pipeline import diagnose
from agrobot.studies import shipped
from harness.truth_tractor import DEG, EFFECTS, TABLE, UNLISTED, make_log

__all__ = ["EFFECTS", "diagnose_hidden", "diagnose_many", "expected_ids", "filtered_gyro", "recovered"]


# truth faults the catalogue has since named: truth id -> the effect a right diagnosis names
NAMED = {"gyro_scale_factor": "gyro_scale", "wheel_slip": "speed_scale", "tyre_saturation": "tyre_saturation",
         "steering_sensor_gain": "steering_gain"}


def expected_ids(truth: dict) -> set[str]:
    """The effect ids a right diagnosis of a truth log finds: its catalogue effects (an antenna
    off its place read late is a position reference on a lagging clock: one cause, the
    recording's), and 'unexplained' when it holds a fault outside the catalogue."""
    ids = {NAMED.get(i, i) for i in truth["effects"]}
    if {"antenna_lever_arm", "gps_latency"} <= ids:
        ids = (ids - {"antenna_lever_arm", "gps_latency"}) | {"position_reference"}
    unlisted = ids & (set(UNLISTED) - set(NAMED))
    return (ids - unlisted) | ({"unexplained"} if unlisted else set())


def recovered(effect: str, truth: dict, params: dict) -> tuple[float, float, float]:
    """(estimate, truth, tolerance) of each effect's headline parameter; tolerances are stated here."""
    if effect == "actuator_delay":
        return params["command_delay"], truth["delay"], 0.03                        # s
    if effect == "steering_deadband":
        return params["steering_deadband"], truth["deadband"] + 0.5 / 150, 0.5 * DEG
    if effect == "steering_rate_limit":
        return params["steering_rate_limit"], truth["rate"], 0.2 * truth["rate"]
    if effect == "steering_offset":
        return params["steer_angle_offset"], truth["offset"], 0.3 * DEG
    if effect == "yaw_rate_bias":
        return params["yaw_rate_bias"], truth["bias"], 0.003                         # rad/s
    if effect == "gps_latency":
        return params["gps_latency"], truth["latency"], 0.04                         # s
    if effect == "speed_dependent_cornering":     # per m/s at a 2 m/s reference: relative (truth_tractor)
        relative = 2.0 / truth.get("v_ref", 2.0)
        return params["cornering_speed_slope"] / relative, truth["k"], 0.08
    if effect == "side_slope":
        return math.asin(math.hypot(params["slope_east"], params["slope_north"]) / 9.81), truth["slope"], 1.0 * DEG
    if effect == "antenna_lever_arm":
        err = math.hypot(params["antenna_forward"] - truth["forward"], params["antenna_left"] - truth["left"])
        return err, 0.0, 0.15                                                        # m, both axes
    if effect == "position_reference":               # the point (m, both axes) and the clock (s) in one number
        err = math.hypot(params["position_forward"] + TRUTH_ANTENNA - truth["forward"],
                         params["position_left"] - truth["left"])
        return max(err / 0.15, abs(params["position_clock"] - truth["latency"]) / 0.04), 0.0, 1.0
    if effect == "gyro_scale":
        return params["gyro_scale"], truth["gyro_scale"], 0.02
    if effect == "speed_scale":
        return params["speed_scale"], 1.0 + truth["slip"], 0.02
    if effect == "tyre_saturation":     # the truth's F = C a / (1 + |a| / a_s) tends to C_f a_s at the front axle:
        # an equivalent friction C_f a_s / F_zf; the Magic Formula differs in shape, hence 35 %
        m, lf, lr = truth.get("m", TABLE["m"]), TABLE["l_f"], TABLE["l_r"]
        mu = truth["C_f"] * truth["alpha_s"] / (m * 9.81 * lr / (lf + lr))
        return params["tyre_friction"] * force_limit_share(params["tyre_shape"]), mu, 0.35 * mu
    if effect == "steering_gain":                # a command-only log of a sensor read g x the angle, the loop
        return params["steering_gain"], 1.0 / truth["sensor_gain"], 0.03     # closed on it: wheels turn cmd / g
    if effect == "steering_clock":
        return params["steering_clock"], truth["steering_clock"], 0.04
    if effect == "gyro_filter":                  # the vehicle's own lag the baseline misses biases it (~0.02 s)
        return params["gyro_time_constant"], truth["gyro_time_constant"], 0.03              # s
    if effect == "steering_ratio_curve":
        return params["steering_ratio_curvature"], truth["ratio_curvature"], 0.25 * truth["ratio_curvature"]
    raise KeyError(effect)


def filtered_gyro(frame, tau: float, fine: float = 0.001):
    """The log with its yaw_rate read through a first-order low-pass of time constant ``tau`` [s]:
    tau y' = r - y integrated exactly on a ``fine`` grid, r linear between the rows, from rest at r[0]."""
    t, r = frame["t"].to_numpy(float), frame["yaw_rate"].to_numpy(float)
    tf = np.arange(t[0], t[-1] + fine / 2, fine)
    y = lfilter([1.0 - math.exp(-fine / tau)], [1.0, -math.exp(-fine / tau)], np.interp(tf, t, r),
                zi=[math.exp(-fine / tau) * r[0]])[0]
    out = frame.copy()
    out["yaw_rate"] = np.interp(t, tf, y)
    return out


TRUTH_ANTENNA = 0.0       # m: the baseline studies' antenna_forward (figure8, passenger_car: at the rear axle)


BLAS_THREADS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
STUDIES = shipped()
BASELINES = {"tractor": STUDIES / "figure8.toml", "car": STUDIES / "passenger_car.toml"}


def diagnose_hidden(case: tuple) -> dict:
    """Write the log of (effect, seed, folder[, TABLE scale[, duration[, healthy variant[, vehicle[, values[,
    identify]]]]]]) to ``folder`` and diagnose it (no plots) against the vehicle's baseline study (BASELINES);
    ``identify`` (default False: the truths' catalogue is judged on the diagnosis alone, five times cheaper)
    identifies the vehicle on the same log first, as ``diagnose`` does for a user;
    ``effect`` may be several ids joined by '+', ``healthy`` one or several of truth_tractor.HEALTHY
    (a truth without fault that differs from the baseline), ``values`` magnitudes that replace the
    drawn ones (truth_tractor.make_log)."""
    effect, seed, folder, *rest = case
    scale = rest[0] if rest else None
    duration = rest[1] if len(rest) > 1 else 240.0
    healthy = rest[2] if len(rest) > 2 else None
    vehicle = rest[3] if len(rest) > 3 else "tractor"
    values = rest[4] if len(rest) > 4 else None
    identify = bool(rest[5]) if len(rest) > 5 else False
    frame, truth = make_log(seed, effect, scale=scale, duration=duration, healthy=healthy, vehicle=vehicle,
                            values=values)
    name = f"{vehicle}_{effect or 'none'}_{healthy.replace('+', '-') + '_' if healthy else ''}{seed}"
    log = Path(folder) / f"{name}.parquet"
    frame.to_parquet(log)
    result = diagnose(log, Path(folder) / name, plots=False, study_path=BASELINES[vehicle], identify=identify)
    found = "+".join(sorted(e["id"] for e in result["effects"])) or "none"
    print(f"{name}: {found} (expected {'+'.join(sorted(expected_ids(truth))) or 'none'})", file=sys.stderr, flush=True)
    return {"effect": effect or "none", "healthy": healthy or "", "seed": seed, "truth": truth, "result": result}


def _fit_on(cores: int) -> None:
    """A case worker's diagnoses fit their candidates on ``cores`` processes (pipeline's default)."""
    pipeline.default_workers = lambda: cores


def diagnose_many(cases: list[tuple], workers: int = 2, run=None) -> list[dict]:
    """diagnose_hidden (or ``run``, a module-level function of one case) over worker processes, each
    with single-threaded BLAS: two processes spinning two BLAS threads each on two cores run 3x slower
    than one process. Each diagnosis fits its candidates on its share of the cores (the result is the
    same whatever the number: tests/test_diagnosis_workers.py), not on every core: two cases each
    fitting ahead on two processes on two cores spend CPU on fits the selection never asks for."""
    saved = {k: os.environ.get(k) for k in BLAS_THREADS}
    os.environ.update({k: "1" for k in BLAS_THREADS})
    share = max(1, default_workers() // max(1, int(workers)))
    try:
        with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn"),
                                 initializer=_fit_on, initargs=(share,)) as pool:
            return list(pool.map(run or diagnose_hidden, cases))
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k)
            else:
                os.environ[k] = v
