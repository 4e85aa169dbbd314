"""Topics of one bag stamped by the recorder's computer share its clock: a wheel odometry whose
yaw rate trails the gyro by its own filter (a rolling mean, planted 0.4 s) is a sensor latency,
never a clock offset offered for realignment; a topic stamped by a clock 1.5 s off its receive
times keeps a clock of its own. The wheel odometry's turn rate is written as odom_yaw_rate (the
skid-steer model's input), said in the notes."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.measurements.recording import ImportOptions, import_recording

LAG = 0.4          # s: the odometry's filter delay (truth)


def _stamp(store, utc: float):
    T = store.types
    return T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](
        sec=int(utc), nanosec=int(round((utc - int(utc)) * 1e9))), frame_id="base_link")


def _imu(store, utc: float, r: float):
    T = store.types
    v3 = T["geometry_msgs/msg/Vector3"]
    return T["sensor_msgs/msg/Imu"](header=_stamp(store, utc), orientation=T["geometry_msgs/msg/Quaternion"](
        x=0, y=0, z=0, w=1), orientation_covariance=np.zeros(9), angular_velocity=v3(0.0, 0.0, r),
        angular_velocity_covariance=np.zeros(9), linear_acceleration=v3(0.0, 0.0, 9.81),
        linear_acceleration_covariance=np.zeros(9))


def _odom(store, utc: float, v: float, r: float):
    T = store.types
    v3 = T["geometry_msgs/msg/Vector3"]
    pose = T["geometry_msgs/msg/PoseWithCovariance"](pose=T["geometry_msgs/msg/Pose"](
        position=T["geometry_msgs/msg/Point"](x=0.0, y=0.0, z=0.0),
        orientation=T["geometry_msgs/msg/Quaternion"](x=0, y=0, z=0, w=1)), covariance=np.zeros(36))
    twist = T["geometry_msgs/msg/TwistWithCovariance"](twist=T["geometry_msgs/msg/Twist"](
        linear=v3(v, 0.0, 0.0), angular=v3(0.0, 0.0, r)), covariance=np.zeros(36))
    return T["nav_msgs/msg/Odometry"](header=_stamp(store, utc), child_frame_id="base_link", pose=pose, twist=twist)


def _bag(folder, odom_clock: float, lag: float = LAG, scale: float = 1.0) -> None:
    """120 s: a 50 Hz gyro and a 10 Hz wheel odometry whose yaw rate is ``scale`` times the gyro's
    delayed by ``lag`` (its filter); both received at their stamps, the odometry's stamps
    ``odom_clock`` s off."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    from agrobot.measurements.rosbag import typestore

    store = typestore()
    rng = np.random.default_rng(11)
    t = np.arange(0.0, 120.0, 0.02)
    knots = np.arange(0.0, 121.0, 2.0)
    r_knots = rng.uniform(-0.5, 0.5, len(knots))
    r = np.interp(t, knots, r_knots)
    with Writer(folder, version=8, storage_plugin=StoragePlugin.SQLITE3) as w:
        imu = w.add_connection("/imu/data", "sensor_msgs/msg/Imu", typestore=store)
        odom = w.add_connection("/wheels/odom", "nav_msgs/msg/Odometry", typestore=store)
        for k, tk in enumerate(t):
            utc = 1.7e9 + tk
            w.write(imu, int((utc + 0.005) * 1e9), store.serialize_cdr(
                _imu(store, utc, r[k] + 0.01 * rng.standard_normal()), "sensor_msgs/msg/Imu"))
            if k % 5 == 0 and tk >= lag:
                w.write(odom, int((utc + 0.005) * 1e9), store.serialize_cdr(_odom(
                    store, utc + odom_clock, 1.0, scale * float(np.interp(tk - lag, t, r))), "nav_msgs/msg/Odometry"))


def _pair(frame):
    return [f for f in frame.attrs["audit"] if sorted(f["channels"]) == ["odom_yaw_rate", "yaw_rate"]
            and f["kind"] in ("clock_offset", "sensor_latency")]


def test_an_odometrys_filter_lag_on_the_bags_clock_is_a_sensor_latency_not_a_clock(tmp_path):
    pytest.importorskip("rosbags")
    _bag(tmp_path / "bag", 0.0)
    frame, report = import_recording(tmp_path / "bag", ImportOptions())
    pair = _pair(frame)
    assert [f["kind"] for f in pair] == ["sensor_latency"], pair
    assert abs(abs(pair[0]["value"]) - LAG) < 0.05 and "the bag's receive clock" in pair[0]["meaning"]
    assert "--align" not in pair[0]["meaning"] and "clocks disagree" not in pair[0]["meaning"]
    assert not report["alignment"].get("applied") if isinstance(report.get("alignment"), dict) else True
    # a wheel odometry's turn rate is the skid-steer model's input, named so in the notes
    assert "odom_yaw_rate" in frame and "yaw_rate_2" not in frame
    assert any("odom_yaw_rate: /wheels/odom.twist.twist.angular.z" in n and "skid-steer" in n for n in report["notes"])


def test_a_fused_odometry_stays_a_second_yaw_rate_source(tmp_path):
    from agrobot.measurements.rosbag import wheel_odometry

    assert wheel_odometry("/husky_velocity_controller/odom", "nav_msgs/msg/Odometry")
    assert not wheel_odometry("/odometry/filtered", "nav_msgs/msg/Odometry")
    assert not wheel_odometry("/wheels/odom", "sensor_msgs/msg/Imu")


def test_a_topic_stamped_by_a_clock_off_the_bags_keeps_its_own(tmp_path):
    pytest.importorskip("rosbags")
    _bag(tmp_path / "bag", 1.5)
    frame, _ = import_recording(tmp_path / "bag", ImportOptions(align="none"))
    assert [f["kind"] for f in _pair(frame)] == ["clock_offset"]
