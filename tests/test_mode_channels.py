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


def test_a_bags_text_mode_topic_selects_its_stretches(tmp_path):
    """A ROS bag whose /mode topic (std_msgs/String, 1 Hz, sent only now and then) says 'auto',
    then 'manual' from 20 to 35 s: --where 'mode == auto' keeps the rows outside that stretch."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    from agrobot.measurements.rosbag import typestore
    from tests.import_recordings import truth
    from tests.test_other_data import _imu, _navsat

    drive = truth(60.0, h=0.01)
    store = typestore()
    string = store.types["std_msgs/msg/String"]
    with Writer(tmp_path / "bag", version=8, storage_plugin=StoragePlugin.SQLITE3) as w:
        fix = w.add_connection("/fix", "sensor_msgs/msg/NavSatFix", typestore=store)
        imu = w.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=store)
        mode = w.add_connection("/mode", "std_msgs/msg/String", typestore=store)
        for k, row in enumerate(drive.iloc[::10].itertuples()):
            utc = 1.7e9 + row.t
            w.write(fix, int(utc * 1e9), store.serialize_cdr(
                _navsat(store, "sensor_msgs/msg/NavSatFix", utc, row.lat, row.lon, 10.0, 4), "sensor_msgs/msg/NavSatFix"))
            w.write(imu, int((utc + 0.01) * 1e9), store.serialize_cdr(_imu(store, utc, row.r), "sensor_msgs/msg/Imu"))
            if k % 10 == 0:
                said = "manual" if 20.0 <= row.t < 35.0 else "auto"
                w.write(mode, int((utc + 0.02) * 1e9), store.serialize_cdr(string(data=said), "std_msgs/msg/String"))
    opts = ImportOptions(signals=[parse_signal("mode=/mode.data")], where="mode == auto", min_stretch=5.0)
    frame, report = load_log(tmp_path / "bag", recording=opts)
    t = frame["t"].to_numpy() + report["used"]["utc_start_s"] - (1.7e9 + float(drive["t"].iloc[0]))
    assert len(t) > 100 and not ((t > 20.2) & (t < 34.8)).any()
    assert t.min() < 19.0 and t.max() > 36.0
    assert "selects" in report["selection"][0]
