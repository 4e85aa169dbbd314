"""The small Ackermann machine's baseline study (harness.truth_tractor.VEHICLES["small_ackermann"]:
its table, steering, outline and speeds), its full-lock radii under a steering map, and a truth log
with a planted steering map (harness.steering_maps) diagnosed against its vehicle's baseline study.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from agrobot.diagnosis.pipeline import diagnose
from agrobot.studies import shipped
from harness.steering_maps import read_through, wheel_angle
from harness.truth_tractor import SMALL_ACKERMANN, SMALL_WHEELBASE, make_log

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
description = "a small Ackermann field robot (wheelbase {L:g} m) at {lo:g}-{hi:g} m/s"
stop_time = 120.0
base_step = 0.005
seed = 1270

[vehicle]
class = "robot"
wheelbase = {L:g}
{dimensions}steering = "angle"
drive = "ackermann"

[components.plan]
type = "test_drive_plan"
step = 0.05
parameters = {{ duration = 120.0, speeds = {speeds}, steer_scale = 1.0 }}

[components.steering]
type = "steering_hydraulics"
step = 0.005
parameters = {{ kp = 160.0, ki = 16.0, deadband = 0.32, max_flow = 0.00005, volume_per_rad = "0.0000333 m3/rad", valve_time_constant = 0.01, angle_limit = "0.9 rad", potentiometer_resolution = "0.001 rad" }}

[components.car]
type = "tractor_yaw_plant"
step = 0.005
parameters = {{ model = "bicycle", m = {m}, I = {I}, l_f = {l_f}, l_r = {l_r}, C_f = {C_f}, C_r = {C_r}, min_speed = 0.2, cornering_reference_speed = {v_ref:g} }}

[components.gyro]
type = "gyro_sensor"
step = 0.02
parameters = {{ noise_std = 0.005 }}

[components.gps]
type = "gps_sensor"
step = 0.025
parameters = {{ position_noise_std = "2 cm", velocity_noise_std = 0.02 }}
"""


def study(folder: Path, dimensions: bool = True, wheelbase: float | None = None,
          speeds: tuple[float, ...] | None = None) -> Path:
    """The small machine's baseline study in ``folder``; ``dimensions``: its [vehicle] length and
    width (the vehicle's outline), else only its class and wheelbase; ``wheelbase``: the study's
    l_f + l_r (and [vehicle] wheelbase) scaled to it (a study of another machine); ``speeds``: the
    test drive's speeds [m/s] (the vehicle's by default)."""
    veh = SMALL_ACKERMANN
    L = wheelbase if wheelbase is not None else SMALL_WHEELBASE
    k = L / SMALL_WHEELBASE
    p = dict(veh["table"], l_f=f"{veh['table']['l_f'] * k:.4g}", l_r=f"{veh['table']['l_r'] * k:.4g}")
    speeds = tuple(speeds or veh["speeds"])
    text = STUDY.format(dimensions=f'length = {veh["length"]}\nwidth = {veh["width"]}\n' if dimensions else "",
                        L=L, lo=min(speeds), hi=max(speeds), speeds=list(speeds), v_ref=veh["v_ref"], **p)
    path = Path(folder) / ("small_ackermann.toml" if wheelbase is None else f"small_ackermann_{wheelbase:g}.toml")
    path.write_text(text)
    return path


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
    frame = read_through(frame, **planted)
    if command_only:
        frame = frame.drop(columns=["delta"])
    name = f"{vehicle}_{effect or 'map'}_{'-'.join(f'{k}{v:g}' for k, v in planted.items())}_{seed}" \
        + ("_cmd" if command_only else "")
    log = Path(folder) / f"{name}.parquet"
    frame.to_parquet(log)
    own = Path(folder) / name
    own.mkdir(exist_ok=True)
    base = study(own) if vehicle == "small_ackermann" else shipped("figure8.toml")
    result = diagnose(log, None, base, plots=False, identify=False)
    print(f"{name}: {result['verdict']} ({result['verdict_status']})", file=sys.stderr, flush=True)
    return {"case": name, "truth": truth, "planted": planted, "result": result}
