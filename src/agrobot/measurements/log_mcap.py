"""A measured log as an MCAP file (``convert --mcap``): every column on the topic ``/signals/log`` (JSON,
one message per row, units from the log's conventions, measurements.log.COLUMNS) and the antenna's
position on ``/log/position`` (foxglove.Point3InFrame, frame ``world``: east/north of the log's datum), on
the log's own time axis (log times: seconds from its first row, in ns).

Imported where used: foxglove (the mcap extra).
"""
from __future__ import annotations

import math
from pathlib import Path

import pandas as pd

from agrobot.orchestrator.mcap_out import write_run_mcap

from .log import COLUMNS


class _Position:
    every = 1

    def channels(self, context) -> None:
        from foxglove.channels import Point3InFrameChannel

        self.channel = Point3InFrameChannel("/log/position", context=context)

    def static(self, t_ns: int) -> None:
        pass

    def step(self, t_ns: int, value) -> None:
        from foxglove.messages import Point3, Point3InFrame, Timestamp

        x, y = value("log.x"), value("log.y")
        if math.isfinite(x) and math.isfinite(y):
            self.channel.log(Point3InFrame(timestamp=Timestamp(sec=t_ns // 1_000_000_000, nsec=t_ns % 1_000_000_000),
                                           frame_id="world", point=Point3(x=x, y=y, z=0.0)), log_time=t_ns)


def write_log_mcap(frame: pd.DataFrame, path: Path, source: str) -> Path:
    """The log ``frame`` (a ``t`` column and SI signals) as the MCAP file ``path``."""
    columns = [c for c in frame.columns if c != "t"]
    renamed = frame.rename(columns={c: f"log.{c}" for c in columns})
    units = {f"log.{c}": COLUMNS[c][0] for c in columns if c in COLUMNS}
    descriptions = {f"log.{c}": COLUMNS[c][1] for c in columns if c in COLUMNS}
    scene = _Position() if {"x", "y"} <= set(columns) else None
    return write_run_mcap(path, renamed, ratios={"log": 1}, units=units, descriptions=descriptions, scene=scene,
                          metadata={"source": source, "time": "log times are seconds from the log's first row, in ns"})
