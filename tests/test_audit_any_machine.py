"""Properties the import audit must hold on any machine's recording, each on generated recordings
with a known truth (harness.quirk_recordings, harness.quirk_drive):

- a receiver's speed and course are correlated with another clock's signals only where its fix
  holds its usual quality (a DGPS stretch's positions are noise, not a signal): GPS time against
  UTC is found on a mower whose fix falls to DGPS or float;
- the GNSS course rate is read wherever its chord is long against the fixes' own noise, not above
  one speed for every machine: a slow machine's gyro clock offset is found on its RTK course;
- a row written late is not a clock step (the return to the sequence after it is no leap);
- the direction is told on chords of DIRECTION_NOISE position sigmas: a reversal inside a DGPS
  stretch is named;
- a machine that steers its wheels cannot turn on the spot: a straight reversal between two short
  stops, which its steering cannot vote on, is named by its course turned by pi;
- an angle that is a rate is judged on the speed signed where the machine reverses.
"""
from __future__ import annotations

import math
import re
import types

import numpy as np
import pandas as pd
import pytest

from agrobot.api import convert
from agrobot.measurements.direction import check_direction
from agrobot.measurements.log import LogError
from agrobot.measurements.time_base import clock_steps
from harness.quirk_drive import EARTH, LAT0, make_drive
from harness.quirk_recordings import LEAP_SECONDS, compose


@pytest.mark.parametrize("seed", [1, 2, 8])
def test_gps_time_is_found_past_the_receivers_degraded_fixes(tmp_path, seed):
    truth = compose(seed, tmp_path, classes=["fix_quality_drop", "leap_seconds"], layout="devices", machine="mower")
    assert truth["planted"]["fix_quality_drop"]["share"]["4"] < 0.95          # a degraded stretch is planted
    found = convert(tmp_path).report["audit"]["alignment"]["found"]
    assert found["gnss"]["late_s"] == pytest.approx(LEAP_SECONDS, abs=0.1)


def test_a_slow_machines_gyro_clock_is_found_on_its_rtk_course(tmp_path):
    checked = 0
    for seed in range(1, 14):
        folder = tmp_path / f"s{seed}"
        truth = compose(seed, folder, classes=["clock_offset"], layout="devices", machine="mower")
        late = truth["planted"]["clock_offset"]
        if late["group"] != "imu":
            continue
        found = convert(folder).report["audit"]["alignment"]["found"]
        assert found["imu"]["late_s"] == pytest.approx(late["late_s"], abs=0.05), seed
        checked += 1
    assert checked >= 4


@pytest.mark.parametrize("seed", range(4))
def test_a_row_written_late_is_no_clock_step(seed):
    """A heading steady where a row is written five rows late (its change across the return to the
    sequence looks like one row's), turning elsewhere; and a true step of 2 s, still found."""
    rng = np.random.default_rng(seed)
    t = 1.7e9 + np.arange(0.0, 60.0, 0.1)
    heading = 40.0 * np.sin(0.05 * (t - t[0])) + 0.1 * rng.standard_normal(len(t))   # deg: steady near 31.4 s
    order = list(range(len(t)))
    order.insert(319, order.pop(314))              # row 314 written five rows late: its stamp 0.5 s back
    stamps, found = clock_steps(t[order], [heading[order]], "late.csv")
    assert found == [] and np.array_equal(stamps, t[order])
    track = 0.5 * (t - t[0]) + 0.3 * np.sin(0.5 * (t - t[0]))
    stepped = np.where(np.arange(len(t)) > 400, t + 2.0, t)
    _, found = clock_steps(stepped, [track], "stepped.csv")
    assert len(found) == 1 and found[0]["finding"]["value"] == pytest.approx(2.0, abs=0.01)


def test_a_reversal_inside_a_dgps_stretch_is_named():
    """A mower backs up at about 0.5 m/s while its fix is DGPS (0.3 m noise); its dual-antenna
    heading stays good: the course (on longer chords) against the heading names the stretch."""
    rng = np.random.default_rng(5)
    drive = make_drive(rng, "mower", 90.0, reversing=1)
    (a, b), = drive.reversing
    t = np.arange(0.0, 90.0, 0.1)
    dgps = (t > a - 3.0) & (t < b + 3.0)
    sigma = np.where(dgps, 0.3, 0.01)
    east = drive.at("east", t) + sigma * rng.standard_normal(len(t))
    north = drive.at("north", t) + sigma * rng.standard_normal(len(t))
    gnss = pd.DataFrame({"utc": 1.7e9 + t, "lat": LAT0 + np.degrees(north / EARTH),
                         "lon": 5.0 + np.degrees(east / (EARTH * math.cos(math.radians(LAT0)))),
                         "quality": np.where(dgps, 2.0, 4.0), "speed": np.abs(drive.at("v", t)),
                         "heading": drive.at("psi", t) + np.radians(0.2) * rng.standard_normal(len(t))})
    streams = types.SimpleNamespace(gnss=gnss, signals={}, report={})
    with pytest.raises(LogError) as refused:
        check_direction(streams, types.SimpleNamespace(sign_speed=False), "dgps.nmea", 1.7e9)
    said = [float(x) for x in re.findall(r"(\d+\.\d)-(\d+\.\d) s", str(refused.value))[0]]
    back = drive.t[drive.v < 0]
    assert said == pytest.approx([back[0], back[-1]], abs=1.0)


def test_a_straight_reversal_told_by_steering_alone_is_named():
    """No gyro, no heading: a machine that steers its wheels drives a winding path, stops, backs up
    8 s straight (the wheels at zero: the steering votes on nothing), stops and drives on. Its
    course turned by pi across both short stops names the stretch: it cannot turn on the spot."""
    h, L = 0.05, 1.2
    t = np.arange(0.0, 60.0, h)
    a, b = 20.0, 29.0                                                  # the reversal, stop to stop
    ramp = np.clip(np.minimum(np.abs(t - a), np.abs(t - b)) / 0.5, 0.0, 1.0)     # 0.5 s to and from rest
    back = (t > a) & (t < b)
    v = np.where(back, -0.6, 1.2) * ramp
    delta = np.where(back, 0.0, 0.25 * np.sin(0.4 * t))
    psi = np.cumsum(v * np.tan(delta) / L) * h
    east, north = np.cumsum(v * np.cos(psi)) * h, np.cumsum(v * np.sin(psi)) * h
    rng = np.random.default_rng(4)
    east, north = east + 0.01 * rng.standard_normal(len(t)), north + 0.01 * rng.standard_normal(len(t))
    gnss = pd.DataFrame({"utc": 1.7e9 + t, "lat": LAT0 + np.degrees(north / EARTH),
                         "lon": 5.0 + np.degrees(east / (EARTH * math.cos(math.radians(LAT0)))),
                         "quality": 4.0, "speed": np.nan})
    streams = types.SimpleNamespace(gnss=gnss, signals={"delta": (1.7e9 + t, delta), "v": (1.7e9 + t, np.abs(v))},
                                    report={})
    with pytest.raises(LogError) as refused:
        check_direction(streams, types.SimpleNamespace(sign_speed=False), "straight.csv", 1.7e9)
    said = [tuple(map(float, x)) for x in re.findall(r"(\d+\.\d)-(\d+\.\d) s", str(refused.value))]
    assert len(said) == 1 and said[0] == pytest.approx((a, b), abs=1.0)


def test_an_angle_that_is_a_rate_is_named_in_a_recording_that_reverses(tmp_path):
    """The wheel angle's column holds its rate, in recordings that back up with an unsigned speed:
    judged on the speed signed where the machine reverses (--sign-speed), it is named."""
    checked = 0
    for seed in range(12):
        folder = tmp_path / f"s{seed}"
        truth = compose(seed, folder, classes=["reversing_unsigned", "mislabelled_channel"], layout="table")
        if truth["planted"]["mislabelled_channel"]["channel"] != "delta":
            continue
        found = [f for f in convert(folder, sign_speed=True).report["audit"]["findings"]
                 if f["kind"] == "mislabelled_channel"]
        assert [f["channels"] for f in found] == [["delta"]], seed
        checked += 1
    assert checked >= 3
