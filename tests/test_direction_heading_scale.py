"""Direction evidence from a heading or an integrated gyro (measurements.direction.by_heading), on
generated 20 Hz drives with a known truth:

* a gyro written 57.3 times too small (converted from degrees twice, declared rad/s): its integral
  never turns while the course turns by pi in a U-turn; it tells no U-turn from a reversal, so it
  is no evidence, and a forward drive is never named reversing;
* a course-over-ground heading with 0.02 rad of noise at each 20 Hz sample (a truck's receiver):
  its rate read on the course rate's chords follows the course, so a real reversal is named."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from agrobot.api import convert
from agrobot.measurements import LogError

HZ = 20.0
LAT0, LON0 = 57.71, 11.94
SPEED = 5.0


def drive(legs: list[tuple[float, float, float]], seed: int = 3) -> pd.DataFrame:
    """A 20 Hz drive from legs (seconds, signed speed [m/s], yaw rate [rad/s] as a function of
    nothing: constant on the leg; a weave is added on the legs with speed): t, lat, lon, v (signed),
    r (true, ENU), psi (true body heading, ENU)."""
    rng = np.random.default_rng(seed)
    rows, psi, x, y, t = [], 0.0, 0.0, 0.0, 0.0
    for seconds, v, r in legs:
        for _ in range(int(round(seconds * HZ))):
            weave = 0.12 * math.sin(2 * math.pi * t / 8.0) if v != 0 else 0.0
            rate = r + weave
            rows.append((t, x, y, v, rate, psi))
            psi += rate / HZ
            x += v * math.cos(psi) / HZ
            y += v * math.sin(psi) / HZ
            t += 1 / HZ
    d = pd.DataFrame(rows, columns=["t", "x", "y", "v", "r", "psi"])
    d["x"] += rng.normal(0, 0.02, len(d))
    d["y"] += rng.normal(0, 0.02, len(d))
    d["lat"] = LAT0 + np.degrees(d["y"] / 6.371e6)
    d["lon"] = LON0 + np.degrees(d["x"] / (6.371e6 * math.cos(math.radians(LAT0))))
    return d


def test_a_gyro_57_times_too_small_is_no_evidence_of_reversing(tmp_path):
    d = drive([(5, 0.0, 0.0), (50, SPEED, 0.0), (math.pi / 0.2, SPEED, 0.2), (40, SPEED, 0.0), (5, 0.0, 0.0)])
    out = pd.DataFrame({"t": d["t"], "lat": d["lat"], "lon": d["lon"], "v": d["v"],
                        "yaw_rate": d["r"] * math.pi / 180})          # rad/s converted once more
    out.to_csv(tmp_path / "truck.csv", index=False, float_format="%.10f")
    rec = convert(tmp_path / "truck.csv", signals=["v=v[m/s]", "yaw_rate=yaw_rate[rad/s]", "lat=lat[deg]",
                                                   "lon=lon[deg]"], time="t[s]", wheelbase=4.0)
    assert not [f for f in rec.report["audit"]["findings"] if f["kind"] == "reversing"]


def test_a_noisy_20_hz_heading_names_the_reversal(tmp_path):
    legs = [(5, 0.0, 0.0), (40, SPEED, 0.0), (3, 0.0, 0.0), (20, -2.0, 0.0), (3, 0.0, 0.0), (40, SPEED, 0.0),
            (5, 0.0, 0.0)]
    d = drive(legs)
    noise = np.random.default_rng(7).normal(0, 0.02, len(d))
    compass = np.mod(math.pi / 2 - d["psi"] + noise, 2 * math.pi)      # clockwise from north, as receivers write it
    out = pd.DataFrame({"t": d["t"], "lat": d["lat"], "lon": d["lon"], "v": d["v"].abs(), "heading": compass})
    out.to_csv(tmp_path / "truck.csv", index=False, float_format="%.10f")
    with pytest.raises(LogError, match="reverses at") as err:
        convert(tmp_path / "truck.csv", signals=["v=v[m/s]", "heading=heading[rad]", "lat=lat[deg]", "lon=lon[deg]"],
                time="t[s]", wheelbase=4.0)
    said = str(err.value).split("reverses at ")[1].split(" s")[0]
    start, end = (float(x) for x in said.split("-"))
    back = d["t"][d["v"] < 0]          # named from standstill to standstill: within the 3 s stops around it
    assert back.min() - 3.5 < start <= back.min() + 0.5 and back.max() - 0.5 <= end < back.max() + 3.5, \
        (said, back.min(), back.max())
    assert "the course against the heading" in str(err.value)


@pytest.mark.parametrize("factor", [1.0, math.pi / 180])
def test_a_20_hz_course_rate_is_read_over_chords_not_per_fix(tmp_path, factor):
    """Fixes at 20 Hz with 5 cm of noise each: the course rate differenced per fix is mostly noise
    (the gyro pair 'too weak to judge'); over 0.25 s either side it follows the gyro, which then
    agrees in scale, or is named 57.3 times too small (a yaw rate converted from degrees twice)."""
    d = drive([(5, 0.0, 0.0), (120, 6.0, 0.0), (5, 0.0, 0.0)])
    rng = np.random.default_rng(1)
    lat = d["lat"] + np.degrees(rng.normal(0, 0.05, len(d)) / 6.371e6)
    lon = d["lon"] + np.degrees(rng.normal(0, 0.05, len(d)) / (6.371e6 * math.cos(math.radians(LAT0))))
    pd.DataFrame({"t": d["t"], "lat": lat, "lon": lon, "v": d["v"], "yaw_rate": d["r"] * factor}).to_csv(
        tmp_path / "truck.csv", index=False, float_format="%.10f")
    rec = convert(tmp_path / "truck.csv", signals=["v=v[m/s]", "yaw_rate=yaw_rate[rad/s]", "lat=lat[deg]",
                                                   "lon=lon[deg]"], time="t[s]", wheelbase=4.0)
    pair = [f for f in rec.report["audit"]["findings"] if "course_rate" in f["channels"]]
    latency = [f for f in pair if f["kind"] == "sensor_latency"]
    assert latency and "too weak" not in latency[0]["meaning"], latency
    scale = [f for f in pair if f["kind"] == "scale_disagreement"]
    if factor == 1.0:
        assert not scale, scale
    else:
        assert len(scale) == 1 and abs(scale[0]["value"] / factor - 1) < 0.1 and "degrees/radians" in scale[0]["meaning"]


def test_a_noisy_20_hz_compass_heading_is_turned_to_enu(tmp_path):
    """A compass heading (clockwise from north) with 0.02 rad of noise a sample at 20 Hz: its sense
    is read against the course on the same chords, so the log's heading is pi/2 - heading, the
    truth's ENU yaw angle, and the report says it was judged by the track."""
    d = drive([(5, 0.0, 0.0), (120, SPEED, 0.0), (5, 0.0, 0.0)])
    noise = np.random.default_rng(11).normal(0, 0.02, len(d))
    compass = np.mod(math.pi / 2 - d["psi"] + noise, 2 * math.pi)
    pd.DataFrame({"t": d["t"], "lat": d["lat"], "lon": d["lon"], "v": d["v"], "heading": compass}).to_csv(
        tmp_path / "truck.csv", index=False, float_format="%.10f")
    rec = convert(tmp_path / "truck.csv", signals=["v=v[m/s]", "heading=heading[rad]", "lat=lat[deg]", "lon=lon[deg]"],
                  time="t[s]", wheelbase=4.0)
    said = rec.report["columns"]["heading"]
    assert "clockwise from north" in said and "by its turns against the course" in said, said
    log = rec.log
    t0 = rec.report["used"]["start"]
    psi = np.interp(log["t"].to_numpy() + t0, d["t"], d["psi"])
    err = np.angle(np.exp(1j * (log["heading"].to_numpy() - psi)))
    assert np.median(np.abs(err)) < 0.05, np.median(np.abs(err))


def wandering(n: int, sigma: float, tau: float, rng) -> np.ndarray:
    """A receiver's position wander: first-order autoregressive noise of std ``sigma`` [m] and
    correlation time ``tau`` [s] at 20 Hz (slower than the scale's 2 s averaging removes)."""
    a = math.exp(-1 / (HZ * tau))
    e = rng.normal(0, sigma * math.sqrt(1 - a * a), n)
    x = np.zeros(n)
    for i in range(1, n):
        x[i] = a * x[i - 1] + e[i]
    return x


@pytest.mark.parametrize("factor", [1.0, math.pi / 180])
def test_a_course_rate_noisier_than_the_gyro_shrinks_no_scale_into_a_disagreement(tmp_path, factor):
    """Fixes wandering 0.2 m over 1 s: the gyro regressed on the course rate reads about 0.87 of its
    true scale (the course's noise shrinks the slope), the course rate on the gyro about 1.01. A gyro
    true to its unit is no scale disagreement; one 57.3 times too small is named a degrees/radians
    mix-up (the factor lies between the two regressions)."""
    d = drive([(5, 0.0, 0.0), (200, SPEED, 0.0), (5, 0.0, 0.0)])
    rng = np.random.default_rng(1)
    lat = d["lat"] + np.degrees(wandering(len(d), 0.2, 1.0, rng) / 6.371e6)
    lon = d["lon"] + np.degrees(wandering(len(d), 0.2, 1.0, rng) / (6.371e6 * math.cos(math.radians(LAT0))))
    pd.DataFrame({"t": d["t"], "lat": lat, "lon": lon, "v": d["v"], "yaw_rate": d["r"] * factor}).to_csv(
        tmp_path / "truck.csv", index=False, float_format="%.10f")
    rec = convert(tmp_path / "truck.csv", signals=["v=v[m/s]", "yaw_rate=yaw_rate[rad/s]", "lat=lat[deg]",
                                                   "lon=lon[deg]"], time="t[s]", wheelbase=4.0)
    scale = [f for f in rec.report["audit"]["findings"]
             if f["kind"] == "scale_disagreement" and "course_rate" in f["channels"]]
    if factor == 1.0:
        assert not scale, scale
    else:
        assert len(scale) == 1 and "degrees/radians" in scale[0]["meaning"], scale


def test_no_scale_is_named_on_a_second_of_course(tmp_path):
    """Fixes wandering 0.15 m each at 20 Hz: the course is read (chords of 40 sigmas) on about 1 s of
    the drive; a gyro true to its unit gets no scale disagreement from so little."""
    d = drive([(5, 0.0, 0.0), (120, 6.0, 0.0), (5, 0.0, 0.0)])
    rng = np.random.default_rng(1)
    lat = d["lat"] + np.degrees(rng.normal(0, 0.15, len(d)) / 6.371e6)
    lon = d["lon"] + np.degrees(rng.normal(0, 0.15, len(d)) / (6.371e6 * math.cos(math.radians(LAT0))))
    pd.DataFrame({"t": d["t"], "lat": lat, "lon": lon, "v": d["v"], "yaw_rate": d["r"]}).to_csv(
        tmp_path / "truck.csv", index=False, float_format="%.10f")
    rec = convert(tmp_path / "truck.csv", signals=["v=v[m/s]", "yaw_rate=yaw_rate[rad/s]", "lat=lat[deg]",
                                                   "lon=lon[deg]"], time="t[s]", wheelbase=4.0)
    assert not [f for f in rec.report["audit"]["findings"] if f["kind"] == "scale_disagreement"]
