"""A GNSS/IMU module on CAN mounted with x up (gravity on AccelerationX, as a CANmod.gps can be):
a yaw rate mapped from AngularRateZ is a roll rate; the audit names the vertical axis from the
accelerometer in the log and the mapping that reads it. A module mounted level (z up) is left alone."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.measurements.recording import ImportOptions, import_recording
from agrobot.measurements.signal_expressions import parse_signal
from tests.test_can_validity_flags import DBC as VALIDITY_DBC

DBC = VALIDITY_DBC.split("BO_ 9 gnss_imu")[0] + '''BO_ 9 gnss_imu: 8 Vector__XXX
 SG_ AccelerationX : 1|10@1+ (0.125,-64) [-64|63.875] "m/s^2" Vector__XXX
 SG_ AccelerationY : 11|10@1+ (0.125,-64) [-64|63.875] "m/s^2" Vector__XXX
 SG_ AccelerationZ : 21|10@1+ (0.125,-64) [-64|63.875] "m/s^2" Vector__XXX
 SG_ AngularRateX : 31|11@1+ (0.25,-256) [-256|255.75] "deg/s" Vector__XXX
 SG_ AngularRateY : 42|11@1+ (0.25,-256) [-256|255.75] "deg/s" Vector__XXX
 SG_ AngularRateZ : 53|11@1+ (0.25,-256) [-256|255.75] "deg/s" Vector__XXX
 SG_ ImuValid : 0|1@1+ (1,0) [0|1] "" Vector__XXX
'''
UP_READING = 9.62      # m/s^2: the vertical axis's mean reading (truth)


def write_drive(folder, up: str, seconds: float = 80.0, sentinel_every: int = 0):
    """10 Hz fixes and speed, a 50 Hz IMU for ``seconds``: a drive east at about 3 m/s turning at
    r(t) = 0.2 sin(0.3 t) rad/s, carried by the ``up`` axis's rate, gravity on its accelerometer;
    every ``sentinel_every``-th IMU frame (if any) sends raw 0 on the accelerations (the DBC's -64)."""
    import cantools

    (folder / "module.dbc").write_text(DBC)
    db = cantools.database.load_string(DBC)
    pos, spd, imu = (db.get_message_by_name(n) for n in ("gnss_pos", "gnss_speed", "gnss_imu"))
    rng = np.random.default_rng(8)
    lines = []
    for k, t in enumerate(np.arange(0.0, seconds, 0.02)):
        stamp = 1.7e9 + t
        if k % 5 == 0:
            east = 3.0 * t
            lon = 10.20 + np.degrees(east / (6371000.0 * np.cos(np.radians(56.1))))
            data = pos.encode({"PositionValid": 1, "Latitude": 56.1, "Longitude": lon})
            lines.append(f"({stamp:.6f}) can0 003#{data.hex().upper()}")
            data = spd.encode({"SpeedValid": 1, "Speed": 3.0})
            lines.append(f"({stamp:.6f}) can0 007#{data.hex().upper()}")
        rate = {a: 2.0 * rng.standard_normal() for a in "XYZ"}
        accel = {a: 0.4 * rng.standard_normal() for a in "XYZ"}
        rate[up] = np.degrees(0.2 * np.sin(0.3 * t))
        accel[up] = UP_READING + 0.3 * rng.standard_normal()
        values = {"ImuValid": 1, **{f"AngularRate{a}": 0.25 * round(4 * rate[a]) for a in "XYZ"},
                  **{f"Acceleration{a}": 0.125 * round(8 * accel[a]) for a in "XYZ"}}
        if sentinel_every and k % sentinel_every == 0:
            values.update({f"Acceleration{a}": -64.0 for a in "XYZ"})
        lines.append(f"({stamp:.6f}) can0 009#{imu.encode(values).hex().upper()}")
    (folder / "drive.log").write_text("\n".join(lines) + "\n")


def _import(folder, yaw="gnss_imu.AngularRateZ[deg/s]"):
    signals = ["lat=gnss_pos.Latitude[deg]", "lon=gnss_pos.Longitude[deg]", "v=gnss_speed.Speed[m/s]",
               f"yaw_rate={yaw}"]
    return import_recording(folder / "drive.log", ImportOptions(
        dbc=folder / "module.dbc", signals=[parse_signal(s) for s in signals], rate=10.0))


def _axis(frame):
    return [f for f in frame.attrs["audit"] if f["kind"] == "mislabelled_channel" and f["channels"] == ["yaw_rate"]
            and "vertical axis" in f["meaning"]]


def test_a_yaw_rate_mapped_from_a_horizontal_axis_is_named_with_the_vertical_one(tmp_path):
    pytest.importorskip("cantools")
    write_drive(tmp_path, "X")
    frame, _ = _import(tmp_path)
    found = _axis(frame)
    assert len(found) == 1 and not found[0]["resolved"]
    assert "vertical axis is x" in found[0]["meaning"] and "--signal yaw_rate=gnss_imu.AngularRateX" in found[0]["meaning"]
    assert abs(found[0]["value"] - UP_READING) < 0.2


@pytest.mark.parametrize("up, yaw", [("Z", "gnss_imu.AngularRateZ[deg/s]"), ("X", "gnss_imu.AngularRateX[deg/s]")])
def test_a_yaw_rate_mapped_from_the_vertical_axis_is_not_named(tmp_path, up, yaw):
    pytest.importorskip("cantools")
    write_drive(tmp_path, up, seconds=40.0)
    frame, _ = _import(tmp_path, yaw)
    assert not _axis(frame)


def test_raw_zero_accelerations_at_the_declared_minimum_are_no_value_and_named(tmp_path):
    """Every 10th IMU frame sends raw 0 on its accelerations (-64 m/s^2, the DBC's declared
    minimum, beyond any ground vehicle): left out and named; the vertical axis is still x; the
    angular rates' minimum (-256 deg/s, 4.5 rad/s) is a possible value and stays a value."""
    pytest.importorskip("cantools")
    write_drive(tmp_path, "X", seconds=40.0, sentinel_every=10)
    frame, report = _import(tmp_path)
    notes = " ".join(report["notes"])
    for axis in "XYZ":
        assert f"gnss_imu.Acceleration{axis}: 200 of 2000 values sit on the DBC's declared bound -64" in notes
    assert not any(k.startswith("gnss_imu.AngularRate") for k in report["can"]["sentinels"])
    found = _axis(frame)
    assert len(found) == 1 and abs(found[0]["value"] - UP_READING) < 0.2
