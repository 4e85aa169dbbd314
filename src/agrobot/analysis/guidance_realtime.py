"""Metrics of the figure-8 with the tractor as one component (simulated or hardware) and of the
emulated tractor: path (cross-track) error of the CG against the 8-shaped path, the time-based
Euclidean error where the truth is known, and the time spent in the watchdog's safe state."""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.spatial import cKDTree

from agrobot.components.models.figure8_path import Figure8Path
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study

from .figure8 import settled_index
from .signal_roles import MissingSignal, between_samples, component_named, rms, signal
from .mcap_scene import mcap_scene  # noqa: F401 - the run's MCAP scene (orchestrator.mcap_out)

# figure -> (SI unit, bound or note), printed with pass/fail after a run (orchestrator.key_figures).
# The paper bounds the time-based Euclidean error by 0.40 m on straights and 0.60 m on curves; over
# the whole lap, without the split, the larger bound is what the error must stay under.
METRICS = {"euclid_max": ("m", "< 0.60 (the curves' bound)"), "euclid_rms": ("m", None),
           "path_error_max": ("m", None), "path_error_mean": ("m", None),
           "position_valid_share": ("1", None), "safe_state_time_s": ("s", None), "fix_age_max": ("s", None),
           "sim_time_s": ("s", None), "wall_time_s": ("s", None)}
METRIC_UNITS = {**{k: unit for k, (unit, _) in METRICS.items()}, "metrics_from_time_s": "s", "events": "count"}
BOUNDS_SOURCE = "paper"


def path_error(x: np.ndarray, y: np.ndarray, path: Figure8Path, spacing: float = 0.01) -> np.ndarray:
    """Distance from each point to the nearest point of the path (sampled every ``spacing`` m)."""
    s = np.arange(0.0, path.lap_length, spacing)
    pts = np.array([path.pose(si)[:2] for si in s])
    return cKDTree(pts).query(np.column_stack([x, y]))[0]


def _path(study: Study) -> Figure8Path:
    try:
        ref = resolve(study).parameters(component_named(study, "reference"))
    except MissingSignal:
        ref = {}
    return Figure8Path(float(ref.get("radius", 10.0)), float(ref.get("centre_offset", 20.0)))


def metrics(frame: pd.DataFrame, study: Study) -> dict[str, float]:
    name = component_named(study, "tractor")      # the composite subsystem or the hardware
    t = frame["t"].to_numpy()
    try:      # settled: after the reference's start ramp; without a reference (the emulator), the tractor's
        start = settled_index(t, signal(frame, study, "reference", "speed_ref"))
    except MissingSignal:
        start = settled_index(t, frame[f"{name}.speed_measured"].to_numpy(), fraction=0.9)
    x, y = frame[f"{name}.x_cg"].to_numpy(), frame[f"{name}.y_cg"].to_numpy()
    out: dict[str, float] = {}
    # over the samples with a position (a hardware tractor has none before its first fix, or while
    # the fix is lost); the share is reported so that a partial figure is not taken for a whole one
    valid = np.isfinite(x) & np.isfinite(y)
    valid[:start] = False
    out["position_valid_share"] = float(valid[start:].mean()) if len(valid) > start else 0.0
    if valid.any():
        err = path_error(x[valid], y[valid], _path(study))
        out.update(path_error_max=float(err.max()), path_error_mean=float(err.mean()))
        try:
            x_ref, y_ref = between_samples(frame, study, "reference", ("x_ref", "y_ref"))
            e = np.hypot(x - x_ref, y - y_ref)[valid]
            out.update(euclid_max=float(e.max()), euclid_rms=rms(e))
        except MissingSignal:
            pass
    try:
        safe = signal(frame, study, "watchdog", "safe_state")
        out["safe_state_time_s"] = float(np.sum(safe > 0.5) * np.median(np.diff(t)))
    except MissingSignal:
        pass
    out["fix_age_max"] = float(frame[f"{name}.fix_age"].max())
    out["metrics_from_time_s"] = float(t[start])
    return out
