"""Rows at a 2 Hz GNSS epoch rate beside a 50 Hz gyro (a field robot's bag): the default grid is
named with what it leaves out and the --rate that keeps it; with that --rate, nothing to say."""
from __future__ import annotations

import numpy as np

from agrobot.measurements.recording import ImportOptions, import_recording


def _bag(folder, seconds: float = 40.0):
    from rosbags.rosbag2 import StoragePlugin, Writer

    from agrobot.measurements.rosbag import typestore
    from tests.test_other_data import _imu, _navsat

    store = typestore()
    with Writer(folder, version=8, storage_plugin=StoragePlugin.SQLITE3) as w:
        fix = w.add_connection("/fix", "sensor_msgs/msg/NavSatFix", typestore=store)
        imu = w.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=store)
        for tk in np.arange(0.0, seconds, 0.02):                  # 50 Hz gyro, 2 Hz fixes driving east at 1 m/s
            utc = 1.7e9 + tk
            w.write(imu, int(utc * 1e9), store.serialize_cdr(_imu(store, utc, 0.2 * np.sin(tk)), "sensor_msgs/msg/Imu"))
            if round(tk / 0.02) % 25 == 0:
                lon = 10.0 + np.degrees(tk / (6371000.0 * np.cos(np.radians(50.0))))
                w.write(fix, int(utc * 1e9), store.serialize_cdr(
                    _navsat(store, "sensor_msgs/msg/NavSatFix", utc, 50.0, lon, 100.0, 4), "sensor_msgs/msg/NavSatFix"))


def test_the_default_grid_says_what_it_leaves_out(tmp_path):
    _bag(tmp_path / "bag")
    frame, report = import_recording(tmp_path / "bag", ImportOptions())
    notes = [n for n in report["notes"] if "rows at the GNSS epoch rate" in n]
    assert abs(report["rate_hz"] - 2.0) < 0.01
    assert notes and "yaw_rate (50 Hz)" in notes[0] and "--rate 50 " in notes[0] + " "
    frame, report = import_recording(tmp_path / "bag", ImportOptions(rate=50.0))
    assert abs(report["rate_hz"] - 50.0) < 0.01
    assert not [n for n in report["notes"] if "rows at the GNSS epoch rate" in n]
