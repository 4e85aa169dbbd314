"""Folders of numpy channels (a folder per signal with its ``t`` and ``value`` arrays, as
comma2k19's processed_log holds a car's CAN speed, steering-wheel angle and phone IMU) convert
as a recording: every value written is the generated source's after unit conversion, at the
source's own times; a gyro of three axes gives value0..value2, its down axis the yaw rate with
its sign turned. Arrays that are not a channel's, and a channel's file that is not a numpy array
(a text export, an empty copy), are refused naming the file, nothing written."""
from __future__ import annotations

import math

import numpy as np
import pytest

from agrobot.measurements import LogError
from agrobot.measurements.options import ImportOptions
from agrobot.measurements.recording import import_recording
from agrobot.measurements.signal_expressions import parse_signal

BOOT = 46_400.0                  # s: a device's boot clock, not POSIX


def save(path, array, suffix: bool = False):
    """numpy.save to ``path`` as named (comma2k19 writes no .npy suffix)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path.with_suffix(".npy") if suffix else path, "wb") as f:
        np.save(f, array)


def write_drive(root, seconds: float = 60.0):
    """Known truth: CAN speed [m/s] (N x 1) and steering-wheel angle [deg] at 100 Hz, a gyro
    [forward, right, down] in rad/s at 104 Hz; the log's yaw rate is minus the down axis."""
    t_can = BOOT + np.arange(0.0, seconds, 0.01)
    t_imu = BOOT + 0.003 + np.arange(0.0, seconds, 1 / 104)
    speed = 15.0 + 2.0 * np.sin(0.2 * (t_can - BOOT))
    wheel = 30.0 * np.sin(0.5 * (t_can - BOOT))
    down = -0.1 * np.sin(0.5 * (t_imu - BOOT) - 0.1)
    gyro = np.column_stack([0.01 * np.ones_like(t_imu), 0.02 * np.ones_like(t_imu), down])
    log = root / "processed_log"
    save(log / "CAN" / "speed" / "t", t_can)
    save(log / "CAN" / "speed" / "value", speed[:, None])
    save(log / "CAN" / "steering_angle" / "t", t_can, suffix=True)
    save(log / "CAN" / "steering_angle" / "value", wheel, suffix=True)
    save(log / "IMU" / "gyro" / "t", t_imu)
    save(log / "IMU" / "gyro" / "value", gyro)
    return {"t_can": t_can, "t_imu": t_imu, "v": speed, "delta": wheel, "yaw_rate": -down}


SIGNALS = ["delta=processed_log_CAN_steering_angle.value[deg]", "v=processed_log_CAN_speed.value[m/s]",
           "yaw_rate=-1*processed_log_IMU_gyro.value2[rad/s]"]


def test_numpy_channel_folders_convert_with_every_value_the_sources(tmp_path):
    truth = write_drive(tmp_path / "route")
    frame, report = import_recording(tmp_path / "route", ImportOptions(signals=[parse_signal(s) for s in SIGNALS]))
    read = sorted(str(p).split("processed_log/")[-1] for p in report["files"]["numpy"])
    assert read == ["CAN/speed", "CAN/steering_angle", "IMU/gyro"], report["files"]
    t = frame["t"].to_numpy()
    t0 = report["used"]["utc_start_s"]          # the log's t counts from its start on the boot clock
    assert BOOT <= t0 < BOOT + 1.0
    for column, times, scale in (("v", "t_can", 1.0), ("delta", "t_can", math.pi / 180),
                                 ("yaw_rate", "t_imu", 1.0)):
        want = np.interp(t + t0, truth[times], truth[column] * scale)
        assert np.allclose(frame[column].to_numpy(), want, atol=1e-6 * max(1.0, np.abs(want).max())), column


@pytest.mark.parametrize("bad, expect", [
    ("length", "values of shape (5,) (float64) beside 6000 times"),
    ("text", "values of shape"),
    ("times", "times of shape (6000, 2)"),
    ("csv_value", "speed/value: not a numpy array (it begins b'15.0\\n15.1\\n'); expected a numpy.save array of "
                  "the samples"),
    ("empty_times", "speed/t: not a numpy array (it is empty or unreadable); expected a numpy.save array of the times"),
])
def test_arrays_that_are_not_a_channels_are_refused_by_name(tmp_path, cli, bad, expect):
    write_drive(tmp_path / "route")
    folder = tmp_path / "route" / "processed_log" / "CAN" / "speed"
    if bad == "length":
        save(folder / "value", np.ones(5))
    elif bad == "text":
        save(folder / "value", np.array(["a"] * 6000))
    elif bad == "csv_value":                  # a text export where the array was: named, not skipped
        (folder / "value").write_text("15.0\n15.1\n")
    elif bad == "empty_times":
        (folder / "t").write_bytes(b"")
    else:
        save(folder / "t", np.ones((6000, 2)))
    with pytest.raises(LogError, match="speed"):
        import_recording(tmp_path / "route", ImportOptions(signals=[parse_signal(s) for s in SIGNALS]))
    args = ["convert", tmp_path / "route", "--out", tmp_path / "out.csv"] + [a for s in SIGNALS for a in ("--signal", s)]
    run = cli(*args)
    assert run.returncode == 2 and expect in run.stderr and "Traceback" not in run.stderr, run.stderr
    assert not (tmp_path / "out.csv").exists()
