"""More vehicle classes for the truth (harness.truth_tractor) and their baseline studies, and a
steering map planted on a truth log.

- ``ackermann``: a small Ackermann machine (a field robot of 120 kg, wheelbase 1.27 m) driven at
  0.5-0.85 m/s with a fast servo steering: lateral accelerations below 1 m/s2, the kinematic
  regime r = v tan(delta) / L. Registered in truth_tractor.VEHICLES on import, so that
  ``make_log(..., vehicle="ackermann")`` draws it; ``study(folder)`` writes its baseline study.
- ``steering_map(frame, ...)``: the log as a machine whose steering map is off reads it: the wheels
  turn M(reading) = k reading (1 + a sign(reading)) (1 + c reading^2) + offset, so the log's command
  and wheel angle (both in the reading's units) are M^-1 of the truth's angles. The truth's own
  dynamics and sensors are untouched; the planted map is known, the diagnosis is not told it.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from agrobot.diagnosis.pipeline import diagnose
from agrobot.studies import shipped
from harness.truth_tractor import DEG, VEHICLES, make_log

ACKERMANN = dict(m=120.0, I=30.0, l_f=0.6, l_r=0.67, C_f=3000.0, C_r=3000.0, sigma_f=0.02)
ACKERMANN_STEERING = dict(tau=0.035, rate=1.5, deadband=0.002)     # the study's first-order equivalent
VEHICLES.setdefault("ackermann", dict(
    table=ACKERMANN, tau=ACKERMANN_STEERING["tau"], rate=ACKERMANN_STEERING["rate"],
    deadband=ACKERMANN_STEERING["deadband"], speeds=(0.5, 0.65, 0.85), steer_scale=1.0, resolution=0.1 * DEG,
    gyro_noise=0.005, v_ref=0.65, min_speed=0.3))

STUDY = """\
connections = [
  "plan.steer_angle_cmd -> steering.steer_angle_cmd",
  "steering.steer_angle -> car.steer_angle",
  "plan.speed_cmd -> car.speed",
  "car.yaw_rate -> gyro.yaw_rate",
  "car.x_antenna -> gps.x_true",
  "car.y_antenna -> gps.y_true",
  "car.vel_east_antenna -> gps.vel_east_true",
  "car.vel_north_antenna -> gps.vel_north_true",
]

[study]
name = "small_ackermann"
description = "a small Ackermann field robot (wheelbase 1.27 m) at 0.5-0.85 m/s"
stop_time = 120.0
base_step = 0.005
seed = 1270

[vehicle]
class = "robot"
wheelbase = 1.27
{dimensions}steering = "angle"
drive = "ackermann"

[components.plan]
type = "test_drive_plan"
step = 0.05
parameters = {{ duration = 120.0, speeds = [0.5, 0.65, 0.85], steer_scale = 1.0 }}

[components.steering]
type = "steering_hydraulics"
step = 0.005
parameters = {{ kp = 160.0, ki = 16.0, deadband = 0.32, max_flow = 0.00005, volume_per_rad = "0.0000333 m3/rad", valve_time_constant = 0.01, angle_limit = "0.9 rad", potentiometer_resolution = "0.001 rad" }}

[components.car]
type = "tractor_yaw_plant"
step = 0.005
parameters = {{ model = "bicycle", m = {m}, I = {I}, l_f = {l_f}, l_r = {l_r}, C_f = {C_f}, C_r = {C_r}, min_speed = 0.2, cornering_reference_speed = 0.65 }}

[components.gyro]
type = "gyro_sensor"
step = 0.02
parameters = {{ noise_std = 0.005 }}

[components.gps]
type = "gps_sensor"
step = 0.025
parameters = {{ position_noise_std = "2 cm", velocity_noise_std = 0.02 }}
"""


def study(folder: Path, dimensions: bool = True, wheelbase: float | None = None) -> Path:
    """The small machine's baseline study in ``folder``; ``dimensions``: its [vehicle] length and
    width (1.9 m x 1.1 m), else only its class and wheelbase; ``wheelbase``: the study's l_f + l_r
    (and [vehicle] wheelbase) scaled to it (a study of another machine)."""
    p = dict(ACKERMANN)
    L = p["l_f"] + p["l_r"]
    text = STUDY.format(dimensions='length = 1.9\nwidth = 1.1\n' if dimensions else "", **p)
    if wheelbase is not None:
        k = wheelbase / L
        text = (text.replace("wheelbase = 1.27", f"wheelbase = {wheelbase:g}")
                .replace(f"l_f = {p['l_f']}", f"l_f = {p['l_f'] * k:.4g}")
                .replace(f"l_r = {p['l_r']}", f"l_r = {p['l_r'] * k:.4g}"))
    path = Path(folder) / ("small_ackermann.toml" if wheelbase is None else f"small_ackermann_{wheelbase:g}.toml")
    path.write_text(text)
    return path


def wheel_angle(reading: np.ndarray, gain: float = 1.0, asymmetry: float = 0.0, curvature: float = 0.0,
                offset: float = 0.0) -> np.ndarray:
    """M(reading): the wheels' angle for a command or reading (the map planted)."""
    r = np.asarray(reading, float)
    return gain * r * (1.0 + asymmetry * np.sign(r)) * (1.0 + curvature * r * r) + offset


def steering_map(frame, gain: float = 1.0, asymmetry: float = 0.0, curvature: float = 0.0, offset: float = 0.0):
    """The log with delta_cmd and delta re-read through M^-1 (monotone over +-60 deg; interpolated)."""
    grid = np.linspace(-60 * DEG, 60 * DEG, 24001)
    angles = wheel_angle(grid, gain, asymmetry, curvature, offset)
    if np.any(np.diff(angles) <= 0):
        raise ValueError("the steering map must increase with the reading")
    out = frame.copy()
    for col in ("delta_cmd", "delta"):
        if col in out:
            out[col] = np.interp(out[col].to_numpy(float), angles, grid)
    return out


def full_lock_radii(wheelbase: float, lock: float, **planted) -> tuple[float, float]:
    """(left, right) turning radius at +-``lock`` of reading under the map: L / tan(|M(+-lock)|)."""
    return tuple(wheelbase / math.tan(abs(float(wheel_angle(np.array([s * lock]), **planted)[0]))) for s in (1, -1))


def diagnose_planted(case: tuple) -> dict:
    """Write and diagnose (no plots, no identify) the log of (vehicle, truth effect or None, planted
    steering map {gain, asymmetry, curvature, offset}, seed, folder, command_only, duration[, values])
    against the vehicle's baseline study (the tractor's: studies/figure8.toml; the small machine's:
    ``study``)."""
    vehicle, effect, planted, seed, folder, command_only, duration, *rest = case
    frame, truth = make_log(seed, effect, duration=duration, vehicle=vehicle, values=rest[0] if rest else None)
    frame = steering_map(frame, **planted)
    if command_only:
        frame = frame.drop(columns=["delta"])
    name = f"{vehicle}_{effect or 'map'}_{'-'.join(f'{k}{v:g}' for k, v in planted.items())}_{seed}" \
        + ("_cmd" if command_only else "")
    log = Path(folder) / f"{name}.parquet"
    frame.to_parquet(log)
    own = Path(folder) / name
    own.mkdir(exist_ok=True)
    base = study(own) if vehicle == "ackermann" else shipped("figure8.toml")
    result = diagnose(log, None, base, plots=False, identify=False)
    print(f"{name}: {result['verdict']} ({result['verdict_status']})", file=sys.stderr, flush=True)
    return {"case": name, "truth": truth, "planted": planted, "result": result}
