"""Every binary reader fuzzed: a small valid file of each binary format (an ISO 11783 time log's
TLG.bin, a ROS 1 bag, a ROS 2 bag as MCAP and as SQLite .db3, a Vector BLF CAN log), generated here
from known values,
is damaged (bytes flipped, cut, repeated, zeroed, the file truncated, a length or count made huge,
an offset pointed back at an earlier byte) and read as a user's would
(measurements.recording.import_recording). Each outcome is a log whose time increases, or an
InputError naming the file and where (a byte offset, a record, a message, a frame), never another
exception, within SECONDS and a bounded memory growth. The MDF 4 reader has its own
(tests/test_mdf4_links.py). Fixed seed (derandomized): the same examples every run."""
from __future__ import annotations

import re
import resource
import struct
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from agrobot.orchestrator.errors import InputError
from harness.generated_recordings import candump_lines, write_timelog
from tests.test_fuzz_readers import mutate

SETTINGS = settings(max_examples=60, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
SECONDS = 10.0
GROWTH_MB = 400.0
# where the damage is; or a whole-file fault: its start (magic) or its having nothing to read
WHERE = re.compile(r"offset|byte|record|message|frame|line|field|topic|stream|DLV|magic|empty|no run|no record|no CAN frame|"
                   r"page|table")


def _imu_bag(path: Path, ros1: bool, storage: str = "mcap") -> Path:
    """50 IMU messages at 10 Hz, yaw rate 0.1 sin(0.5 t) rad/s (stamps 1000 s on); ROS 2: ``storage``
    mcap or sqlite3 (the bag's file, .mcap or .db3)."""
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    types = store.types
    imu, header, stamp = types["sensor_msgs/msg/Imu"], types["std_msgs/msg/Header"], types["builtin_interfaces/msg/Time"]
    vector, quaternion = types["geometry_msgs/msg/Vector3"], types["geometry_msgs/msg/Quaternion"]
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with (Writer1(path) if ros1 else Writer2(path, version=8, storage_plugin=plugin)) as w:
        c = w.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=store)
        for k in range(50):
            t = 1000 + 0.1 * k
            when = stamp(sec=int(t), nanosec=int(round((t % 1) * 1e9)))
            msg = imu(header=header(seq=k, stamp=when, frame_id="imu") if ros1 else header(stamp=when, frame_id="imu"),
                      orientation=quaternion(x=0.0, y=0.0, z=0.0, w=1.0), orientation_covariance=np.zeros(9),
                      angular_velocity=vector(x=0.0, y=0.0, z=0.1 * np.sin(0.5 * t)),
                      angular_velocity_covariance=np.zeros(9), linear_acceleration=vector(x=0.0, y=0.0, z=9.81),
                      linear_acceleration_covariance=np.zeros(9))
            data = (store.serialize_ros1 if ros1 else store.serialize_cdr)(msg, "sensor_msgs/msg/Imu")
            w.write(c, int(t * 1e9), data)
    return path if ros1 else next(path.glob("*.mcap" if storage == "mcap" else "*.db3"))


def _blf(path: Path) -> Path:
    """The project's TractorFeedback frames of harness.generated_recordings.candump_lines, as BLF."""
    import can

    with can.BLFWriter(str(path)) as w:
        for line in candump_lines(10.0):
            ident, data = line.split()[2].split("#")
            w.on_message_received(can.Message(timestamp=float(line[1:line.index(")")]), arbitration_id=int(ident, 16),
                                              is_extended_id=False, data=bytes.fromhex(data), channel=0))
    return path


def _bases() -> dict[str, tuple[str, bytes]]:
    pytest.importorskip("rosbags")
    pytest.importorskip("can")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        log = write_timelog(tmp / "t", 40)
        return {"tlg": ("TLG00001.bin", (log / "TLG00001.bin").read_bytes()),
                "tlg_header": ("TLG00001.xml", (log / "TLG00001.xml").read_bytes()),
                "ros1": ("drive.bag", _imu_bag(tmp / "drive.bag", True).read_bytes()),
                "mcap": ("drive.mcap", _imu_bag(tmp / "rosbag2", False).read_bytes()),
                "db3": ("drive.db3", _imu_bag(tmp / "sqlite", False, "sqlite3").read_bytes()),
                "blf": ("bus.blf", _blf(tmp / "bus.blf").read_bytes())}


BASES: dict = {}


def _base(kind: str) -> tuple[str, bytes]:
    if not BASES:
        BASES.update(_bases())
    return BASES[kind]


def _edits():
    """Byte edits (tests.test_fuzz_readers.mutate) and structural ones: ("huge", where, width) writes
    the largest value of a 4- or 8-byte field, ("back", where, width) an offset pointing earlier."""
    structural = st.tuples(st.sampled_from(["huge", "back"]), st.floats(0.0, 1.0), st.sampled_from([4, 8]),
                           st.integers(0, 255))
    plain = st.tuples(st.sampled_from(["flip", "cut", "repeat", "insert", "truncate", "zero"]),
                      st.floats(0.0, 1.0), st.integers(1, 64), st.integers(0, 255))
    return st.lists(st.one_of(plain, structural), min_size=1, max_size=4)


def damaged(data: bytes, edits) -> bytes:
    out = bytearray(mutate(data, [e for e in edits if e[0] not in ("huge", "back")]))
    for kind, where, width, _ in (e for e in edits if e[0] in ("huge", "back")):
        if len(out) <= width:
            continue
        i = int(where * (len(out) - width))
        value = (1 << (8 * width)) - 1 if kind == "huge" else i // 2
        out[i:i + width] = value.to_bytes(width, "little")
    return bytes(out)


def _peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


START_MB: list[float] = []     # the peak when this file's first test starts (other files may run before it)


@pytest.fixture(autouse=True, scope="module")
def _peak_at_start():
    START_MB.append(_peak_mb())


def read_or_refused(path: Path, shown: Path) -> str:
    """'read' or 'refused': a log whose time increases, or an InputError naming ``shown`` and where."""
    from agrobot.measurements.recording import import_recording

    start = time.perf_counter()
    try:
        frame, _ = import_recording(path)
    except InputError as exc:
        text = str(exc)
        assert str(shown) in text and "Traceback" not in text and "MemoryError" not in text, text
        assert WHERE.search(text.replace(str(shown), "")), text
        return "refused"
    finally:
        assert time.perf_counter() - start < SECONDS
    t = frame["t"].to_numpy(float)
    assert len(t) >= 2 and np.all(np.diff(t) > 0) and np.isfinite(t).all()
    return "read"


@SETTINGS
@given(kind=st.sampled_from(["tlg", "ros1", "mcap", "db3", "blf"]), edits=_edits())
def test_a_damaged_binary_recording_is_read_or_refused_naming_the_file_and_where(kind, edits):
    name, data = _base(kind)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        path = folder / name
        path.write_bytes(damaged(data, edits))
        if kind == "tlg":                 # the time log's header beside its damaged binary
            (folder / "TLG00001.xml").write_bytes(_base("tlg_header")[1])
        read_or_refused(folder if kind == "tlg" else path, path)


@pytest.mark.parametrize("kind", ["ros1", "mcap"])
def test_a_bag_declaring_a_huge_record_is_refused_at_its_offset_before_anything_is_read(kind, tmp_path):
    """The first record after the magic given the largest length: named at its byte offset (13 in a
    ROS 1 bag, 8 in an MCAP file), not read (which would ask for terabytes)."""
    name, data = _base(kind)
    raw = bytearray(data)
    if kind == "ros1":
        raw[13:17] = struct.pack("<I", 0xFFFFFFF0)
        words = r"field 'header_len' declares 4294967280 bytes.*\(at byte offset 13\)"
    else:
        raw[9:17] = struct.pack("<Q", 1 << 62)
        words = rf"record opcode 0x01 declares {1 << 62} bytes.*\(at byte offset 8\)"
    path = tmp_path / name
    path.write_bytes(bytes(raw))
    began = time.perf_counter()
    with pytest.raises(InputError, match=words):
        from agrobot.measurements.recording import import_recording
        import_recording(path)
    assert time.perf_counter() - began < 5


def _db3(tmp_path: Path, name: str, edit) -> Path:
    """The .db3 base written to ``name`` and changed by ``edit(path)``."""
    path = tmp_path / name
    path.write_bytes(_base("db3")[1])
    edit(path)
    return path


def test_a_db3_cut_short_is_refused_at_the_page_it_ends_in_or_by_its_declared_pages(tmp_path):
    from agrobot.measurements.recording import import_recording

    data = _base("db3")[1]
    page = int.from_bytes(data[16:18], "big")           # the SQLite header's page size (big-endian)
    cut = _db3(tmp_path, "cut.db3", lambda p: p.write_bytes(data[:len(data) // 2 + 100]))
    ends = len(data) // 2 + 100
    with pytest.raises(InputError, match=rf"ends {ends % page} bytes into a page of {page} bytes .*\(at byte offset "
                                         rf"{ends - ends % page}\)"):
        import_recording(cut)
    pages = int.from_bytes(data[28:32], "big")
    short = _db3(tmp_path, "short.db3", lambda p: p.write_bytes(data[:page * (pages - 1)]))
    with pytest.raises(InputError, match=rf"declares {pages} pages of {page} bytes .* the file has {page * (pages - 1)}"
                                         rf" .*\(at byte offset 28\)"):
        import_recording(short)
    text = _db3(tmp_path, "text.db3", lambda p: p.write_bytes(b"not a database at all, only text\n" * 10))
    with pytest.raises(InputError, match=rf"{text}: .* does not start with the SQLite magic"):
        import_recording(text)


def test_a_db3_message_that_does_not_decode_is_named_by_file_topic_and_number(tmp_path):
    """Message 7 of /imu (receive time 1000.6 s) given two bytes, which no Imu message fits."""
    import sqlite3

    from agrobot.measurements.recording import import_recording

    def broken(path: Path) -> None:
        with sqlite3.connect(path) as db:
            db.execute("UPDATE messages SET data = x'0001' WHERE timestamp = 1000600000000")
        db.close()
    path = _db3(tmp_path, "blob.db3", broken)
    with pytest.raises(InputError, match=rf"{path}: topic /imu: message 7 of the topic \(receive time "
                                         r"1000.600000000 s\) cannot be decoded as sensor_msgs/msg/Imu: its bytes are "
                                         r"damaged"):
        import_recording(path)


def test_a_db3_type_definition_missing_a_type_it_uses_is_named_by_its_row(tmp_path):
    """The Imu definition's section 'MSG: geometry_msgs/Quaternion' renamed: its orientation field's type is
    defined nowhere."""
    import sqlite3

    from agrobot.measurements.recording import import_recording

    def renamed(path: Path) -> None:
        with sqlite3.connect(path) as db:
            db.execute("UPDATE message_definitions SET encoded_message_definition = replace(encoded_message_definition,"
                       " 'MSG: geometry_msgs/Quaternion', 'MSG: geometry_msgs/Quaternixn')")
        db.close()
    path = _db3(tmp_path, "definition.db3", renamed)
    with pytest.raises(InputError, match=rf"{path}: .*table 'message_definitions' row 1 \(sensor_msgs/msg/Imu\): the "
                                         r"field type geometry_msgs/Quaternion has no MSG: section"):
        import_recording(path)


def test_the_valid_bases_read_their_known_values(tmp_path):
    """The undamaged files read whole: 50 yaw rates of 0.1 sin(0.5 t) from each bag, 200 frames
    at 20 Hz from the BLF (so a refusal above is the damage's, not the generator's)."""
    from agrobot.measurements.recording import import_recording

    for kind in ("ros1", "mcap", "db3"):
        name, data = _base(kind)
        (tmp_path / name).write_bytes(data)
        frame, _ = import_recording(tmp_path / name)
        t = frame["t"].to_numpy(float)
        assert len(t) == 50
        assert np.allclose(frame["yaw_rate"], 0.1 * np.sin(0.5 * (1000 + t - t[0])), atol=1e-9)
    name, data = _base("blf")
    (tmp_path / name).write_bytes(data)
    frame, _ = import_recording(tmp_path / name)
    assert len(frame) == 200 and np.allclose(np.diff(frame["t"]), 0.05)


def test_the_fuzzing_stayed_within_its_memory_bound():
    """Last in the file: every example above ran in this process; its peak grew this little."""
    assert _peak_mb() - START_MB[0] < GROWTH_MB
