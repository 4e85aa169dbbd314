"""A declared mode channel selects the judged stretches (``--where``), however it is written: text
('auto', 'manual', 'paused'), numbers, or numbers written only when the mode changes (blank cells
between: a channel at a lower rate). Generated recordings (harness.quirk_recordings) with the
hand-driven and paused stretches known; the stretches --where selects must be the truth's others."""
from __future__ import annotations

import csv

import numpy as np
import pytest

from agrobot.measurements.options import ImportOptions
from agrobot.measurements.recording import load_log
from agrobot.measurements.signal_expressions import parse_signal
from harness.quirk_recordings import START, compose

CODES = {"auto": "1", "manual": "2", "paused": "0"}


def rewrite_mode(path, how: str) -> None:
    """The mode column as numbers (``numbers``) or as numbers said only when they change (``changes``)."""
    rows = list(csv.reader(path.open()))
    k = rows[0].index("mode")
    last = None
    for row in rows[1:]:
        code = CODES[row[k]]
        row[k] = "" if how == "changes" and code == last else code
        last = code
    with path.open("w", newline="") as f:
        csv.writer(f).writerows(rows)


@pytest.mark.parametrize("layout, how, where, mapping", [
    ("table", "text", "mode == auto", []),
    ("devices", "text", "mode == 'auto'", ["mode=vehicle.mode"]),
    ("devices", "numbers", "mode == 1", []),
    ("table", "changes", "mode == 1", ["mode=log.mode"]),
])
def test_where_selects_the_truths_stretches(tmp_path, layout, how, where, mapping):
    truth = compose(11, tmp_path / "rec", classes=["mode_stretches"], layout=layout, machine="mower")
    if how != "text":
        rewrite_mode(tmp_path / "rec" / ("log.csv" if layout == "table" else "vehicle.csv"), how)
    opts = ImportOptions(signals=[parse_signal(s) for s in mapping], where=where, min_stretch=5.0)
    frame, report = load_log(tmp_path / "rec", recording=opts)
    assert report["selection"] and "selects" in report["selection"][0]
    t = frame["t"].to_numpy() + report["used"]["utc_start_s"] - START       # on the truth's clock
    other = truth["planted"]["mode_stretches"]["manual"] + truth["planted"]["mode_stretches"]["paused"]
    inside = np.zeros(len(t), bool)
    for a, b in other:
        inside |= (t >= a + 0.15) & (t < b - 0.15)
    assert len(t) > 100 and not inside.any()
    first_manual = other[0]
    assert t.min() < first_manual[0] and t.max() > first_manual[1]      # stretches on both sides kept
