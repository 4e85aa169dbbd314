"""The small Ackermann machine's recording (harness.truth_tractor.VEHICLES["small_ackermann"]) as
its logger writes it, for the audit's tests: every channel in one 20 Hz row, the slower ones held
(a dual-antenna heading that updates at 5 Hz and RTK positions at 10 Hz repeat their last value
until the next update), with a known truth.

The truth: a kinematic bicycle (wheelbase ``L``, the machine's l_f + l_r) with a smooth random steering, driving forward at
about 1.4 m/s and, within ``reverse`` (start, end) s, backing up at 0.8 m/s (stopping before and
after); yaw rate r = v tan(delta) / L with v signed, the track its integral. The rows (``log.csv``,
POSIX seconds, the row clock jittered by up to 4 ms): ``lat``, ``lon`` [deg] held from the 10 Hz
fixes, ``heading`` [deg, clockwise from north] held from the 5 Hz heading, ``speed`` [m/s] the
wheel encoder's ``speed_scale`` x the speed, unsigned unless ``signed``, ``speed_late`` s late
(a filter), ``steer`` [rad] the wheel angle measured on every row, and, with ``gear``, ``gear`` (+1
forward, -1 reverse); with ``gyro``, ``gyro`` [rad/s] that factor x the yaw rate; with ``lateral``,
``ay`` [m/s2] that factor x v r. ``split``: the speed and steering in ``drive.csv`` on a clock ``late`` s
late, the positions and heading in ``gnss.csv``.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from harness.truth_tractor import SMALL_WHEELBASE as L

H = 0.002
FORWARD, BACKWARD = 1.4, 0.8
START = 1.7e9


def speed_profile(t: np.ndarray, reverse: tuple[float, float] | None, steady: bool = False) -> np.ndarray:
    """Signed speed [m/s]: forward FORWARD (+- 20 % unless ``steady``), -BACKWARD within ``reverse``
    with a 1.5 s stop-and-go either side."""
    v = FORWARD * (1.0 + (0.0 if steady else 0.2 * np.sin(2 * math.pi * t / 23.0) + 0.1 * np.sin(2 * math.pi * t / 7.0)))
    if reverse is None:
        return v
    a, b = reverse
    knots = [a - 2.0, a - 0.5, a, a + 1.0, b - 1.0, b, b + 0.5, b + 2.0]
    shape = [1.0, 0.0, 0.0, -1.0, -1.0, 0.0, 0.0, 1.0]
    s = np.interp(t, knots, shape)
    return np.where(s >= 0, s * v, s * BACKWARD)


def truth(seconds: float = 90.0, seed: int = 3, reverse: tuple[float, float] | None = None,
          steady: bool = False) -> pd.DataFrame:
    """The drive on a fine grid: t, v (signed), delta, r, psi (ENU yaw), east, north, lat, lon."""
    from scipy.interpolate import CubicSpline

    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, H)
    knots = np.arange(0.0, seconds + 3.0, 2.5)
    delta = np.clip(CubicSpline(knots, rng.uniform(-0.35, 0.35, len(knots)))(t), -0.4, 0.4)
    v = speed_profile(t, reverse, steady)
    r = v * np.tan(delta) / L
    psi = np.cumsum(r) * H
    east, north = np.cumsum(v * np.cos(psi)) * H, np.cumsum(v * np.sin(psi)) * H
    lat = 52.0 + np.degrees(north / 6_371_000.0)
    lon = 5.0 + np.degrees(east / (6_371_000.0 * math.cos(math.radians(52.0))))
    return pd.DataFrame({"t": t, "v": v, "delta": delta, "r": r, "psi": psi, "east": east, "north": north,
                         "lat": lat, "lon": lon})


def held(rows: np.ndarray, rate: float, phase: float, t: np.ndarray, x: np.ndarray, noise: float = 0.0,
         rng=None) -> np.ndarray:
    """x sampled at ``rate`` Hz (from ``phase`` s) with white ``noise``, and held: each row carries
    the last update."""
    updates = np.arange(phase, t[-1], 1.0 / rate)
    values = np.interp(updates, t, x) + (noise * rng.standard_normal(len(updates)) if noise else 0.0)
    i = np.clip(np.searchsorted(updates, rows, side="right") - 1, 0, len(updates) - 1)
    return values[i]


def write_machine_log(folder: Path, seconds: float = 90.0, seed: int = 3, reverse: tuple[float, float] | None = None,
                      signed: bool = False, gear: bool = False, speed_scale: float = 0.9, speed_late: float = 0.0,
                      steady: bool = False, split: bool = False, late: float = 0.0, gyro: float | None = None,
                      lateral: float | None = None) -> Path:
    """The recording's folder (module docstring); its truth is ``truth(seconds, seed, reverse)``."""
    folder.mkdir(parents=True, exist_ok=True)
    drive = truth(seconds, seed, reverse, steady)
    rng = np.random.default_rng(seed + 100)
    t, rows = drive["t"].to_numpy(), np.arange(0.5, seconds - 0.5, 0.05)
    rows = rows + rng.uniform(-0.004, 0.004, len(rows))
    noise = rng.standard_normal((5, len(rows)))
    metre = math.degrees(1.0 / 6_371_000.0)            # deg of latitude per metre
    lat = held(rows, 10.0, 0.001, t, drive["lat"].to_numpy(), 0.01 * metre, np.random.default_rng(seed + 1))
    lon = held(rows, 10.0, 0.001, t, drive["lon"].to_numpy(), 0.016 * metre, np.random.default_rng(seed + 2))
    compass = 90.0 - np.degrees(drive["psi"].to_numpy())        # clockwise from north
    heading = held(rows, 5.0, 0.051, t, compass, 0.2, np.random.default_rng(seed + 3)) % 360.0
    v = speed_scale * drive["v"].to_numpy()
    speed = np.interp(rows - speed_late, t, v if signed else np.abs(v)) + 0.02 * noise[0]
    steer = np.interp(rows, t, drive["delta"].to_numpy()) + 0.003 * noise[1]
    gnss = pd.DataFrame({"time": rows + START, "lat": lat, "lon": lon, "heading": heading})
    machine = pd.DataFrame({"time": rows + START + (late if split else 0.0), "speed": speed, "steer": steer})
    r_rows = np.interp(rows, t, drive["r"].to_numpy())
    if gyro is not None:
        machine["gyro"] = gyro * r_rows + 0.005 * noise[2]
    if lateral is not None:
        machine["ay"] = lateral * np.interp(rows, t, drive["v"].to_numpy()) * r_rows + 0.05 * noise[3]
    if gear:
        machine["gear"] = np.where(np.interp(rows, t, drive["v"].to_numpy()) < -0.05, -1, 1)
    for frame in (gnss, machine):
        frame["time"] = frame["time"].map(lambda x: f"{x:.3f}")
    if split:
        gnss.to_csv(folder / "gnss.csv", index=False, float_format="%.10g")
        machine.to_csv(folder / "drive.csv", index=False, float_format="%.6g")
    else:
        pd.concat([gnss, machine.drop(columns="time")], axis=1).to_csv(folder / "log.csv", index=False,
                                                                       float_format="%.10g")
    return folder


def signals(split: bool = False, gear: bool = False, gyro: bool = False, lateral: bool = False) -> list[str]:
    """The --signal mapping a user gives for this recording."""
    g, m = ("gnss", "drive") if split else ("log", "log")
    out = [f"lat={g}.lat", f"lon={g}.lon", f"heading={g}.heading[deg]", f"v={m}.speed[m/s]", f"delta={m}.steer[rad]"]
    return (out + ([f"direction={m}.gear"] if gear else []) + ([f"yaw_rate={m}.gyro[rad/s]"] if gyro else [])
            + ([f"ay={m}.ay[m/s^2]"] if lateral else []))
