"""The measured log: one column table, one reader (DESIGN.md, 'Measured data').

A log is a table (CSV or Parquet) with a time column ``t`` [s] and named signals in SI units
(``COLUMNS``); more columns are allowed. Every refusal names the file, the column and what was
expected. Identification, diagnosis and the tests read logs through ``read_log`` only.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from orchestrator.errors import InputError

# the canonical columns: name -> (SI unit, meaning)
COLUMNS: dict[str, tuple[str, str]] = {
    "t": ("s", "time"),
    "delta_cmd": ("rad", "front wheel angle commanded to the steering"),
    "delta": ("rad", "front wheel angle measured (potentiometer)"),
    "v": ("m/s", "longitudinal speed"),
    "yaw_rate": ("rad/s", "yaw rate (gyro)"),
    "x": ("m", "GPS antenna east of the datum"),
    "y": ("m", "GPS antenna north of the datum"),
}
CANONICAL = tuple(COLUMNS)

# A column whose largest magnitude passes this bound is almost surely in degrees: no tractor
# steers beyond 70 deg (1.22 rad) or yaws faster than 3 rad/s (172 deg/s).
DEGREE_SUSPECT = {"delta_cmd": (1.22, "rad"), "delta": (1.22, "rad"), "yaw_rate": (3.0, "rad/s")}


class LogError(InputError, ValueError):
    """A log that cannot be used as it is."""


def read_log(path: str | Path, required: tuple[str, ...] = CANONICAL) -> pd.DataFrame:
    """Load and check a log: columns present and numeric, no NaN, time increasing and evenly
    sampled (a gap is named), angles in radians (degrees are detected and named)."""
    path = Path(path)
    if not path.is_file():
        raise LogError(f"{path}: log not found")
    kind = "Parquet" if path.suffix == ".parquet" else "CSV"
    try:
        frame = pd.read_parquet(path) if kind == "Parquet" else pd.read_csv(path)
    except Exception as exc:
        raise LogError(f"{path}: cannot read as {kind}: {exc}") from None
    missing = [c for c in required if c not in frame.columns]
    if missing:
        raise LogError(f"{path}: missing columns {missing}; a log needs "
                       + ", ".join(f"{c} [{COLUMNS[c][0]}]" if c in COLUMNS else c for c in required))
    for c in required:
        if not pd.api.types.is_numeric_dtype(frame[c]):
            raise LogError(f"{path}: column {c!r} is not numeric (first value {frame[c].iloc[0]!r})")
        bad = frame[c].isna().to_numpy()
        if bad.any():
            raise LogError(f"{path}: column {c!r} has {int(bad.sum())} NaN values (first at row {int(np.argmax(bad))}, "
                           f"t = {frame['t'].iloc[int(np.argmax(bad))]})")
    if len(frame) < 3:
        raise LogError(f"{path}: {len(frame)} rows; a log needs many samples")
    t = frame["t"].to_numpy(dtype=float)
    dt = np.diff(t)
    if np.any(dt <= 0):
        i = int(np.argmax(dt <= 0))
        raise LogError(f"{path}: column 't' is not increasing at row {i + 1} (t = {t[i]} then {t[i + 1]})")
    step = float(np.median(dt))
    if dt.max() > 1.5 * step:
        i = int(np.argmax(dt))
        raise LogError(f"{path}: column 't' has a gap of {dt[i]:.4g} s at t = {t[i]:.4g} s (row {i + 1}); "
                       f"expected an even step of {step:.4g} s: cut the log at the gap or fill it")
    if np.max(np.abs(dt - step)) > 0.01 * step:
        i = int(np.argmax(np.abs(dt - step)))
        raise LogError(f"{path}: column 't' is unevenly sampled: step {dt[i]:.4g} s at row {i + 1}, typical {step:.4g} s")
    for c, (bound, unit) in DEGREE_SUSPECT.items():
        if c in required:
            peak = float(np.abs(frame[c]).max())
            if peak > bound:
                raise LogError(f"{path}: column {c!r} reaches {peak:.3g}, more than {bound} {unit}: it looks like "
                               f"degrees{'/s' if unit == 'rad/s' else ''}; the log must hold {unit} "
                               f"(multiply by pi/180 = {math.pi / 180:.6f})")
    return frame


def split(frame: pd.DataFrame, fraction: float) -> tuple[pd.DataFrame, pd.DataFrame]:
    """(first ``fraction`` of the duration, the rest): a fit part and a held-out part."""
    t = frame["t"].to_numpy(dtype=float)
    cut = t[0] + fraction * (t[-1] - t[0])
    return frame[t < cut].reset_index(drop=True), frame[t >= cut].reset_index(drop=True)


def resample(frame: pd.DataFrame, step: float | None = None) -> pd.DataFrame:
    """The log on an even time grid t0, t0 + step, ... (default step: the median interval), every
    numeric column linearly interpolated: for logs whose clock jitters by a fraction of a step."""
    t = frame["t"].to_numpy(dtype=float)
    if len(t) < 2 or np.any(np.diff(t) <= 0):
        raise LogError("resampling needs a time column 't' that increases")
    step = float(np.median(np.diff(t))) if step is None else float(step)
    if step <= 0:
        raise LogError(f"resampling step {step} s must be > 0")
    grid = t[0] + step * np.arange(int(np.floor((t[-1] - t[0]) / step + 1e-9)) + 1)
    columns = {"t": grid}
    for c in frame.columns:
        if c != "t" and pd.api.types.is_numeric_dtype(frame[c]):
            columns[c] = np.interp(grid, t, frame[c].to_numpy(dtype=float))
    return pd.DataFrame(columns)
