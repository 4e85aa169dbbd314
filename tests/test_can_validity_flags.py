"""A GNSS module on CAN that flags its own frames (PositionValid = 0 before its first fix, the
position then stale and 3 km away, as a CANmod.gps sends it): those frames' values are left out
and named; the log holds the valid fixes only."""
from __future__ import annotations

import numpy as np

from agrobot.measurements.recording import ImportOptions, import_recording
from agrobot.measurements.signal_expressions import parse_signal

DBC = '''VERSION ""

BS_:

BU_:

BO_ 3 gnss_pos: 8 Vector__XXX
 SG_ PositionValid : 0|1@1+ (1,0) [0|1] "" Vector__XXX
 SG_ Latitude : 1|28@1+ (1e-06,-90) [-90|90] "deg" Vector__XXX
 SG_ Longitude : 29|29@1+ (1e-06,-180) [-180|180] "deg" Vector__XXX

BO_ 7 gnss_speed: 5 Vector__XXX
 SG_ SpeedValid : 0|1@1+ (1,0) [0|1] "" Vector__XXX
 SG_ Speed : 1|20@1+ (0.001,0) [0|1048.575] "m/s" Vector__XXX

BO_ 9 gnss_imu: 8 Vector__XXX
 SG_ ImuValid : 0|1@1+ (1,0) [0|1] "" Vector__XXX
 SG_ AngularRateZ : 53|11@1+ (0.25,-256) [-256|255.75] "deg/s" Vector__XXX
'''
NO_FIX = 20.0          # s: the first fix


def _write(folder, speed_flag="SpeedValid"):
    """10 Hz positions and speed, 50 Hz gyro, for 80 s: a drive east at about 3 m/s; before
    NO_FIX the module sends its last stored position (3 km north) flagged PositionValid = 0."""
    import cantools

    dbc = DBC.replace("SpeedValid", speed_flag)
    (folder / "module.dbc").write_text(dbc)
    db = cantools.database.load_string(dbc)
    pos, spd, imu = (db.get_message_by_name(n) for n in ("gnss_pos", "gnss_speed", "gnss_imu"))
    lines = []
    for k, t in enumerate(np.arange(0.0, 80.0, 0.02)):
        stamp = 1.7e9 + t
        v = 3.0 + 0.5 * np.sin(0.2 * t)
        if k % 5 == 0:
            valid = t >= NO_FIX
            east = 3.0 * t - 2.5 * (np.cos(0.2 * t) - 1)            # the integral of v
            lat = 56.10 + (0.0 if valid else 0.027)
            lon = 10.20 + np.degrees(east / (6371000.0 * np.cos(np.radians(56.1))))
            data = pos.encode({"PositionValid": int(valid), "Latitude": lat, "Longitude": lon})
            lines.append(f"({stamp:.6f}) can0 003#{data.hex().upper()}")
            flag = int(valid) if speed_flag == "SpeedValid" else int(not valid)
            data = spd.encode({speed_flag: flag, "Speed": v if valid else 0.0})
            lines.append(f"({stamp:.6f}) can0 007#{data.hex().upper()}")
        data = imu.encode({"ImuValid": 1, "AngularRateZ": 0.25 * round(4 * np.sin(t))})
        lines.append(f"({stamp:.6f}) can0 009#{data.hex().upper()}")
    (folder / "drive.log").write_text("\n".join(lines) + "\n")


def test_frames_flagged_invalid_are_left_out_and_named(tmp_path):
    _write(tmp_path)
    signals = ["lat=gnss_pos.Latitude[deg]", "lon=gnss_pos.Longitude[deg]", "v=gnss_speed.Speed[m/s]",
               "yaw_rate=gnss_imu.AngularRateZ[deg/s]"]
    frame, report = import_recording(tmp_path / "drive.log", ImportOptions(
        dbc=tmp_path / "module.dbc", signals=[parse_signal(s) for s in signals], rate=10.0))
    notes = " ".join(report["notes"])
    assert "gnss_pos: 200 of 800 frames say PositionValid = 0" in notes and "Latitude" in notes
    assert "gnss_speed: 200 of 800 frames say SpeedValid = 0" in notes
    assert "ImuValid" not in notes                          # every gyro frame is valid
    span = frame["t"].iloc[-1] - frame["t"].iloc[0]
    assert span < 80.0 - NO_FIX + 0.5                       # the stale stretch is not a drive
    assert np.ptp(frame["y"]) < 1.0                         # no 3 km jump north: the stale fixes are out
    assert frame["v"].min() > 2.4                           # no zero speed from the flagged frames


def test_a_flag_named_invalid_marks_the_frames_it_sets_not_those_it_clears(tmp_path):
    """SpeedInvalid = 1 before the first fix: those frames are left out, the valid ones (flag 0) kept."""
    _write(tmp_path, speed_flag="SpeedInvalid")
    frame, report = import_recording(tmp_path / "drive.log", ImportOptions(
        dbc=tmp_path / "module.dbc", signals=[parse_signal(s) for s in (
            "lat=gnss_pos.Latitude[deg]", "lon=gnss_pos.Longitude[deg]", "v=gnss_speed.Speed[m/s]")], rate=10.0))
    notes = " ".join(report["notes"])
    assert "gnss_speed: 200 of 800 frames say SpeedInvalid = 1" in notes
    assert frame["v"].notna().mean() > 0.9 and frame["v"].min() > 2.4
