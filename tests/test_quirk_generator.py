"""The quirk generator (harness.quirk_recordings) plants what its truth says: each check reads the
written files back with the csv module and numpy, never with the generator's own code, and
measures the quirk independently (update rates from value changes, the course from the written
positions, gaps and step-backs from the written stamps, a clock offset by cross-correlation)."""
from __future__ import annotations

import csv
import math
import re

import numpy as np
import pytest

from harness.quirk_recordings import CLASSES, LAYOUTS, ORDER, compatible, compose

LAT0 = 52.0


def read(path) -> dict[str, np.ndarray]:
    """A written CSV as {column: values} (quoted rows unwrapped, a units row skipped, blanks NaN)."""
    lines = [line.strip() for line in open(path)]
    lines = [line[1:-1] if line.startswith('"') and line.endswith('"') else line for line in lines]
    rows = list(csv.reader(lines))
    header, body = rows[0], rows[1:]
    if body and not _number(body[0][0]):
        body = body[1:]
    out = {}
    for i, name in enumerate(header):
        cells = [r[i] for r in body]
        out[name] = np.array([float(c) if _number(c) else (math.nan if c == "" else c) for c in cells], dtype=object)
        if all(isinstance(x, float) for x in out[name]):
            out[name] = out[name].astype(float)
    return out


NUMERIC = re.compile(r"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*$")


def _number(text: str) -> bool:
    return bool(NUMERIC.match(text))


def course_and_speed(g: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t, course [rad, ENU], speed [m/s]) of written positions by central differences."""
    t = g["t"] - g["t"][0]
    north = np.radians(g["lat"] - LAT0) * 6_371_000.0
    east = np.radians(g["lon"] - 5.0) * 6_371_000.0 * math.cos(math.radians(LAT0))
    ve, vn = np.gradient(east, t), np.gradient(north, t)
    return t, np.arctan2(vn, ve), np.hypot(ve, vn)


def test_a_held_channel_updates_at_the_stated_rate(tmp_path):
    truth = compose(11, tmp_path, classes=["held_channel"], layout="table")
    held = truth["planted"]["held_channel"]
    log = read(tmp_path / "log.csv")
    duration = log["t"][-1] - log["t"][0]
    for column in held["columns"]:
        changes = np.count_nonzero(np.diff(log[column]) != 0)
        assert changes / duration == pytest.approx(held["update_hz"], rel=0.05), column
    other = next(c for c in ("delta_cmd", "yaw_rate", "delta") if c not in held["columns"])
    assert np.count_nonzero(np.diff(log[other]) != 0) / duration == pytest.approx(20.0, rel=0.02)


def test_the_reversing_stretches_course_is_opposite_the_heading(tmp_path):
    truth = compose(12, tmp_path, classes=["reversing_unsigned", "heading_no_gyro"], layout="table")
    log = read(tmp_path / "log.csv")
    assert np.all(log["v"] >= 0)                          # the speed written unsigned
    t, course, speed = course_and_speed(log)
    heading = math.pi / 2 - np.radians(log["heading"])    # compass degrees -> ENU
    diff = np.degrees(np.abs(np.angle(np.exp(1j * (course - heading)))))
    stretches = truth["planted"]["reversing_unsigned"]["stretches"]
    assert stretches
    inside = np.zeros(len(t), bool)
    for a, b in stretches:
        inside |= (t > a + 1.0) & (t < b - 1.0)
    moving = speed > 0.3
    assert np.median(diff[inside & moving]) > 170.0
    near = np.zeros(len(t), bool)
    for a, b in stretches:
        near |= (t > a - 2.0) & (t < b + 2.0)
    assert np.median(diff[~near & moving]) < 10.0


def test_the_units_row_is_present_and_the_values_are_in_its_units(tmp_path):
    truth = compose(13, tmp_path, classes=["units_row"], layout="table", machine="utility")
    rows = [line.rstrip("\n").split(",") for line in open(tmp_path / "log.csv")][:2]
    units = dict(zip(rows[0], rows[1]))
    assert units["yaw_rate"] == "deg/s" and units["delta"] == "deg" and units["v"] == "km/h"
    assert units["t"] == truth["planted"]["units_row"]["time_unit"]
    log = read(tmp_path / "log.csv")
    drive = truth["drive"]
    t = log["t"] - log["t"][0]
    assert np.percentile(np.abs(log["v"]), 90) / np.percentile(np.abs(drive.at("v", t)), 90) == pytest.approx(3.6, rel=0.02)


def test_dropouts_duplicates_and_rows_out_of_order_are_counted_as_written(tmp_path):
    truth = compose(14, tmp_path, classes=["channel_dropouts", "duplicate_stamps", "out_of_order"], layout="table")
    log = read(tmp_path / "log.csv")
    p = truth["planted"]
    t = np.sort(log["t"])
    stamps = t[np.isfinite(log[p["channel_dropouts"]["channel"]][np.argsort(log["t"], kind="stable")])]
    steps = np.diff(np.unique(stamps))
    gaps = steps[steps > 1.5 / 20.0]
    assert len(gaps) == p["channel_dropouts"]["count"]
    assert gaps.max() == pytest.approx(p["channel_dropouts"]["longest_s"], abs=1e-3)
    assert np.count_nonzero(np.diff(t) == 0) == p["duplicate_stamps"]["count"]
    assert np.count_nonzero(np.diff(log["t"]) < 0) == p["out_of_order"]["count"]


def test_a_late_device_is_late_by_its_truth_against_the_receivers_course(tmp_path):
    truth = compose(15, tmp_path, classes=["clock_offset"], layout="devices", machine="utility")
    late = truth["planted"]["clock_offset"]
    g, imu, veh = (read(tmp_path / f"{n}.csv") for n in ("gnss", "imu", "vehicle"))
    t, course, speed = course_and_speed(g)
    rate = np.gradient(np.unwrap(course), t)
    start = g["t"][0]
    grid = np.arange(10.0, 80.0, 0.01)
    if late["group"] == "imu":
        ref, other = np.interp(grid, t, rate), (imu["t"] - start, imu["yaw_rate"])
    else:
        ref, other = np.interp(grid, t, speed), (veh["t"] - start, veh["v"])
    lags = np.arange(-1.2, 1.2, 0.01)
    rho = [np.corrcoef(ref, np.interp(grid + lag, *other))[0, 1] for lag in lags]
    assert lags[int(np.argmax(rho))] == pytest.approx(late["late_s"], abs=0.03)


def test_quoted_rows_and_a_clean_recording(tmp_path):
    compose(16, tmp_path / "q", classes=["quoted_rows"], layout="devices")
    for name in ("gnss", "imu", "vehicle"):
        lines = open(tmp_path / "q" / f"{name}.csv").read().splitlines()
        assert all(line.startswith('"') and line.endswith('"') and line.count('"') == 2 for line in lines)
    truth = compose(16, tmp_path / "c", classes=[], layout="table")
    assert truth["planted"] == {} and truth["classes"] == []
    log = read(tmp_path / "c" / "log.csv")
    assert set(log) == {"t", "lat", "lon", "fix_quality", "v", "yaw_rate", "delta_cmd", "delta"}
    assert np.all(log["fix_quality"] == 4.0) and np.all(np.diff(log["t"]) > 0)


def test_compositions_are_deterministic_and_compatible(tmp_path):
    a = compose(17, tmp_path / "a")
    b = compose(17, tmp_path / "b")
    assert a["classes"] == b["classes"] and a["planted"] == b["planted"]
    for name in (p.split("/")[-1] for p in a["files"]):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    seen = set()
    for seed in range(25):
        truth = compose(100 + seed, tmp_path / f"s{seed}")
        assert compatible(truth["classes"], truth["layout"]) and truth["classes"]
        seen.update(truth["classes"])
    assert len(CLASSES) >= 14 and set(ORDER) == set(CLASSES) and len(seen) >= 14
    with pytest.raises(ValueError, match="do not fit"):
        compose(1, tmp_path / "x", classes=["one_clock_weak"], layout="devices")
    assert set(LAYOUTS) == {"table", "devices", "nmea"}


def _checksum_ok(line: str) -> bool:
    body, _, given = line[1:].partition("*")
    x = 0
    for ch in body:
        x ^= ord(ch)
    return f"{x:02X}" == given.strip()


def test_an_nmea_recording_reverses_against_its_heading_and_carries_its_bad_checksums(tmp_path):
    truth = compose(18, tmp_path, classes=["reversing_unsigned", "nmea_checksum"], layout="nmea", machine="utility")
    lines = (tmp_path / "gnss.nmea").read_text().splitlines()
    assert sum(not _checksum_ok(line) for line in lines) == truth["planted"]["nmea_checksum"]["count"]
    rmc = [line.split(",") for line in lines if line.startswith("$GPRMC")]
    hdt = [float(line.split(",")[1]) for line in lines if line.startswith("$GPHDT")]
    t = np.array([int(f[1][:2]) * 3600 + int(f[1][2:4]) * 60 + float(f[1][4:]) for f in rmc]) - 8 * 3600
    speed, course = np.array([float(f[7]) for f in rmc]), np.array([float(f[8]) for f in rmc])
    diff = np.abs((course - np.array(hdt) + 180.0) % 360.0 - 180.0)
    inside = np.zeros(len(t), bool)
    for a, b in truth["planted"]["reversing_unsigned"]["stretches"]:
        inside |= (t > a + 0.5) & (t < b - 0.5)
    assert inside.any() and np.all(speed >= 0)
    assert np.median(diff[inside & (speed > 0.5)]) > 170.0 and np.median(diff[~inside & (speed > 0.5)]) < 5.0


def test_the_steering_maps_turn_the_wheels_as_their_truth_says():
    from harness.steering_maps import reading, wheel_angle

    wheels = np.linspace(-0.4, 0.4, 81)
    left = wheels > 0
    r = reading(wheels, asymmetry=0.2)
    assert np.allclose(r[left] * 1.2, wheels[left]) and np.allclose(r[~left] * 0.8, wheels[~left])
    assert np.allclose(reading(wheels, gain=1.25) * 1.25, wheels)
    assert np.allclose(reading(wheels, offset=0.04) + 0.04, wheels)
    d = reading(wheels, curvature=2.0)
    assert np.allclose(d * (1 + 2.0 * d ** 2), wheels, atol=1e-9)
    planted = dict(gain=0.85, asymmetry=-0.15, curvature=1.5, offset=0.035)      # the forward map undoes it
    assert np.allclose(wheel_angle(reading(wheels, **planted), **planted), wheels, atol=1e-9)
    assert np.allclose(reading(wheel_angle(wheels, **planted), **planted), wheels, atol=1e-9)
    assert np.allclose(wheel_angle(0.3, **planted), 0.85 * 0.3 * 0.85 * (1 + 1.5 * 0.09) + 0.035)
