"""An IMU mounted on its side (gravity on y, as on a Clearpath Husky's): the bag reader takes
the yaw rate from the vertical axis its accelerometer names, and says so; a level IMU keeps z."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.measurements.imu_axes import GRAVITY, vertical_axis
from agrobot.measurements.recording import ImportOptions, import_recording
from agrobot.measurements.signal_expressions import parse_signal


def _imu(store, utc: float, angular: tuple, accel: tuple):
    T = store.types
    stamp = T["builtin_interfaces/msg/Time"](sec=int(utc), nanosec=int(round((utc - int(utc)) * 1e9)))
    v3 = T["geometry_msgs/msg/Vector3"]
    return T["sensor_msgs/msg/Imu"](header=T["std_msgs/msg/Header"](stamp=stamp, frame_id="imu_link"),
                                    orientation=T["geometry_msgs/msg/Quaternion"](x=0, y=0, z=0, w=1),
                                    orientation_covariance=np.zeros(9), angular_velocity=v3(*angular),
                                    angular_velocity_covariance=np.zeros(9), linear_acceleration=v3(*accel),
                                    linear_acceleration_covariance=np.zeros(9))


def _bag(folder, up: str, seconds: float = 40.0):
    """A 50 Hz IMU whose ``up`` axis carries gravity and the yaw rate r(t) = 0.3 sin(0.5 t)
    (the truth); the other axes carry small roll and pitch rates."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    from agrobot.measurements.rosbag import typestore

    store = typestore()
    rng = np.random.default_rng(3)
    t = np.arange(0.0, seconds, 0.02)
    r = 0.3 * np.sin(0.5 * t)
    with Writer(folder, version=8, storage_plugin=StoragePlugin.SQLITE3) as w:
        imu = w.add_connection("/imu/data", "sensor_msgs/msg/Imu", typestore=store)
        for k, tk in enumerate(t):
            rates = {"x": 0.02 * rng.standard_normal(), "y": 0.02 * rng.standard_normal(), "z": 0.02 * rng.standard_normal()}
            accel = {"x": 0.5 * rng.standard_normal(), "y": 0.5 * rng.standard_normal(), "z": 0.5 * rng.standard_normal()}
            rates[up] = r[k]
            accel[up] = GRAVITY + 0.3 * rng.standard_normal()
            utc = 1.7e9 + tk
            w.write(imu, int(utc * 1e9), store.serialize_cdr(
                _imu(store, utc, tuple(rates[a] for a in "xyz"), tuple(accel[a] for a in "xyz")), "sensor_msgs/msg/Imu"))
    return t, r


def _read(folder, options=None):
    from agrobot.measurements.rosbag import read_bags

    return read_bags([folder], list((options or ImportOptions()).signals), folder)


@pytest.mark.parametrize("up", ["y", "z"])
def test_the_yaw_rate_comes_from_the_axis_that_carries_gravity(tmp_path, up):
    t, r = _bag(tmp_path / "bag", up)
    signals, report = _read(tmp_path / "bag")
    ts, yaw = signals["yaw_rate"]
    assert np.allclose(yaw, np.interp(ts, 1.7e9 + t, r), atol=1e-6)        # the truth, not the z axis's noise
    turned = [n for n in report.get("choices", []) if "vertical axis" in n]
    assert bool(turned) == (up != "z")
    if turned:
        assert "angular_velocity.y" in turned[0] and "--signal yaw_rate=/imu/data.angular_velocity.z" in turned[0]


def test_a_yaw_rate_the_user_maps_is_kept_and_an_unclear_accelerometer_decides_nothing(tmp_path):
    _bag(tmp_path / "bag", "y")
    options = ImportOptions(signals=[parse_signal("yaw_rate=/imu/data.angular_velocity.z")])
    signals, report = _read(tmp_path / "bag", options)
    assert np.std(signals["yaw_rate"][1]) < 0.05                  # the z axis's noise, as asked
    assert not [n for n in report.get("choices", []) if "vertical axis" in n]
    level = {a: np.full(10, 0.0) for a in "xyz"}
    assert vertical_axis(level) is None
    tilted = {"x": np.full(10, 6.9), "y": np.full(10, 0.0), "z": np.full(10, 6.9)}
    assert vertical_axis(tilted) is None
    assert vertical_axis({"x": np.full(10, -9.7), "y": np.zeros(10), "z": np.full(10, 0.4)})[:2] == ("x", -1.0)


def test_the_converted_log_carries_the_turned_yaw_rate(tmp_path):
    _bag(tmp_path / "bag", "y", seconds=30.0)
    frame, report = import_recording(tmp_path / "bag", ImportOptions(rate=50.0))
    assert np.ptp(frame["yaw_rate"]) > 0.5            # the +-0.3 rad/s truth, not z's +-0.06 noise
    assert any("vertical axis is y" in n for n in report["notes"])
