"""A table of a receiver's fixes with its own speed over ground (``--signal gnss_speed=...``) and a
heading: the speed is the fixes' speed, as a receiver's sentences carry theirs, so the stops are
where it says the machine stands. A standing machine whose fix wanders back 8 m over 5 s (a phone
receiver at a traffic light) is not driving, so not reversing: the import is not refused, and the
log holds the receiver's speed as gnss_speed, not the track's chords as track_speed."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

from agrobot.measurements.recording import ImportOptions, import_recording

R = 6.371e6
LAT0, LON0 = 53.1, 8.85


def _ride(root, seed: int = 3):
    """1 Hz fixes: 150 s riding at 4 m/s weaving (heading clockwise from north), 50 s standing with
    the fix drifting 8 m backwards between 160 and 165 s, 200 s riding again."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 400.0, 1.0)
    standing = (t >= 150) & (t < 200)
    speed = np.where(standing, 0.0, 4.0)
    heading = 0.5 * np.sin(2 * np.pi * t / 40.0)
    heading[standing] = heading[np.flatnonzero(standing)[0] - 1]
    east = np.concatenate([[0.0], np.cumsum(speed[:-1] * np.sin(heading[:-1]))])
    north = np.concatenate([[0.0], np.cumsum(speed[:-1] * np.cos(heading[:-1]))])
    drift = np.clip((t - 160.0) / 5.0, 0.0, 1.0) * 8.0 * standing      # backwards, against the heading
    east, north = east - drift * np.sin(heading), north - drift * np.cos(heading)
    east, north = east + rng.normal(0, 0.05, len(t)), north + rng.normal(0, 0.05, len(t))
    root.mkdir()
    pd.DataFrame({"t": t, "lat": LAT0 + np.degrees(north / R),
                  "lon": LON0 + np.degrees(east / (R * math.cos(math.radians(LAT0)))),
                  "speed": speed, "course": np.degrees(heading) % 360.0}).to_csv(root / "fixes.csv", index=False)
    return root / "fixes.csv"


def test_a_wandering_fix_at_a_standstill_is_not_reversing(tmp_path):
    path = _ride(tmp_path / "ride")
    options = ImportOptions(signals=["lat=lat[deg]", "lon=lon[deg]", "gnss_speed=speed[m/s]", "heading=course[deg]"],
                            time="t[s]", time_range=(0.0, 399.0))
    log, report = import_recording(path, options)
    assert "gnss_speed" in log and "track_speed" not in log
    assert not [f for f in report["audit"]["findings"] if f["kind"] == "reversing"]
    standing = (log["t"] - log["t"].iloc[0] >= 150) & (log["t"] - log["t"].iloc[0] < 200)
    assert float(log.loc[standing, "gnss_speed"].abs().max()) < 0.05


def test_a_receivers_no_value_speed_is_left_out(tmp_path):
    """A phone writes -1 where it has no speed: a speed over ground is never negative, so the log's
    gnss_speed there is interpolated from its neighbours (4 m/s), not -1."""
    path = _ride(tmp_path / "ride")
    table = pd.read_csv(path)
    table.loc[60:62, "speed"] = -1.0
    table.to_csv(path, index=False)
    options = ImportOptions(signals=["lat=lat[deg]", "lon=lon[deg]", "gnss_speed=speed[m/s]", "heading=course[deg]"],
                            time="t[s]", time_range=(0.0, 399.0))
    log, _ = import_recording(path, options)
    assert float(log["gnss_speed"].min()) >= 0.0
    near = (log["t"] - log["t"].iloc[0] - 61.0).abs() < 2.0
    assert np.allclose(log.loc[near, "gnss_speed"], 4.0, atol=0.2)


def test_the_no_value_speeds_left_out_are_said(tmp_path):
    """The -1 values left out of the receiver's speed are counted in the report's notes (a choice
    that changes the log's gnss_speed there is said), and none is said where there are none."""
    path = _ride(tmp_path / "ride")
    options = ImportOptions(signals=["lat=lat[deg]", "lon=lon[deg]", "gnss_speed=speed[m/s]", "heading=course[deg]"],
                            time="t[s]", time_range=(0.0, 399.0))
    _, clean = import_recording(path, options)
    table = pd.read_csv(path)
    table.loc[60:62, "speed"] = -1.0
    table.to_csv(path, index=False)
    _, report = import_recording(path, options)
    said = [n for n in report["notes"] if "gnss_speed" in n and "negative" in n]
    assert len(said) == 1 and "3 negative" in said[0]
    assert not [n for n in clean["notes"] if "gnss_speed" in n and "negative" in n]
