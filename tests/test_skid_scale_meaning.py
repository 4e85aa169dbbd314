"""A skid-steer's wheel odometry turning 3.6 times its gyro is the skid (K = 0.28 against the track
the odometry divides by), never 'a km/h vs m/s mix-up': that reading needs two speeds."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.measurements.recording import ImportOptions, import_recording
from tests.test_bag_one_clock import _imu, _odom

SKID = 3.6         # the odometry's turn rate over the gyro's (truth: K = 1 / 3.6)


def _bag(folder) -> None:
    from rosbags.rosbag2 import StoragePlugin, Writer

    from agrobot.measurements.rosbag import typestore

    store = typestore()
    rng = np.random.default_rng(4)
    t = np.arange(0.0, 120.0, 0.02)
    r = np.interp(t, np.arange(0.0, 121.0, 2.0), rng.uniform(-0.4, 0.4, 61))
    with Writer(folder, version=8, storage_plugin=StoragePlugin.SQLITE3) as w:
        imu = w.add_connection("/imu/data", "sensor_msgs/msg/Imu", typestore=store)
        odom = w.add_connection("/wheels/odom", "nav_msgs/msg/Odometry", typestore=store)
        for k, tk in enumerate(t):
            utc = 1.7e9 + tk
            w.write(imu, int((utc + 0.005) * 1e9), store.serialize_cdr(
                _imu(store, utc, r[k] + 0.01 * rng.standard_normal()), "sensor_msgs/msg/Imu"))
            if k % 5 == 0:
                w.write(odom, int((utc + 0.005) * 1e9), store.serialize_cdr(
                    _odom(store, utc, 0.8, SKID * r[k]), "nav_msgs/msg/Odometry"))


def test_a_skid_steers_odometry_scale_is_named_the_skid_not_km_h(tmp_path):
    pytest.importorskip("rosbags")
    _bag(tmp_path / "bag")
    frame, _ = import_recording(tmp_path / "bag", ImportOptions())
    scale = [f for f in frame.attrs["audit"] if f["kind"] == "scale_disagreement"
             and sorted(f["channels"]) == ["odom_yaw_rate", "yaw_rate"]]
    assert len(scale) == 1 and abs(scale[0]["value"] - SKID) < 0.1, scale
    assert "km/h" not in scale[0]["meaning"] and "skid-steered" in scale[0]["meaning"], scale[0]["meaning"]
