"""The report names where a bag's positions came from: latitude and longitude mapped from custom
topics (header-less Float32 here) are said to be theirs, never a NavSatFix's the bag does not hold."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.measurements.recording import ImportOptions, import_recording
from agrobot.measurements.signal_expressions import parse_signal


def test_positions_from_custom_topics_are_named_by_their_topics(tmp_path):
    pytest.importorskip("rosbags")
    from rosbags.rosbag1 import Writer

    from agrobot.measurements.rosbag import typestore

    store = typestore()
    f32 = store.types["std_msgs/msg/Float32"]
    t = np.arange(0.0, 60.0, 0.1)
    with Writer(tmp_path / "fixes.bag") as w:
        conns = {n: w.add_connection(n, "std_msgs/msg/Float32", typestore=store) for n in ("/lat", "/lon", "/speed")}
        for tk in t:
            for name, value in (("/lat", 40.07 + 1e-5 * tk), ("/lon", -88.2), ("/speed", 1.1)):
                w.write(conns[name], int((1.6e9 + tk) * 1e9), store.serialize_ros1(f32(data=value), "std_msgs/msg/Float32"))
    options = ImportOptions(signals=tuple(parse_signal(s) for s in ("lat=/lat.data[deg]", "lon=/lon.data[deg]",
                                                                   "v=/speed.data[m/s]")))
    _, report = import_recording(tmp_path / "fixes.bag", options)
    x = report["columns"]["x"]
    assert "NavSatFix" not in x and "/lat (std_msgs/msg/Float32)" in x and "/lon (std_msgs/msg/Float32)" in x, x
