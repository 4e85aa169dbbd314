"""A bag recorded while a log was replayed at another speed: its receive clock is not the data's.
--time /topic.field[unit] names the topic that carries the data's own clock (a logger's counter),
and every message is carried onto it; any other --time form for a bag is refused, never ignored."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.measurements import LogError
from agrobot.measurements.recording import ImportOptions, import_recording
from agrobot.measurements.signal_expressions import parse_signal

SLOW = 4.0          # the replay: 4 s of bag per second of data (truth)
STEP_AT = 12.0      # s of data: the yaw rate steps from 0 to 0.3 rad/s (truth)
DURATION = 40.0     # s of data at 40 Hz


def _bag(path, clock_ms: np.ndarray | None = None) -> None:
    """Header-less Float32 topics, one message each per data row, received SLOW times slower than the
    data's clock: /stamp (ms), /gyro_z (rad/s), /speed (m/s)."""
    from rosbags.rosbag1 import Writer

    from agrobot.measurements.rosbag import typestore

    store = typestore()
    f32 = store.types["std_msgs/msg/Float32"]
    t = np.arange(0.0, DURATION, 0.025)
    ms = 795065.0 + 1000.0 * t if clock_ms is None else clock_ms
    with Writer(path) as w:
        conns = {n: w.add_connection(n, "std_msgs/msg/Float32", typestore=store) for n in ("/stamp", "/gyro_z", "/speed")}
        for k, tk in enumerate(t):
            receive = int((1.6e9 + SLOW * tk) * 1e9)
            for name, value in (("/stamp", ms[k]), ("/gyro_z", 0.3 * (tk >= STEP_AT)), ("/speed", 0.8)):
                w.write(conns[name], receive + k % 7, store.serialize_ros1(f32(data=float(value)), "std_msgs/msg/Float32"))


def _options(time: str | None) -> ImportOptions:
    return ImportOptions(signals=(parse_signal("yaw_rate=/gyro_z.data[rad/s]"), parse_signal("v=/speed.data[m/s]")),
                         time=time)


def test_a_replayed_bag_is_read_on_the_clock_its_topic_carries(tmp_path):
    pytest.importorskip("rosbags")
    _bag(tmp_path / "replayed.bag")
    frame, report = import_recording(tmp_path / "replayed.bag", _options("/stamp.data[ms]"))
    t = frame["t"].to_numpy()
    assert t[-1] - t[0] == pytest.approx(DURATION - 0.025, abs=0.05)          # not 4 times as long
    assert 1 / np.median(np.diff(t)) == pytest.approx(40.0, rel=0.02)
    step = t[np.argmax(frame["yaw_rate"].to_numpy() > 0.15)]
    assert step == pytest.approx(STEP_AT - t[0], abs=0.03)
    assert any("4 s per second of data" in n for n in report["notes"]), report["notes"]


@pytest.mark.parametrize("time", ["stamp[ms]", "/stamp.data", "/stamp.data[datetime]", "/a.data+/b.data[s]"])
def test_a_bags_time_in_another_form_is_refused_not_ignored(tmp_path, time):
    pytest.importorskip("rosbags")
    _bag(tmp_path / "replayed.bag")
    with pytest.raises(LogError, match=r"a ROS bag takes --time /topic.field\[unit\]"):
        import_recording(tmp_path / "replayed.bag", _options(time))


def test_a_clock_that_restarts_is_refused_with_the_message_it_restarts_at(tmp_path):
    pytest.importorskip("rosbags")
    ms = 1000.0 * np.arange(0.0, DURATION, 0.025)
    ms[800:] -= ms[800]                                            # the logger restarted its counter at row 800
    _bag(tmp_path / "restart.bag", ms)
    with pytest.raises(LogError, match=r"message 801 holds 0 s after 19.975 s.*--time-range"):
        import_recording(tmp_path / "restart.bag", _options("/stamp.data[ms]"))


def test_a_clock_with_a_value_that_is_not_a_number_is_refused_naming_the_message(tmp_path):
    """A NaN in the clock's field neither increases nor decreases: every message near it would take a
    NaN time (np.interp), so it is refused like a restart, naming the message."""
    pytest.importorskip("rosbags")
    ms = 795065.0 + 1000.0 * np.arange(0.0, DURATION, 0.025)
    ms[500] = np.nan
    _bag(tmp_path / "nan.bag", ms)
    with pytest.raises(LogError, match=r"message 501 holds nan s after"):
        import_recording(tmp_path / "nan.bag", _options("/stamp.data[ms]"))


def test_a_clock_topic_the_bag_lacks_is_named_as_the_time_given(tmp_path):
    _bag(tmp_path / "replayed.bag")
    with pytest.raises(LogError) as err:
        import_recording(tmp_path / "replayed.bag", _options("/nope.data[ms]"))
    assert "--time /nope.data[ms]: no topic '/nope'" in str(err.value) and "data_clock" not in str(err.value)
