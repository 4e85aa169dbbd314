"""Canonical logs (t, delta_cmd, v, yaw_rate, x, y in SI) of the published F1TENTH sets, read by the
recording importer (``python -m agrobot convert``) with the signals named as a user names them.

- F1TENTH FrictionMaps (one CSV per ROS topic, each on its own stamps): the tables are joined on
  time; ``wz`` is in deg/s; the command ``delta`` is the front-wheel angle asked for (there is no
  measured wheel angle); ``pfOdomData.vx`` is the wheel-odometry speed, the particle filter's map
  position is ``x, y``. Every run the importer finds (it splits the recording at clock gaps) is
  kept, on the recording's clock: the tools cut the log at its gaps.
- AutoKoopman steps (41 runs of 3 s at 40 Hz, pose only): each run read by the importer with
  ``time.csv`` as its clock; the yaw rate is the derivative of the unwrapped heading (centred
  differences); runs are laid end to end on one clock with a hole of ``hole`` s between them.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from .recording import ImportOptions, import_recording, import_runs
from .signal_expressions import parse_signal

FRICTIONMAPS_SIGNALS = ("delta_cmd=commandData.delta[rad]", "yaw_rate=imuData.wz[deg/s]", "v=pfOdomData.vx[m/s]",
                        "x=pfOdomData.x[m]", "y=pfOdomData.y[m]")
AUTOKOOPMAN_SIGNALS = ("x=trajectory.col1[m]", "y=trajectory.col2[m]", "heading=trajectory.col3[rad]",
                       "v=trajectory.col4[m/s]", "delta_cmd=input.col1[rad]")


def _import(folder: Path, signals, **options) -> pd.DataFrame:
    """Every run the importer finds in the recording, each at its start on the recording's clock."""
    opts = ImportOptions(signals=[parse_signal(s) for s in signals], **options)
    runs = import_runs(folder, opts) or [import_recording(folder, opts)]
    starts = [rep["used"].get("start", 0.0) for _, rep in runs]
    logs = [log.assign(t=log["t"] + s - min(starts)) for (log, _), s in zip(runs, starts)]
    for log in (logs if len(logs) > 1 else []):         # several runs: their own samples (measurements.runs) each on its clock
        log.attrs.pop("own_samples", None)
    return pd.concat(logs, ignore_index=True)


def frictionmaps_log(folder: str | Path, rate: float | None = None) -> pd.DataFrame:
    """One FrictionMaps data set (its folder, ``.../DataSets/DS1``) as a canonical log at ``rate`` Hz
    (default: the fastest stream's rate): the runs ``convert DS --signal ...`` finds, end to end."""
    folder = Path(folder)
    log = _import(folder, FRICTIONMAPS_SIGNALS, rate=rate)
    log.attrs["source"] = f"F1TENTH FrictionMaps {folder.name}"
    return log


def autokoopman_log(folder: str | Path, measurements=None, hole: float = 1.0) -> pd.DataFrame:
    """The AutoKoopman step runs of ``folder`` (``.../F1tenthCar``: all, or the numbers given) end to
    end, ``hole`` s apart."""
    folder = Path(folder)
    numbers = measurements or sorted(int(p.name.split("_")[1]) for p in folder.glob("measurement_*"))
    parts, start = [], 0.0
    for n in numbers:
        run = _import(folder / f"measurement_{n}", AUTOKOOPMAN_SIGNALS, time="time.col1[s]")
        t = run["t"].to_numpy(float)
        parts.append(pd.DataFrame({"t": start + t - t[0], "delta_cmd": run["delta_cmd"], "v": run["v"],
                                   "yaw_rate": np.gradient(np.unwrap(run["heading"].to_numpy(float)), t),
                                   "x": run["x"], "y": run["y"], "run": n}))
        start += t[-1] - t[0] + hole
    log = pd.concat(parts, ignore_index=True)
    log.attrs["source"] = "F1TENTH AutoKoopman steps"
    return log
