"""rate() of a counter in a ROS bag: a message field typed uint16 (std_msgs/UInt16.data, a wheel
encoder's tick count) rolls over at 2^16 and is unwrapped there, as a .mat file's uint16 is
(measurements.signal_expressions.counter_rate); a float field is differenced as it is."""
from __future__ import annotations

import numpy as np

from agrobot.measurements.recording import ImportOptions, import_recording
from agrobot.measurements.signal_expressions import parse_signal

TICKS_PER_S = 3000.0                 # 3 m/s at 1 mm a tick: 65536 ticks in under 22 s


def _bag(path) -> None:
    """60 s of a 50 Hz std_msgs/UInt16 tick count and a Float32 gyro, header-less (receive times)."""
    from rosbags.rosbag1 import Writer

    from agrobot.measurements.rosbag import typestore

    store = typestore()
    u16, f32 = store.types["std_msgs/msg/UInt16"], store.types["std_msgs/msg/Float32"]
    t = np.arange(0.0, 60.0, 0.02)
    with Writer(path) as w:
        ticks = w.add_connection("/wheel/ticks", "std_msgs/msg/UInt16", typestore=store)
        gyro = w.add_connection("/gyro_z", "std_msgs/msg/Float32", typestore=store)
        for k, tk in enumerate(t):
            receive = int((1.7e9 + tk) * 1e9)
            count = int(TICKS_PER_S * tk) % 65536
            w.write(ticks, receive, store.serialize_ros1(u16(data=count), "std_msgs/msg/UInt16"))
            w.write(gyro, receive + 1000, store.serialize_ros1(f32(data=float(0.1 * np.sin(0.3 * tk))),
                                                                 "std_msgs/msg/Float32"))


def test_a_uint16_tick_count_in_a_bag_is_unwrapped(tmp_path):
    _bag(tmp_path / "drive.bag")
    options = ImportOptions(signals=(parse_signal("v=rate(/wheel/ticks.data)*0.001[m/s]"),
                                     parse_signal("yaw_rate=/gyro_z.data[rad/s]")))
    log, report = import_recording(tmp_path / "drive.bag", options)
    assert np.allclose(log["v"].to_numpy(), TICKS_PER_S * 0.001, atol=0.1), (log["v"].min(), log["v"].max())
    assert "unwrapped modulo 65536" in report["columns"]["v"], report["columns"]["v"]
    assert not [f for f in report["audit"]["findings"] if f["kind"] == "out_of_range"]     # no roll-over as a spike


def test_the_width_of_a_field_from_the_message_definitions():
    from agrobot.measurements.rosbag import field_width, typestore

    defs = typestore().fielddefs
    assert field_width(defs, "std_msgs/msg/UInt16", "data") == 2.0 ** 16
    assert field_width(defs, "std_msgs/msg/UInt16", "") == 2.0 ** 16          # the message's one numeric field
    assert field_width(defs, "std_msgs/msg/Int32", "data") == 2.0 ** 32
    assert field_width(defs, "std_msgs/msg/Float64", "data") is None
    assert field_width(defs, "std_msgs/msg/Int64", "data") is None
    assert field_width(defs, "sensor_msgs/msg/Imu", "header.stamp.sec") == 2.0 ** 32
    assert field_width(defs, "sensor_msgs/msg/Imu", "angular_velocity.z") is None
    assert field_width(defs, "std_msgs/msg/UInt16MultiArray", "data[1]") == 2.0 ** 16
    assert field_width(defs, "std_msgs/msg/UInt16", "nothing") is None
