"""A table written as parquet holds its columns and units and none of the frame's other attrs
(orchestrator.atomic_files.write_frame): pyarrow would keep them in its pandas metadata, and an
import's own samples, as long as the log, would grow it several times over."""
from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pyarrow.parquet as pq

from agrobot.orchestrator.atomic_files import read_table, write_frame


def _frame(own_samples: bool) -> pd.DataFrame:
    t = np.arange(0.0, 60.0, 0.01)
    frame = pd.DataFrame({"t": t, "v": 1.0 + 0.1 * np.sin(t)})
    frame.attrs["units"] = {"t": "s", "v": "m/s"}
    if own_samples:                        # 20 times the column's samples, as an import keeps them
        stamps = np.arange(0.0, 60.0, 0.0005)
        frame.attrs["own_samples"] = {"v": (stamps.tolist(), np.cos(stamps).tolist())}
    return frame


def test_a_frames_attrs_other_than_units_are_not_written(tmp_path):
    bare, heavy = tmp_path / "bare.parquet", tmp_path / "heavy.parquet"
    write_frame(bare, _frame(False))
    write_frame(heavy, _frame(True))
    assert heavy.stat().st_size <= bare.stat().st_size + 64, (heavy.stat().st_size, bare.stat().st_size)
    assert "attributes" not in json.loads(pq.read_schema(heavy).metadata[b"pandas"])
    back = read_table(heavy)
    assert back.attrs == {"units": {"t": "s", "v": "m/s"}}
    assert np.array_equal(back["v"].to_numpy(), _frame(False)["v"].to_numpy())
