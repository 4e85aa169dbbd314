"""A recording whose positions are in signals the readers do not know by name (a GNSS module's
Latitude/Longitude on CAN): the missing x and y name the remedy, and the remedy works."""
from __future__ import annotations

import numpy as np
import pandas as pd

from agrobot.measurements.recording import ImportOptions, import_recording
from agrobot.measurements.signal_expressions import parse_signal


def _table(path):
    """20 Hz rows of a drive north-east at about 2 m/s with its positions as GNSS_Lat/GNSS_Lon [deg]."""
    t = np.arange(0.0, 60.0, 0.05)
    north, east = 2.0 * t * np.cos(0.3), 2.0 * t * np.sin(0.3)
    lat = 56.1 + np.degrees(north / 6371000.0)
    lon = 10.2 + np.degrees(east / (6371000.0 * np.cos(np.radians(56.1))))
    pd.DataFrame({"t": t, "v": 2.0 + 0.1 * np.sin(0.2 * t), "yaw_rate": 0.01 * np.sin(0.3 * t), "GNSS_Lat": lat, "GNSS_Lon": lon}).to_csv(path, index=False)
    return path


def test_missing_positions_name_the_signal_that_maps_them(tmp_path):
    path = _table(tmp_path / "drive.csv")
    _, report = import_recording(path, ImportOptions(signals=[parse_signal("v=v[m/s]"),
                                                              parse_signal("yaw_rate=yaw_rate[rad/s]")]))
    assert "--signal lat=" in report["missing"]["x"] and "--signal lon=" in report["missing"]["y"]
    frame, _ = import_recording(path, ImportOptions(signals=[parse_signal("lat=GNSS_Lat[deg]"),
                                                             parse_signal("lon=GNSS_Lon[deg]")]))
    travelled = np.hypot(np.ptp(frame["x"]), np.ptp(frame["y"]))
    assert abs(travelled - 2.0 * (frame["t"].iloc[-1] - frame["t"].iloc[0])) < 0.05 * travelled
