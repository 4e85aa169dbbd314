"""Is the study this log's vehicle? The log's own kinematics give its wheelbase, L = v delta / r
in gentle steady turning (|a_y| small, the kinematic yaw rate), and its speed and steering
ranges; they are compared with the study's wheelbase, and with the shipped studies, so that a log
diagnosed against the default study (a tractor) says when it comes from another vehicle.
"""
from __future__ import annotations

import math

import numpy as np

from agrobot.identification.ordinary_driving import study_plant
from agrobot.orchestrator.study import load_study
from agrobot.studies import shipped

CANDIDATES = ("figure8.toml", "passenger_car.toml", "f1tenth.toml")
MISMATCH = math.log(1.3)     # the log's turns and the study's wheelbase more than 30 % apart: named before any verdict
SIZE = math.log(1.3)         # a shipped study is suggested only for a vehicle of its size: within 30 % of the log's


def log_vehicle(frame) -> dict | None:
    """{wheelbase, speed_range, steering_range} of the log's vehicle, None when the log has no
    gentle turns to read a wheelbase from (needs v, yaw_rate and delta or delta_cmd)."""
    steer = "delta" if "delta" in frame else "delta_cmd" if "delta_cmd" in frame else None
    if steer is None or "v" not in frame or "yaw_rate" not in frame:
        return None
    v, d, r = (frame[c].to_numpy(float) for c in ("v", steer, "yaw_rate"))
    ok = np.isfinite(v) & np.isfinite(d) & np.isfinite(r)
    v, d, r = v[ok], d[ok], r[ok]
    moving = v > max(0.2, 0.1 * float(np.percentile(v, 90))) if len(v) else np.zeros(0, bool)
    if moving.sum() < 50:
        return None
    a_y = np.abs(v * r)
    gentle = moving & (np.abs(d) > 0.02) & (np.abs(r) > 0.02) & (a_y < max(1.0, np.percentile(a_y[moving], 50)))
    gentle &= np.sign(d) == np.sign(r)
    if gentle.sum() < 30:
        return None
    L = float(np.median(v[gentle] * np.tan(np.abs(d[gentle])) / np.abs(r[gentle])))
    return {"wheelbase": L, "from": steer, "samples": int(gentle.sum()),
            "lateral_acceleration_p99": float(np.percentile(a_y[moving], 99)),
            "speed_range": [float(np.percentile(v[moving], 10)), float(np.percentile(v[moving], 90))],
            "steering_range": float(np.percentile(np.abs(d[moving]), 99))}


def study_check(frame, wheelbase: float, study_name: str) -> tuple[dict | None, str | None]:
    """(the log's vehicle, a warning naming the shipped study that fits better) when its
    wheelbase is off the study's by more than MISMATCH in log ratio; (vehicle, None) otherwise."""
    mine = log_vehicle(frame)
    if mine is None or not mine["wheelbase"] > 0:
        return mine, None
    off = abs(math.log(mine["wheelbase"] / wheelbase))
    if off <= MISMATCH:
        return mine, None
    fits = []
    for name in CANDIDATES:
        _, p = study_plant(load_study(shipped(name)))
        fits.append((abs(math.log(mine["wheelbase"] / (p.l_f + p.l_r))), name, p.l_f + p.l_r))
    best = min(fits)
    ratio = wheelbase / mine["wheelbase"]
    text = (f"the log's turns are not the study's vehicle: wheelbase {mine['wheelbase']:.3g} m from "
            f"v tan({mine['from']}) / yaw_rate in gentle turns (an effective one, which understeer and a steering "
            f"map's gain lengthen; speeds {mine['speed_range'][0]:.3g}-{mine['speed_range'][1]:.3g} m/s, "
            f"|{mine['from']}| up to {math.degrees(mine['steering_range']):.3g} deg) against the study's {study_name} "
            f"{wheelbase:.3g} m ({100 * (ratio - 1):+.0f} %): either the study is another vehicle, or its steering "
            f"map is off (the wheels turn {ratio:.2g} x the angle the log says; the steering_gain the verdict "
            f"judges tells)")
    if best[0] <= SIZE and best[1] != study_name:
        text += f"; studies/{best[1]} (wheelbase {best[2]:.3g} m) is of the log's size: try --study studies/{best[1]}"
    else:
        text += (f"; no shipped study is of the log's size (nearest studies/{best[1]}, {best[2]:.3g} m): if the "
                 f"study's wheelbase is the vehicle's, the steering map is the cause, else write a study with its "
                 f"[vehicle] table")
    mine["mismatch"] = text
    return mine, text
