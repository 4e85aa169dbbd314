"""A diagnosis as an MCAP file (``diagnose --mcap``): on one time axis, the log's time, each judged stage's
measured signal, the baseline study's replay and the final model's, and both residuals (measured minus
simulated), on ``/diagnosis/<stage>`` (JSON, SI units: rad, rad/s, m, m/s; the position stage east and
north apart); and the measured log's columns on ``/diagnosis/log``. PlotJuggler and Foxglove plot them by
name (orchestrator.mcap_out)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from agrobot.orchestrator.mcap_out import write_run_mcap

from .catalogue import SIGNALS

TOPIC_PREFIX = "/diagnosis/"


def diagnosis_table(replay, base: dict, final: dict) -> tuple[pd.DataFrame, dict[str, str]]:
    """(the table of every stage's measured, baseline, final and residuals on the replay's samples, units)."""
    columns, units = {"t": np.asarray(replay.t, float)}, {}
    for stage in replay.stages:
        unit = SIGNALS[stage][1]
        measured = np.asarray(replay.measured(stage), float)
        series = {"measured": measured, "baseline": np.asarray(replay.predicted(stage, base), float),
                  "final": np.asarray(replay.predicted(stage, final), float)}
        series["residual_baseline"] = measured - series["baseline"]
        series["residual_final"] = measured - series["final"]
        for name, values in series.items():
            if values.ndim == 2:                  # the position stage: east and north
                for k, axis in enumerate(("east", "north")):
                    columns[f"{stage}.{name}_{axis}"] = values[:, k]
                    units[f"{stage}.{name}_{axis}"] = unit
            else:
                columns[f"{stage}.{name}"] = values
                units[f"{stage}.{name}"] = unit
    frame = getattr(replay, "frame", None)
    if frame is not None and len(frame) == len(columns["t"]):
        for col in frame.columns:
            if col != "t" and pd.api.types.is_numeric_dtype(frame[col]):
                columns[f"log.{col}"] = frame[col].to_numpy(float)
    return pd.DataFrame(columns), units


def write_diagnosis_mcap(replay, base: dict, final: dict, path: Path, source: str) -> Path:
    table, units = diagnosis_table(replay, base, final)
    return write_run_mcap(path, table, ratios={}, units=units, descriptions={}, prefix=TOPIC_PREFIX,
                          metadata={"log": source, "time": "log times are seconds from the log's first sample, in ns",
                                    "baseline": "the study's model", "final": "the diagnosis's final model"})
