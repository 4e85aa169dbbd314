"""A mode topic in a rosbag2 MCAP file (written here with rosbags' MCAP storage) is carried into the
log at its own times: each row holds the last mode said at or before it, nothing before the first
message, and --where selects by it. The mode is sent at 1 Hz, 0.02 s after the fixes of its
moment: 'auto', then 'manual' from 20 to 35 s."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.measurements.options import ImportOptions
from agrobot.measurements.recording import load_log
from agrobot.measurements.signal_expressions import parse_signal

START = 1.7e9


@pytest.fixture(scope="module")
def bag(tmp_path_factory):
    """(the rosbag2 folder, [(POSIX s, mode said)])."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    from agrobot.measurements.rosbag import typestore
    from tests.import_recordings import truth
    from tests.test_other_data import _imu, _navsat

    folder = tmp_path_factory.mktemp("mcap") / "bag"
    drive = truth(60.0, h=0.01)
    store = typestore()
    string = store.types["std_msgs/msg/String"]
    said = []
    with Writer(folder, version=8, storage_plugin=StoragePlugin.MCAP) as w:
        fix = w.add_connection("/fix", "sensor_msgs/msg/NavSatFix", typestore=store)
        imu = w.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=store)
        mode = w.add_connection("/mode", "std_msgs/msg/String", typestore=store)
        for k, row in enumerate(drive.iloc[::10].itertuples()):
            utc = START + row.t
            w.write(fix, int(utc * 1e9), store.serialize_cdr(
                _navsat(store, "sensor_msgs/msg/NavSatFix", utc, row.lat, row.lon, 10.0, 4), "sensor_msgs/msg/NavSatFix"))
            w.write(imu, int((utc + 0.01) * 1e9), store.serialize_cdr(_imu(store, utc, row.r), "sensor_msgs/msg/Imu"))
            if k % 10 == 0:
                said.append((utc + 0.02, "manual" if 20.0 <= row.t < 35.0 else "auto"))
                w.write(mode, int(said[-1][0] * 1e9), store.serialize_cdr(string(data=said[-1][1]), "std_msgs/msg/String"))
    assert [p.suffix for p in folder.iterdir() if p.suffix != ".yaml"] == [".mcap"]
    return folder, said


@pytest.mark.parametrize("inside", [False, True], ids=["folder", "mcap file"])
def test_a_mode_topic_is_carried_at_its_own_times(bag, inside):
    folder, said = bag
    source = next(folder.glob("*.mcap")) if inside else folder
    frame, report = load_log(source, recording=ImportOptions(signals=[parse_signal("mode=/mode.data")]))
    t = frame["t"].to_numpy() + report["used"]["utc_start_s"]
    times = np.array([u for u, _ in said])
    k = np.searchsorted(times, t + 1e-6, side="right") - 1         # the last message at or before each row
    want = [said[i][1] if i >= 0 else None for i in k]
    got = [None if not isinstance(m, str) else m for m in frame["mode"]]
    assert len(t) > 500 and got == want
    assert sum(m == "manual" for m in got) == pytest.approx(15.0 / np.median(np.diff(t)), abs=2)


def test_where_selects_by_the_mcap_mode_topic(bag):
    folder, said = bag
    opts = ImportOptions(signals=[parse_signal("mode=/mode.data")], where="mode == auto", min_stretch=5.0)
    frame, report = load_log(folder, recording=opts)
    t = frame["t"].to_numpy() + report["used"]["utc_start_s"] - START
    manual = [u - START for u, m in said if m == "manual"]
    assert len(t) > 100 and not ((t >= manual[0]) & (t < manual[-1] + 1.0)).any()
    assert t.min() < manual[0] and t.max() > manual[-1] + 1.0 and "selects" in report["selection"][0]
