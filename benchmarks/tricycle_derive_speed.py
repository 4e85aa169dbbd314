"""The Brain Corp tricycle's logs with a speed (``python3 derive_speed.py [FOLDER]``, numpy only).

The upstream rows (mostafa-bagheri/pose_estimator, ``datasetN.csv``: time [s], a 32-bit traction
encoder on the steered front wheel [ticks], the gyro's yaw rate "filtered" [rad/s], the steering
angle [rad]) carry no speed. The front wheel's speed is the encoder's difference over the stamps'
difference row by row,

    v_front[i] = (enc[i] - enc[i-1]) / (t[i] - t[i-1]) * 2 pi R / ticks_per_rev,

with the difference read modulo 2^32 (the counter's wrap) and the first row given the first
interval's speed; R and ticks_per_rev come from the machine info beside the data (``dataset.txt``:
front_wheel_radius_meters, ticks_per_rev). The rear axle's speed, the point the single-track model
steers about, is v = v_front cos(delta) (the front wheel at distance L ahead turning with it:
r = v_front sin(delta) / L = v tan(delta) / L).

Nothing is smoothed: a burst of rows 1 ms apart gives a speed spike of up to 19 m/s (three rows in
dataset1) that readers of ``derived/`` see as logged (benchmarks/tricycle_yaw_lag.py interpolates
over them). Writes ``derived/datasetN_log.csv`` with the columns t [s], delta [rad], v [m/s],
yaw_rate [rad/s], v_front [m/s] for every ``datasetN.csv`` in FOLDER (default: this file's folder).
"""
from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np

WRAP = 2 ** 32             # the traction encoder's counter is 32-bit (dataset.txt)
HEADER = "t,delta,v,yaw_rate,v_front"


def machine(info: Path) -> dict[str, float]:
    """The ``name = value`` lines of dataset.txt."""
    found = {m.group(1): float(m.group(2)) for m in re.finditer(r"^\s*(\w+)\s*=\s*([-+0-9.eE]+)", info.read_text(), re.M)}
    for key in ("front_wheel_radius_meters", "ticks_per_rev"):
        if key not in found:
            raise SystemExit(f"{info}: no line '{key} = NUMBER' (expected the machine info of pose_estimator)")
    return found


def derived(rows: np.ndarray, metres_per_tick: float) -> np.ndarray:
    """(t, delta, v, yaw_rate, v_front) from the upstream (t, encoder, yaw rate, delta) rows."""
    t, enc, yaw_rate, delta = rows.T
    ticks = (np.diff(enc) + WRAP // 2) % WRAP - WRAP // 2
    v_front = ticks / np.diff(t) * metres_per_tick
    v_front = np.concatenate([v_front[:1], v_front])
    return np.column_stack([t, delta, v_front * np.cos(delta), yaw_rate, v_front])


def main() -> None:
    folder = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parent
    info = machine(folder / "dataset.txt")
    metres_per_tick = 2 * np.pi * info["front_wheel_radius_meters"] / info["ticks_per_rev"]
    runs = sorted(folder.glob("dataset[0-9]*.csv"))
    if not runs:
        raise SystemExit(f"{folder}: no datasetN.csv (expected pose_estimator's rows)")
    (folder / "derived").mkdir(exist_ok=True)
    for path in runs:
        rows = np.loadtxt(path, delimiter=",", comments="#")
        if rows.ndim != 2 or rows.shape[1] != 4 or np.any(np.diff(rows[:, 0]) <= 0):
            raise SystemExit(f"{path}: expected 4 columns (time, encoder, angular velocity, steering angle) "
                             "on strictly increasing times")
        out = folder / "derived" / f"{path.stem}_log.csv"
        np.savetxt(out, derived(rows, metres_per_tick), delimiter=",", header=HEADER, comments="", fmt="%.9g")
        print(f"{out}: {len(rows)} rows")


if __name__ == "__main__":
    main()
