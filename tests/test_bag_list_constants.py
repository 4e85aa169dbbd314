"""convert --list on a bag names a message's fields, never its type's constants: rosgraph_msgs/Log
declares DEBUG = 1 ... FATAL = 16, which no message carries."""
from __future__ import annotations

import pytest

from agrobot.measurements.rosbag import list_bag


def test_a_log_messages_constants_are_not_listed_as_fields(tmp_path):
    pytest.importorskip("rosbags")
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    T = store.types
    log = T["rosgraph_msgs/msg/Log"](header=T["std_msgs/msg/Header"](seq=0, stamp=T["builtin_interfaces/msg/Time"](
        sec=1, nanosec=0), frame_id=""), level=4, name="n", msg="m", file="f", function="g", line=213, topics=[])
    with Writer(tmp_path / "log.bag") as w:
        c = w.add_connection("/rosout", "rosgraph_msgs/msg/Log", typestore=store)
        for k in range(3):
            w.write(c, (1 + k) * 10**9, store.serialize_ros1(log, "rosgraph_msgs/msg/Log"))
    lines = list_bag([tmp_path / "log.bag"])
    fields = [line.split(":")[0].strip() for line in lines if line.startswith("    /rosout.")]
    assert fields == ["/rosout.level", "/rosout.line"], lines
