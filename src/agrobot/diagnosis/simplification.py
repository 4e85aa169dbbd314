"""What the baseline's own simplifications leave on a healthy log.

The replay is simpler than the study it comes from: the steering is its first-order equivalent
(the study's steering component is a PI around a valve with a dead-band and a spool lag, closed
on a potentiometer), and the yaw model is fed the *measured* wheel angle, which a potentiometer
reports in steps of q. A tractor with no fault, described exactly by the study, still leaves a
residual above the sensors' white noise in both stages. Its size is measured, for this log, on a
*healthy twin*:

- steering: the study's own steering component, its potentiometer set to the log's resolution q
  (measurements.log.resolution; for an imported recording, read on the sensor's own frames), driven by the log's delta_cmd; its reading (plus white noise of the
  log's level beyond quantisation, sqrt(max(w^2 - q^2/12, 0))) is replayed through the
  first-order equivalent with its time constant refitted on the fit part, as the diagnosis does;
  the held-out RMS is what a healthy steering leaves;
- yaw: the fitted yaw model driven by the twin's true wheel angle and by its reading; the RMS of the
  difference (held-out part) is the quantised input's share, added in quadrature to the gyro's
  white level.

A stage is only called misfit when its residual exceeds this healthy level materially
(unexplained.is_misfit), and the report states the level beside the noise floor.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import least_squares

from agrobot.measurements.log import resolution

from .replay import steering_replay

COMMAND, TRUE, READING = "steer_angle_cmd", "steer_angle", "steer_angle_measured"
RESOLUTION_PARAMETER = "potentiometer_resolution"


def steering_twin(baseline, cmd: np.ndarray, h: float, q: float, seed: int = 0) -> tuple[np.ndarray, np.ndarray] | None:
    """(true angle, reading) of the study's steering component driven by ``cmd`` held over each
    step ``h``, its potentiometer at ``q``; None when the study's steering has not the ports
    (steer_angle_cmd in, steer_angle and steer_angle_measured out)."""
    view = baseline.study
    if view is None or not view.has("steering"):
        return None
    model, name = view.model, view.names["steering"]
    cls = model.component_class(name)
    if not {COMMAND} <= set(cls.declared("input")) or not {TRUE, READING} <= set(cls.declared("output")):
        return None
    params = dict(model.parameters(name))
    if RESOLUTION_PARAMETER in params:
        params[RESOLUTION_PARAMETER] = q
    comp = cls(name, params, np.random.default_rng(seed))
    comp.initialize(0.0, h)
    true, reading = np.empty(len(cmd)), np.empty(len(cmd))
    try:
        for k, c in enumerate(cmd):
            true[k], reading[k] = comp.y[TRUE], comp.y[READING]
            comp.u[COMMAND] = float(c)
            comp.step(k * h, h)
    finally:
        comp.terminate()
    return true, reading


def healthy_levels(replay, values: dict, floors: dict, seed: int = 0) -> dict:
    """Per replayed stage: the held-out RMS a healthy vehicle described exactly by the study
    leaves in this log's replay, and how it was found (the steering and yaw stages from the twin;
    the others, and a log without a steering command, from their noise floors and the quantised
    wheel angle alone)."""
    h = replay.h
    q = 0.0 if getattr(replay, "command_only", False) else \
        (replay.frame.attrs.get("resolution", {}).get("delta") or resolution(replay.delta))
    out = {"delta_resolution": q, "how": {}, **{s: floors[s] for s in replay.stages}}
    if "steering" not in replay.stages:
        if "yaw" in replay.stages and q > 0:
            smooth = np.convolve(replay.delta, np.ones(9) / 9.0, mode="same")        # a plausible true angle
            share = _quantised_input_share(replay, values, smooth, q * np.round(smooth / q))
            out["yaw"] = math.hypot(floors["yaw"], share)
            out["how"]["yaw"] = (f"the yaw model driven by a smoothed wheel angle and by it quantised to the log's "
                                 f"{math.degrees(q):.3g} deg steps: {math.degrees(share):.3g} deg/s, with the gyro's white level")
        return out
    key = ("steering_twin", q, seed)              # the twin depends on the log only: simulated once per replay
    cache = replay.__dict__.setdefault("_cache", {})
    if key not in cache:
        cache[key] = steering_twin(replay.baseline, replay.cmd, h, q, seed)
    twin = cache[key]
    if twin is None:
        out["how"]["steering"] = "noise floor only: the study's steering has no steer_angle_cmd/steer_angle/" \
                                 "steer_angle_measured ports to simulate"
        return out
    true, reading = twin
    rng = np.random.default_rng([seed, 28])
    white = math.sqrt(max(floors["_sensors"]["delta"] ** 2 - q ** 2 / 12.0, 0.0))
    measured = reading + white * rng.standard_normal(len(reading))
    if q > 0:
        measured = q * np.round(measured / q)
    fit, test = replay.masks["steering"]["fit"], replay.masks["steering"]["test"]

    def residual(x, mask):
        return (measured - steering_replay(replay.cmd, h, {**values, "steering_time_constant": x[0]}, measured[0]))[mask]

    tau0 = values["steering_time_constant"]
    sol = least_squares(lambda x: residual(x, fit), [tau0], bounds=([0.005], [1.0]), diff_step=1e-3, max_nfev=50)
    steer = float(np.sqrt(np.mean(residual(sol.x, test) ** 2)))
    out["steering"] = max(steer, floors["steering"])
    out["how"]["steering"] = (f"the study's steering component with a {math.degrees(q):.3g} deg potentiometer, driven "
                              f"by the log's delta_cmd, replayed through the first-order equivalent "
                              f"(tau refitted: {sol.x[0]:.3f} s): held-out RMS {math.degrees(steer):.3g} deg")
    if "yaw" in replay.stages:
        share = _quantised_input_share(replay, values, true, measured)
        out["yaw"] = math.hypot(floors["yaw"], share)
        out["how"]["yaw"] = (f"the yaw model driven by the twin's measured instead of its true wheel angle: "
                             f"{math.degrees(share):.3g} deg/s held-out RMS, with the gyro's white level "
                             f"{math.degrees(floors['yaw']):.3g} deg/s")
    return out


def _quantised_input_share(replay, values: dict, true: np.ndarray, measured: np.ndarray) -> float:
    """Held-out RMS of the yaw model's response to the measured minus the true wheel angle."""
    test = replay.masks["yaw"]["test"]
    both = replay.yaw.response_to(np.column_stack([true, measured]), values)
    return float(np.sqrt(np.mean((both[test, 1] - both[test, 0]) ** 2)))
