"""MATLAB .mat recordings convert as a recording: each struct a group of channels on its own time
field, its multi-column fields channel by channel (``Gyro[2]``, or named by the struct's column
names), a time vector one longer than its data matched from the first with the row left out named,
a struct on a clock from zero named beside those on POSIX dates, and a file without a time field
refused naming the file, the struct and what was expected. The files are generated here
(scipy.io.savemat; a v7.3 file laid out as MATLAB writes it, with h5py) with a known truth."""
from __future__ import annotations

import importlib.util
import sys

import numpy as np
import pytest
from scipy.io import savemat

from agrobot.measurements import LogError
from agrobot.measurements.listing import list_source
from agrobot.measurements.options import ImportOptions
from agrobot.measurements.recording import import_recording

EPOCH = 1.7e9                    # s: POSIX, a date in 2023
SECONDS = 60.0


def drive() -> dict:
    """Known truth: a gyro (rad/s, 3 axes) at 100 Hz and a wheel speed (m/s) at 50 Hz whose time
    vector holds one more stamp than its rows (the stamp closing the last interval), both on POSIX
    seconds; a motion-capture pose (m, m, rad) at 120 Hz on a clock from zero."""
    t_imu = EPOCH + np.arange(0.0, SECONDS, 0.01)
    gyro = np.column_stack([0.01 * np.ones_like(t_imu), 0.02 * np.cos(t_imu - EPOCH), 0.2 * np.sin(0.5 * (t_imu - EPOCH))])
    t_wheel = EPOCH + 0.004 + np.arange(0.0, SECONDS + 0.02, 0.02)      # one stamp more than speeds
    speed = 2.0 + np.sin(0.7 * (t_wheel[:-1] - EPOCH))
    t_pose = np.arange(0.0, SECONDS, 1 / 120)
    pose = np.column_stack([np.cos(0.1 * t_pose), np.sin(0.1 * t_pose), 0.1 * t_pose])
    return {"imu": {"Time": t_imu, "Gyro": gyro, "Rate": 100.0},
            "wheel": {"time": t_wheel, "Speed": speed},
            "mocap": {"t": t_pose, "Pose": pose, "PoseNames": np.array(["x", "y", "theta"], dtype=object)}}


def write_mat(path, truth: dict, **kw):
    savemat(path, truth, **kw)
    return path


SIGNALS = ["yaw_rate=imu.Gyro[2][rad/s]", "v=wheel.Speed[m/s]"]


def test_a_mat_files_structs_convert_with_every_value_the_sources(tmp_path):
    truth = drive()
    mat = write_mat(tmp_path / "drive.mat", {k: v for k, v in truth.items() if k != "mocap"})
    frame, report = import_recording(mat, ImportOptions(signals=SIGNALS))
    assert report["files"] == {"matlab": [str(mat)]}
    t = frame["t"].to_numpy() + report["used"]["utc_start_s"]
    imu, wheel = truth["imu"], truth["wheel"]
    assert np.allclose(frame["yaw_rate"], np.interp(t, imu["Time"], imu["Gyro"][:, 2]), atol=1e-6)
    # each speed at the start of its interval: the last stamp left over, not each speed one stamp later
    assert np.allclose(frame["v"], np.interp(t, wheel["time"][:-1], wheel["Speed"]), atol=1e-6)
    assert not np.allclose(frame["v"], np.interp(t, wheel["time"][1:], wheel["Speed"]), atol=1e-4)
    said = " ".join(report["notes"])
    assert "wheel: time holds 3001 rows, Speed 3000: matched row by row from the first, time's row 3001" in said
    assert "passed over: matching from the last" in said


def test_the_listing_names_groups_channels_clocks_and_the_rows_left_out(tmp_path):
    mat = write_mat(tmp_path / "drive.mat", drive(), oned_as="column")
    text = "\n".join(list_source(mat, ImportOptions()))
    assert "MATLAB file drive.mat: MAT-file version 5" in text
    for channel in ("imu.Gyro[0]", "imu.Gyro[2]", "wheel.Speed", "mocap.x", "mocap.y", "mocap.theta"):
        assert f"  {channel}: " in text, channel
    assert "imu: Rate = 100.0 (a scalar: not a channel)" in text
    assert "mocap: Pose: its 3 columns named by the group's column names (x, y, theta)" in text
    assert "mocap: its clock counts from its own start (0.000 s), the clock of imu, wheel from 1970" in text
    assert "time's row 3001 (time 1700000060.004000) left out" in text


def test_a_channel_of_a_group_on_a_clock_from_zero_is_not_joined_with_dated_ones(tmp_path):
    mat = write_mat(tmp_path / "drive.mat", drive())
    with pytest.raises(LogError, match=r"drive.mat \(wheel\) 2023.*drive.mat \(mocap\) 0.000 s on the logger.*"
                                       r"one counts from its start, another from 1970"):
        import_recording(mat, ImportOptions(signals=["x=mocap.x[m]", "y=mocap.y[m]", "v=wheel.Speed[m/s]"]))
    frame, report = import_recording(mat, ImportOptions(signals=["x=mocap.x[m]", "y=mocap.y[m]"]))
    t = frame["t"].to_numpy() + report["used"]["utc_start_s"]
    assert np.allclose(frame["x"], np.cos(0.1 * t), atol=1e-6)
    assert "mocap: seconds from the logger's start, not dates" in report["clocks"]["reference"]


def test_a_version_4_file_of_top_level_arrays_is_one_group_named_after_the_file(tmp_path):
    t = EPOCH + np.arange(0.0, 30.0, 0.05)
    mat = write_mat(tmp_path / "run 1.mat", {"t": t, "speed": 3.0 + np.sin(t - EPOCH)}, format="4")
    frame, report = import_recording(mat, ImportOptions(signals=["v=run_1.speed[km/h]"]))
    tt = frame["t"].to_numpy() + report["used"]["utc_start_s"]
    assert np.allclose(frame["v"], (3.0 + np.sin(tt - EPOCH)) / 3.6, atol=1e-6)


def test_a_datenum_time_is_read_as_posix_seconds_and_said_so(tmp_path):
    t = EPOCH + np.arange(0.0, 30.0, 0.05)
    datenum = t / 86400.0 + 719529.0
    mat = write_mat(tmp_path / "d.mat", {"gps": {"Timestamp": datenum, "Speed": 3.0 + np.sin(t - EPOCH)}})
    frame, report = import_recording(mat, ImportOptions(signals=["v=gps.Speed[m/s]"]))
    assert abs(report["used"]["utc_start_s"] - EPOCH) < 0.06
    tt = frame["t"].to_numpy() + report["used"]["utc_start_s"]
    assert np.allclose(frame["v"], 3.0 + np.sin(tt - EPOCH), atol=1e-5)
    assert any("MATLAB datenum days" in n for n in report["notes"])


def test_a_mat_file_without_a_time_field_is_refused_naming_the_file_and_struct(tmp_path, cli):
    mat = write_mat(tmp_path / "notime.mat", {"odometry": {"Ticks": np.arange(200).reshape(100, 2)}})
    run = cli("convert", mat, "--signal", "v=odometry.Ticks[0][m/s]", "--out", tmp_path / "out.csv")
    assert run.returncode == 2 and "Traceback" not in run.stderr, run.stderr
    assert f"{mat}: no time field in it: struct odometry (fields Ticks); expected in each struct a field named " \
           "t, time, timestamp, time_s (any letter case" in run.stderr, run.stderr
    assert not (tmp_path / "out.csv").exists()
    listed = list_source(mat, ImportOptions())
    assert all("no time field in it: struct odometry" in line for line in listed[1:]), listed


def test_a_struct_without_a_time_beside_a_timed_one_is_named_when_asked_for(tmp_path):
    mat = write_mat(tmp_path / "two.mat", {"odometry": {"Ticks": np.arange(200).reshape(100, 2)},
                                           "gps": {"t": np.arange(100.0), "v": np.ones(100)}})
    with pytest.raises(LogError) as caught:
        import_recording(mat, ImportOptions(signals=["v=odometry.Ticks[0][m/s]"]))
    assert str(caught.value).startswith(f"{mat} (odometry): no time column"), caught.value
    assert "odometry: no time field (expected one named t, time, timestamp" in "\n".join(list_source(mat, ImportOptions()))


def _write_v73(path, groups: dict) -> None:
    """A MATLAB v7.3 file as MATLAB lays it out: a 512-byte user block opening with MATLAB's text
    header, each struct an HDF5 group, each array stored transposed (MATLAB is column-major), its
    class in MATLAB_class; a cell array of texts as references to char arrays."""
    import h5py

    with h5py.File(path, "w", userblock_size=512) as f:
        refs = f.create_group("#refs#")
        for name, fields in groups.items():
            g = f.create_group(name)
            g.attrs["MATLAB_class"] = np.bytes_("struct")
            for k, v in fields.items():
                if isinstance(v, list):
                    cells = [refs.create_dataset(f"{name}{k}{i}", data=np.array([[ord(c)] for c in s], np.uint16))
                             for i, s in enumerate(v)]
                    for c in cells:
                        c.attrs["MATLAB_class"] = np.bytes_("char")
                    d = g.create_dataset(k, data=np.array([[c.ref for c in cells]], dtype=h5py.ref_dtype).T)
                    d.attrs["MATLAB_class"] = np.bytes_("cell")
                else:
                    d = g.create_dataset(k, data=np.atleast_2d(np.asarray(v)).T if np.ndim(v) == 2 else
                                         np.asarray(v)[None, :])
                    d.attrs["MATLAB_class"] = np.bytes_("double")
    with open(path, "r+b") as f:
        f.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Dec  7 18:00:00 2026 HDF5 schema 1.00 .")


@pytest.mark.skipif(importlib.util.find_spec("h5py") is None, reason="h5py (the matlab extra) is not installed: "
                    "a v7.3 file cannot be written or read")
def test_a_version_7_3_file_converts_as_the_same_file_in_version_5(tmp_path):
    truth = drive()
    mocap = {"t": truth["mocap"]["t"], "Pose": truth["mocap"]["Pose"], "PoseNames": ["x", "y", "theta"]}
    _write_v73(tmp_path / "new.mat", {"imu": truth["imu"] | {"Rate": np.array([100.0])}, "wheel": truth["wheel"],
                                      "mocap": mocap})
    listing = "\n".join(list_source(tmp_path / "new.mat", ImportOptions()))
    assert "MAT-file version 7.3" in listing and "  mocap.theta: " in listing and "  imu.Gyro[1]: " in listing
    new, _ = import_recording(tmp_path / "new.mat", ImportOptions(signals=SIGNALS))
    old, _ = import_recording(write_mat(tmp_path / "old.mat", truth), ImportOptions(signals=SIGNALS))
    assert np.array_equal(new[["t", "yaw_rate", "v"]].to_numpy(), old[["t", "yaw_rate", "v"]].to_numpy())


def test_a_version_7_3_file_without_h5py_is_refused_saying_what_it_needs(tmp_path, monkeypatch):
    path = tmp_path / "new.mat"
    path.write_bytes(b"MATLAB 7.3 MAT-file".ljust(512, b" ") + b"\x89HDF\r\n\x1a\n" + bytes(64))
    monkeypatch.setitem(sys.modules, "h5py", None)           # import h5py fails as where it is not installed
    with pytest.raises(LogError) as caught:
        import_recording(path, ImportOptions(signals=SIGNALS))
    assert str(caught.value).startswith(f"{path}: a MATLAB v7.3 MAT-file (HDF5): reading it needs h5py")
    assert "pip install 'agrobot-guidance[matlab]'" in str(caught.value)


def test_a_wheel_tick_counter_that_wraps_becomes_a_speed_with_rate(tmp_path):
    """Known truth: a wheel turning forward and back, its hall counter a uint16 that wraps every
    65536 ticks (several times in the minute); v = rate(ticks) x metres per tick, unwrapped at
    the counter's width read from its type."""
    per_metre = 703 / (np.pi * 0.213)                  # ticks per metre of a 0.213 m wheel, 703 ticks a turn
    t = EPOCH + np.arange(0.0, SECONDS, 0.02)
    distance = (t - EPOCH) + 2.5 / 0.3 * (1 - np.cos(0.3 * (t - EPOCH)))     # v = 1 + 2.5 sin(0.3 t): reverses
    ticks = np.floor(per_metre * distance).astype(np.int64) + 65000
    mat = write_mat(tmp_path / "wheel.mat", {"odometry": {"Time": t, "Ticks": (ticks % 65536).astype(np.uint16)}})
    frame, report = import_recording(mat, ImportOptions(signals=[f"v=rate(odometry.Ticks)*{1 / per_metre!r}[m/s]"]))
    tt = frame["t"].to_numpy() + report["used"]["utc_start_s"]
    mid, rate = 0.5 * (t[1:] + t[:-1]), np.diff(ticks) / np.diff(t)
    assert np.allclose(frame["v"], np.interp(tt, mid, rate / per_metre), atol=1e-6)
    assert frame["v"].min() < -1.0 and frame["v"].max() > 3.0
    assert "unwrapped modulo 65536" in report["columns"]["v"]


def test_rate_takes_one_signal_name():
    from agrobot.measurements.signal_expressions import parse_signal

    with pytest.raises(LogError, match=r"rate\(\.\.\.\) takes one signal name"):
        parse_signal("v=rate(a.b + c.d)[m/s]")


def test_a_seconds_clock_eight_days_from_its_start_is_not_a_datenum(tmp_path):
    """A logger up 8.1 days counts its seconds into the datenums of 1900-2100 (693962 to 767011);
    stepping 0.05 s it is no datenum (a datenum steps by 0.05 / 86400 days): read as seconds."""
    t = 700000.0 + np.arange(0.0, 30.0, 0.05)
    mat = write_mat(tmp_path / "up.mat", {"gps": {"Timestamp": t, "Speed": 3.0 + np.sin(t - t[0])}})
    frame, report = import_recording(mat, ImportOptions(signals=["v=gps.Speed[m/s]"]))
    assert not any("MATLAB datenum days" in n for n in report["notes"]), report["notes"]
    assert np.allclose(np.diff(frame["t"].to_numpy()), 0.05, atol=1e-6)
