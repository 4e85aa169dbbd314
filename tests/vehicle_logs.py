"""Canonical logs (t, delta_cmd, v, yaw_rate, x, y in SI) of the real F1TENTH sets, built with
pandas in one place so that a general converter can replace it later.

- F1TENTH FrictionMaps (one CSV per ROS topic, each on its own stamps): every topic is joined
  onto the steering command's clock with ``merge_asof`` (nearest stamp within ``tolerance``);
  ``wz`` is in deg/s (-> rad/s); the command ``delta`` is the front-wheel angle asked for
  (-> ``delta_cmd``; there is no measured wheel angle); ``pfOdomData.vx`` is the wheel-odometry
  speed (-> ``v``); the particle filter's map position is ``x, y``. Stamps further apart than
  ``gap`` leave a hole in ``t`` (the tools split the log there).
- AutoKoopman steps (41 runs of 3 s at 40 Hz, pose only): the yaw rate is the derivative of the
  unwrapped orientation (centred differences); ``input.csv`` holds one desired steering angle per
  interval (the last repeats); runs are laid end to end on one clock with a 1 s hole between them.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

DATA = Path(__file__).resolve().parent / "data"
FRICTIONMAPS = DATA / "f1tenth_frictionmaps" / "DataSets"
AUTOKOOPMAN = DATA / "f1tenth_autokoopman_steps" / "F1tenthCar"
ROOT_STUDIES = Path(__file__).resolve().parent.parent / "studies"


def _topic(path: Path, columns: dict[str, str]) -> pd.DataFrame:
    raw = pd.read_csv(path)
    stamp = raw["s"].to_numpy(np.int64) + raw["ns"].to_numpy(np.int64) * 1e-9
    out = pd.DataFrame({"stamp": stamp, **{new: raw[old].to_numpy(float) for old, new in columns.items()}})
    return out.sort_values("stamp").reset_index(drop=True)


def frictionmaps_log(run: str | Path, tolerance: float = 0.05, clock: str = "command") -> pd.DataFrame:
    """One FrictionMaps run (``"DS1"`` or its folder) as a canonical log on the clock of the
    steering command (``clock="command"``) or of the gyro (``"imu"``); the command is the value
    last sent (a held command), the other topics the nearest sample."""
    folder = Path(run) if Path(run).is_dir() else FRICTIONMAPS / str(run)
    cmd = _topic(folder / "commandData.csv", {"delta": "delta_cmd"})
    imu = _topic(folder / "imuData.csv", {"wz": "wz_deg"})
    odom = _topic(folder / "pfOdomData.csv", {"vx": "v", "x": "x", "y": "y"})
    if clock == "imu":
        joined = pd.merge_asof(imu, cmd, on="stamp", direction="backward", tolerance=4 * tolerance)
        joined = pd.merge_asof(joined, odom, on="stamp", direction="nearest", tolerance=tolerance)
    else:
        joined = cmd
        for other in (imu, odom):
            joined = pd.merge_asof(joined, other, on="stamp", direction="nearest", tolerance=tolerance)
    joined = joined.dropna().reset_index(drop=True)
    log = pd.DataFrame({"t": joined["stamp"] - joined["stamp"].iloc[0], "delta_cmd": joined["delta_cmd"],
                        "v": joined["v"], "yaw_rate": np.radians(joined["wz_deg"]),
                        "x": joined["x"], "y": joined["y"]})
    log.attrs["source"] = f"F1TENTH FrictionMaps {folder.name}"
    return log


def autokoopman_log(measurements=None, hole: float = 1.0) -> pd.DataFrame:
    """The AutoKoopman step runs (all, or the numbers given) end to end, ``hole`` s apart."""
    numbers = measurements or sorted(int(p.name.split("_")[1]) for p in AUTOKOOPMAN.glob("measurement_*"))
    parts, start = [], 0.0
    for n in numbers:
        folder = AUTOKOOPMAN / f"measurement_{n}"
        t = pd.read_csv(folder / "time.csv", header=None)[0].to_numpy(float)
        traj = pd.read_csv(folder / "trajectory.csv", header=None).to_numpy(float)
        inputs = pd.read_csv(folder / "input.csv", header=None).to_numpy(float)
        steer = np.append(inputs[:, 0], inputs[-1, 0])[: len(t)]
        heading = np.unwrap(traj[:, 2])
        parts.append(pd.DataFrame({"t": start + t - t[0], "delta_cmd": steer, "v": traj[:, 3],
                                   "yaw_rate": np.gradient(heading, t), "x": traj[:, 0], "y": traj[:, 1],
                                   "run": n}))
        start += t[-1] - t[0] + hole
    log = pd.concat(parts, ignore_index=True)
    log.attrs["source"] = "F1TENTH AutoKoopman steps"
    return log
