"""Recordings composed of quirk classes at random, each quirk written with its truth, as real files
that ``agrobot convert`` (agrobot.api.convert) reads: the generalisation benchmark's input
(benchmarks/quirk_composition.py) and its tests' (tests/test_quirk_generator.py).

The truth is a drive of harness.quirk_drive (a kinematic Ackermann machine: mower, utility vehicle
or tractor). Its channels are written as a logger writes them, in one of two layouts:

- ``table``: one CSV, one row one clock, 20 Hz rows: t, lat, lon, fix_quality, v, yaw_rate,
  delta_cmd, delta (and heading, mode, yaw_rate_2 where a class adds them);
- ``devices``: one CSV per device on its own stamps: gnss.csv (10 Hz: t, lat, lon, fix_quality),
  imu.csv (50 Hz: t, yaw_rate), vehicle.csv (20 Hz: t, delta_cmd, delta, v);
- ``nmea``: a dual-antenna receiver's gnss.nmea at 10 Hz: GGA (position, fix quality), RMC (speed
  and course over ground, the date), HDT (heading).

Values are SI in the log's convention (rad, rad/s, m/s) unless a class says otherwise; t is POSIX
seconds. A clean recording has noise only (positions 1 cm, yaw rate 0.003 rad/s, speed 0.01 m/s,
wheel angle 0.002 rad).

The classes (CLASSES), each planting one quirk and returning its truth (the number a benchmark
checks the audit named):

- from a small autonomous Ackermann machine's logs (a converted mower): ``reversing_unsigned``
  (backs up 8-12 s once or twice, the speed written unsigned: truth the stretches), ``held_channel``
  (one channel updated 2 or 4 times slower than its rows, sample and hold: truth its update rate),
  ``one_clock_weak`` (one CSV, noisy slow channels whose correlations are weak: truth no offset; a
  realignment is wrong), ``units_row`` (a row of units under the header, values in deg, deg/s,
  km/h as it declares: truth the units), ``quoted_rows`` (every row one quoted field),
  ``fix_quality_drop`` (RTK fixed falling to DGPS 2 or float 5 for 5-15 s: truth the stretches),
  ``mode_stretches`` (auto / manual / paused in a mode column; by hand the wheels follow the
  driver, not the command: truth the stretches), ``heading_no_gyro`` (no gyro, a dual-antenna
  heading in degrees clockwise from north);
- from a by-wire vehicle's and a terminal's recordings: ``clock_offset`` (a device's stamps
  0.3-0.9 s late), ``channel_dropouts`` (one channel's 5-15 gaps of 0.2-0.7 s: truth count and
  longest), ``raw_units`` (a gyro in deg/s or a speed in km/h with no unit: truth the factor),
  ``two_yaw_sources`` (a second gyro off by 7-15 % in scale), ``mislabelled_channel`` (an
  accelerometer's vertical axis as the gyro, or the wheel angle's rate as the angle);
- from the issue trackers of log tools: ``leap_seconds`` (the receiver's file on GPS time, 18 s
  ahead of UTC: https://github.com/tomojitakasu/RTKLIB/issues/501,
  https://github.com/ArduPilot/UAVLogViewer/pull/308), ``gps_week_rollover`` (the receiver's dates
  1024 weeks early: https://github.com/openvehicles/Open-Vehicle-Monitoring-System-3/issues/284,
  https://github.com/mikalhart/TinyGPSPlus/issues/75), ``duplicate_stamps`` (rows written twice
  with one stamp, some with the next values: https://github.com/stereolabs/zed-ros-wrapper/issues/577,
  https://github.com/carla-simulator/ros-bridge/issues/51), ``out_of_order`` (rows written later
  than their stamps' place: https://github.com/ros/ros_comm/issues/952), ``clock_jump`` (the
  logger's clock stepped by 1-3 s either way mid-recording, as NTP does:
  https://github.com/microsoft/gctoolkit/issues/127, https://github.com/juju/juju/pull/3941),
  ``decimal_commas`` (fields by ';', numbers as 1,5, a spreadsheet's European-locale CSV:
  https://github.com/nyetwurk/ecuxplot/issues/14: truth the columns per file holding one),
  ``two_talkers`` (each NMEA epoch's GGA from GN, the combined solution, and GP, a GPS-only one
  0.3-0.8 m off, in one order: https://github.com/projecthorus/chasemapper/pull/37: truth the
  epochs both give and that GN holds the recording's positions).

A composition is a seeded random subset of compatible classes (each class names the layouts it
fits and the classes it excludes) planted on one drive; ``compose`` writes it to a folder and
returns its truth.
"""
from __future__ import annotations

import csv
import datetime
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from harness.generated_recordings import sentence
from harness.quirk_drive import EARTH, LAT0, MACHINES, Drive, make_drive

START = 1_777_622_400.0             # POSIX s: 2026-05-01 08:00 UTC, the drive's t = 0
WEEK_ROLLOVER = 1024 * 7 * 86400.0  # s: a 10-bit GPS week counter's period
LEAP_SECONDS = 18.0                 # s: GPS time ahead of UTC since 2017
LAYOUTS = ("table", "devices", "nmea")
CSV = ("table", "devices")
SHEET_RATES = {"log": 20.0, "gnss": 10.0, "imu": 50.0, "vehicle": 20.0, "imu2": 40.0}
NOISE = {"position": 0.01, "yaw_rate": 0.003, "v": 0.01, "delta": 0.002, "delta_cmd": 0.0}


@dataclass
class Sheet:
    """One file's rows: its stamps (POSIX s) and columns (numbers, NaN for a blank, or text), the
    units row it would carry, how its time is written (posix | datetime)."""

    name: str
    t: np.ndarray
    columns: dict
    units: dict = field(default_factory=dict)
    time_format: str = "posix"

    @property
    def rate(self) -> float:
        return SHEET_RATES[self.name]


@dataclass
class Recording:
    """A composition under construction and, once written, its files and truth."""

    seed: int
    layout: str
    machine: str
    classes: list
    drive: Drive | None = None
    sheets: dict = field(default_factory=dict)
    planted: dict = field(default_factory=dict)
    taken: set = field(default_factory=set)            # channels a class has changed
    signals: list | None = None                        # the --signal mapping a user gives, where one is needed
    quoted: bool = False
    units_row: bool = False
    decimal_comma: bool = False                        # fields by ';', numbers as 1,5 (a European locale)
    talkers: tuple = ()                                # NMEA: a second talker's GGA each epoch (GP beside GN)
    noise: dict = field(default_factory=lambda: dict(NOISE))
    files: list = field(default_factory=list)
    written: dict = field(default_factory=dict)       # per file: rows, stamps stepping back, repeated stamps
    corrupt: set = field(default_factory=set)          # NMEA: the rows whose GGA is corrupted

    def holder(self, column: str) -> Sheet | None:
        return next((s for s in self.sheets.values() if column in s.columns), None)

    def truth(self) -> dict:
        """What a benchmark checks against: the composition and each planted class's truth."""
        return {"seed": self.seed, "layout": self.layout, "machine": self.machine,
                "wheelbase": MACHINES[self.machine]["wheelbase"], "classes": list(self.classes),
                "planted": self.planted, "files": [str(p) for p in self.files], "signals": self.signals,
                "written": self.written, "drive": self.drive}


@dataclass
class QuirkClass:
    """A class of quirk: its stage (drive: before the drive is made; channel: on the columns;
    file: on the stamps and rows; text: on the written text), the layouts it fits, the classes it
    cannot share a recording with, and its planting function (recording, rng) -> truth."""

    name: str
    stage: str
    layouts: tuple
    excludes: tuple
    plant: Callable


CLASSES: dict[str, QuirkClass] = {}
CLOCKS = ("clock_offset", "leap_seconds", "gps_week_rollover", "clock_jump")


def quirk(stage: str, layouts=CSV, excludes=()):
    def register(fn):
        name = fn.__name__.removeprefix("plant_")
        CLASSES[name] = QuirkClass(name, stage, tuple(layouts), tuple(excludes), fn)
        return fn
    return register


# --- the channels --------------------------------------------------------------------------------
def _sampled(drive: Drive, rng, name: str, t: np.ndarray, noise: dict) -> dict:
    """The columns of a sheet at stamps ``t`` (from 0) with their noise."""
    out = {}
    if name in ("log", "gnss"):
        e = drive.at("east", t) + noise["position"] * rng.standard_normal(len(t))
        n = drive.at("north", t) + noise["position"] * rng.standard_normal(len(t))
        out["lat"] = LAT0 + np.degrees(n / EARTH)
        out["lon"] = 5.0 + np.degrees(e / (EARTH * math.cos(math.radians(LAT0))))
        out["fix_quality"] = np.full(len(t), 4.0)
    if name in ("log", "vehicle"):
        for c in ("delta_cmd", "delta", "v"):
            out[c] = drive.at(c, t) + noise[c] * rng.standard_normal(len(t))
    if name in ("log", "imu"):
        out["yaw_rate"] = drive.at("yaw_rate", t) + noise["yaw_rate"] * rng.standard_normal(len(t))
    return out


def build_sheets(rec: Recording, rng, duration: float) -> None:
    """The layout's sheets of the drive, clean."""
    names = {"table": ("log",), "devices": ("gnss", "imu", "vehicle"), "nmea": ("gnss",)}[rec.layout]
    for name in names:
        t = np.arange(0.0, duration - 1e-9, 1.0 / SHEET_RATES[name])
        rec.sheets[name] = Sheet(name, t, _sampled(rec.drive, rng, name, t, rec.noise))
    if rec.layout == "nmea":                 # a dual-antenna receiver: heading, speed and course over ground
        s, d = rec.sheets["gnss"], rec.drive
        psi, v = d.at("psi", s.t), d.at("v", s.t)
        s.columns["heading"] = np.mod(90.0 - np.degrees(psi) + 0.2 * rng.standard_normal(len(s.t)), 360.0)
        s.columns["speed"] = np.abs(v)
        s.columns["course"] = np.mod(90.0 - np.degrees(np.where(v < 0, psi + math.pi, psi)), 360.0)


# --- drive-stage classes -----------------------------------------------------------------------------
@quirk("drive", layouts=LAYOUTS)
def plant_reversing_unsigned(rec: Recording, rng) -> dict:
    """Stretches backing up, the speed written unsigned (the course opposite the heading there)."""
    rec.planted["reversing_unsigned"] = {"count": int(rng.integers(1, 3))}
    return rec.planted["reversing_unsigned"]


@quirk("drive")
def plant_mode_stretches(rec: Recording, rng) -> dict:
    rec.planted["mode_stretches"] = {}
    return rec.planted["mode_stretches"]


def drive_for(rec: Recording, rng, duration: float) -> Drive:
    back = rec.planted.get("reversing_unsigned", {}).get("count", 0)
    modes = "mode_stretches" in rec.planted
    return make_drive(rng, rec.machine, duration, reversing=back, manual=int(modes), paused=int(modes))


def negative(t: np.ndarray, v: np.ndarray) -> list:
    """[start, end] of each stretch where v < 0 (backing up), in s."""
    edges = np.diff(np.concatenate(([0], (v < 0).astype(int), [0])))
    return [[float(t[a]), float(t[b - 1])] for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1))]


def finish_drive_classes(rec: Recording) -> None:
    """What the drive-stage classes write into the columns, and their truth's times."""
    d = rec.drive
    if "reversing_unsigned" in rec.planted:
        for s in rec.sheets.values():
            if "v" in s.columns:
                s.columns["v"] = np.abs(s.columns["v"])
        rec.planted["reversing_unsigned"].update(stretches=negative(d.t, d.v), speed_written="unsigned")
        rec.taken.add("v")
    if "mode_stretches" in rec.planted:
        s = rec.sheets.get("vehicle") or rec.sheets["log"]
        mode = np.array(["auto"] * len(s.t), dtype=object)
        for a, b in d.manual:
            mode[(s.t >= a) & (s.t < b)] = "manual"
        for a, b in d.paused:
            mode[(s.t >= a) & (s.t < b)] = "paused"
        s.columns["mode"] = mode
        rec.planted["mode_stretches"].update(manual=[list(x) for x in d.manual], paused=[list(x) for x in d.paused],
                                             channel="mode")


# --- channel-stage classes ---------------------------------------------------------------------------
def _free(rec: Recording, rng, choices) -> str | None:
    """A channel among ``choices`` that some sheet holds and no class has changed yet."""
    free = [c for c in choices if rec.holder(c) is not None and c not in rec.taken]
    if not free:
        return None
    c = str(free[int(rng.integers(len(free)))])
    rec.taken.add(c)
    return c


@quirk("channel", layouts=LAYOUTS)
def plant_held_channel(rec: Recording, rng) -> dict:
    """One channel (positions: lat and lon together) updated every ``factor``-th row, held between."""
    c = _free(rec, rng, ("heading", "lat", "yaw_rate", "v", "delta"))
    if c is None:
        return {}
    s = rec.holder(c)
    factor = int(rng.choice([2, 4]))
    both = ("lat", "lon") if c == "lat" else (c,)
    k = (np.arange(len(s.t)) // factor) * factor
    for name in both:
        s.columns[name] = s.columns[name][k]
    rec.taken.update(both)
    return {"channel": "position" if c == "lat" else c, "columns": list(both), "file": s.name,
            "update_hz": s.rate / factor, "row_hz": s.rate, "factor": factor}


def per_update(rec: Recording, column: str, rows: np.ndarray, e: np.ndarray) -> np.ndarray:
    """Noise ``e`` drawn for the ascending ``rows`` as ``column`` carries it: a held channel's
    changes with its updates only (each row takes its update's first row's draw)."""
    held = rec.planted.get("held_channel", {})
    if column not in held.get("columns", ()):
        return e
    k = rows // held["factor"]
    return e[np.searchsorted(k, k)]


@quirk("channel", layouts=("table",))
def plant_one_clock_weak(rec: Recording, rng) -> dict:
    """One row, one clock, with the slow noisy channels that make weak spurious correlations."""
    s = rec.sheets["log"]
    gyro, pos = rng.uniform(0.02, 0.04), rng.uniform(0.03, 0.05)
    n = len(s.t)

    def noise(column: str, sigma: float) -> np.ndarray:
        return per_update(rec, column, np.arange(n), sigma * rng.standard_normal(n))
    if "yaw_rate" in s.columns:
        s.columns["yaw_rate"] = s.columns["yaw_rate"] + noise("yaw_rate", gyro)
    s.columns["lat"] = s.columns["lat"] + np.degrees(noise("lat", pos) / EARTH)
    return {"offset_s": 0.0, "file": s.name, "gyro_noise": gyro, "position_noise": pos}


@quirk("text", excludes=("raw_units", "two_yaw_sources"))
def plant_units_row(rec: Recording, rng) -> dict:
    """A row of units under the header; angles in deg, rates in deg/s, the speed in km/h as it says."""
    factors = {"delta_cmd": ("deg", 180 / math.pi), "delta": ("deg", 180 / math.pi),
               "yaw_rate": ("deg/s", 180 / math.pi), "v": ("km/h", 3.6)}
    time_unit = str(rng.choice(["s", "Unix epoch seconds"]))
    written = {}
    for s in rec.sheets.values():
        s.units = {"t": time_unit, "lat": "deg", "lon": "deg", "fix_quality": "-", "mode": "-", "heading": "deg",
                   "yaw_rate_2": "rad/s"}
        for c, (unit, k) in factors.items():
            if c in s.columns and c not in ("heading",):
                s.columns[c] = s.columns[c] * k
                s.units[c] = unit
                written[c] = {"unit": unit, "factor": k}
    rec.units_row = True
    return {"units": written, "time_unit": time_unit}


@quirk("text")
def plant_quoted_rows(rec: Recording, rng) -> dict:
    rec.quoted = True
    return {"files": sorted(rec.sheets)}


@quirk("text")
def plant_decimal_commas(rec: Recording, rng) -> dict:
    """Numbers written with a decimal comma and fields separated by ';', as a spreadsheet in a
    European locale writes a CSV (https://github.com/nyetwurk/ecuxplot/issues/14,
    https://github.com/JuliaData/CSV.jl/issues/83): truth the columns per file that hold one."""
    rec.decimal_comma = True
    return {"files": sorted(rec.sheets), "separator": ";"}


@quirk("text", layouts=("nmea",))
def plant_two_talkers(rec: Recording, rng) -> dict:
    """Each epoch's GGA from two talkers: the combined solution (GN, the recording's positions)
    and a GPS-only one (GP, 0.3-0.8 m off, DGPS), in one order throughout, as receivers configured
    for both write them (https://github.com/projecthorus/chasemapper/pull/37,
    https://github.com/LORD-MicroStrain/microstrain_inertial/issues/408): truth the count of
    epochs with both and the talker that holds the recording's positions."""
    s = rec.sheets["gnss"]
    first = str(rng.choice(["GN", "GP"]))
    sigma = float(rng.uniform(0.3, 0.8))
    e, n = sigma * rng.standard_normal((2, len(s.t)))
    s.columns["gp_lat"] = s.columns["lat"] + np.degrees(n / EARTH)
    s.columns["gp_lon"] = s.columns["lon"] + np.degrees(e / (EARTH * math.cos(math.radians(LAT0))))
    rec.talkers = ("GN", "GP") if first == "GN" else ("GP", "GN")
    return {"talkers": list(rec.talkers), "kept": "GN", "count": int(len(s.t)), "gp_noise_m": sigma}


@quirk("channel", layouts=LAYOUTS)
def plant_fix_quality_drop(rec: Recording, rng) -> dict:
    """The fix falls from RTK fixed (4) to DGPS (2) or RTK float (5) for 5-15 s, once to three
    times; the positions noisier there (0.3 m DGPS, 0.05 m float; held positions hold it too)."""
    s = rec.holder("fix_quality")
    duration = float(s.t[-1])
    stretches = []
    for _ in range(int(rng.integers(1, 4))):
        for _ in range(100):
            a = rng.uniform(5.0, duration - 20.0)
            b = a + rng.uniform(5.0, 15.0)
            if all(a > y + 3 or b < x - 3 for x, y, _ in stretches):
                stretches.append((float(a), float(b), int(rng.choice([2, 5]))))
                break
    q = s.columns["fix_quality"]
    held = rec.planted.get("held_channel", {})
    n = len(s.t)            # held positions change fix with their updates: each row goes with its update's first
    first = (np.arange(n) // held["factor"]) * held["factor"] if "lat" in held.get("columns", ()) else np.arange(n)
    for a, b, code in stretches:
        inside = (s.t[first] >= a) & (s.t[first] < b)
        q[inside] = code
        sigma = 0.3 if code == 2 else 0.05
        e = per_update(rec, "lat", np.flatnonzero(inside), sigma * rng.standard_normal(inside.sum()))
        s.columns["lat"][inside] += np.degrees(e / EARTH)
    rec.taken.add("fix_quality")
    return {"stretches": [list(x) for x in sorted(stretches)], "channel": "fix_quality",
            "share": {str(c): float(np.mean(q == c)) for c in (2, 4, 5)}}


@quirk("channel", excludes=("two_yaw_sources", "mislabelled_channel"))
def plant_heading_no_gyro(rec: Recording, rng) -> dict:
    """No gyro; a dual-antenna heading (degrees clockwise from north, as receivers write it,
    0.1-0.3 deg noise) in the receiver's file."""
    for s in rec.sheets.values():
        s.columns.pop("yaw_rate", None)
    rec.sheets.pop("imu", None)
    s = rec.holder("lat")
    sigma = rng.uniform(0.1, 0.3)
    compass = 90.0 - np.degrees(rec.drive.at("psi", s.t)) + sigma * rng.standard_normal(len(s.t))
    s.columns["heading"] = np.mod(compass, 360.0)
    rec.taken.add("yaw_rate")
    return {"channel": "heading", "file": s.name, "convention": "degrees clockwise from north",
            "noise_deg": sigma, "gyro": None}


@quirk("channel", layouts=LAYOUTS)
def plant_channel_dropouts(rec: Recording, rng) -> dict:
    """One channel's 5-15 silences of 0.2-0.7 s (its cells blank; the other columns go on)."""
    c = _free(rec, rng, ("delta", "yaw_rate", "v", "heading"))
    if c is None:
        return {}
    s = rec.holder(c)
    duration, gaps = float(s.t[-1]), []
    for _ in range(int(rng.integers(5, 16))):
        for _ in range(100):
            a, span = rng.uniform(3.0, duration - 3.0), rng.uniform(0.2, 0.7)
            if all(a > y + 1.0 or a + span < x - 1.0 for x, y in gaps):
                gaps.append((float(a), float(a + span)))
                break
    x = s.columns[c]
    for a, b in gaps:
        x[(s.t >= a) & (s.t < b)] = np.nan
    kept = s.t[np.isfinite(x)]
    steps = np.diff(kept)
    silences = steps[steps > 1.5 / s.rate]      # the written stamps either side of each silence
    return {"channel": c, "file": s.name, "count": int(len(silences)), "longest_s": float(silences.max()),
            "gaps": [list(g) for g in sorted(gaps)]}


@quirk("channel", excludes=("units_row",))
def plant_raw_units(rec: Recording, rng) -> dict:
    """A gyro written in deg/s or a speed in km/h, with no unit anywhere."""
    c = _free(rec, rng, ("yaw_rate", "v"))
    if c is None:
        return {}
    k = 180 / math.pi if c == "yaw_rate" else 3.6
    s = rec.holder(c)
    s.columns[c] = s.columns[c] * k
    return {"channel": c, "factor": k, "unit": "deg/s" if c == "yaw_rate" else "km/h"}


def _mapping(rec: Recording) -> list:
    """The --signal mapping of every column the log takes, as a user names them (TABLE.COLUMN)."""
    units = {"delta_cmd": "rad", "delta": "rad", "v": "m/s", "yaw_rate": "rad/s", "yaw_rate_2": "rad/s", "lat": "deg",
             "lon": "deg"}
    return [f"{c}={s.name}.{c}[{u}]" for s in rec.sheets.values() for c, u in units.items() if c in s.columns]


@quirk("channel", excludes=("units_row", "raw_units"))
def plant_two_yaw_sources(rec: Recording, rng) -> dict:
    """A second gyro, its scale 7-15 % off the first's (the first is right)."""
    if rec.holder("yaw_rate") is None or "yaw_rate" in rec.taken:
        return {}
    scale = float(rng.uniform(1.07, 1.15) if rng.random() < 0.5 else rng.uniform(0.85, 0.93))
    if rec.layout == "table":
        s = rec.sheets["log"]
    else:
        s = rec.sheets["imu2"] = Sheet("imu2", np.arange(0.0, float(rec.drive.t[-1]), 1.0 / SHEET_RATES["imu2"]), {})
    s.columns["yaw_rate_2"] = scale * rec.drive.at("yaw_rate", s.t) + 0.004 * rng.standard_normal(len(s.t))
    rec.taken.update({"yaw_rate", "yaw_rate_2"})
    return {"channels": ["yaw_rate", "yaw_rate_2"], "scale": scale, "file": s.name, "signals_needed": True}


@quirk("channel", excludes=("heading_no_gyro", "two_yaw_sources"))
def plant_mislabelled_channel(rec: Recording, rng) -> dict:
    """The 'gyro' column holding an accelerometer's vertical axis (g), or the wheel angle's column
    holding its rate."""
    c = _free(rec, rng, ("yaw_rate", "delta"))
    if c is None:
        return {}
    s = rec.holder(c)
    if c == "yaw_rate":
        s.columns[c] = 9.81 + 0.05 * rng.standard_normal(len(s.t))
        return {"channel": c, "holds": "acceleration (vertical, m/s2)", "value": 9.81}
    s.columns[c] = np.gradient(rec.drive.at("delta", s.t), s.t) + 0.005 * rng.standard_normal(len(s.t))
    return {"channel": c, "holds": "the wheel angle's rate (rad/s)", "value": None}


# --- file-stage classes -------------------------------------------------------------------------------
@quirk("file", layouts=("devices",), excludes=CLOCKS)
def plant_clock_offset(rec: Recording, rng) -> dict:
    """A device's stamps late against the receiver's."""
    group = str(rng.choice([g for g in ("imu", "vehicle") if g in rec.sheets]))
    late = float(rng.uniform(0.3, 0.9))
    rec.sheets[group].t = rec.sheets[group].t + late
    return {"group": group, "late_s": late, "against": "gnss"}


@quirk("file", layouts=("devices",), excludes=CLOCKS)
def plant_leap_seconds(rec: Recording, rng) -> dict:
    """The receiver's file on GPS time, the others on UTC: its stamps 18 s late."""
    rec.sheets["gnss"].t = rec.sheets["gnss"].t + LEAP_SECONDS
    return {"group": "gnss", "late_s": LEAP_SECONDS}


@quirk("file", layouts=("devices", "nmea"), excludes=CLOCKS)
def plant_gps_week_rollover(rec: Recording, rng) -> dict:
    """The receiver's dates (written as date strings) 1024 weeks early."""
    s = rec.sheets["gnss"]
    s.t = s.t - WEEK_ROLLOVER
    s.time_format = "datetime"
    return {"group": "gnss", "late_s": -WEEK_ROLLOVER, "weeks": 1024}


def _file(rec: Recording, rng) -> Sheet:
    names = sorted(rec.sheets)
    return rec.sheets[names[int(rng.integers(len(names)))]]


@quirk("file", layouts=LAYOUTS)
def plant_duplicate_stamps(rec: Recording, rng) -> dict:
    """5-20 rows written twice with one stamp: half the copies identical, half with the next row's values."""
    s = _file(rec, rng)
    count = int(rng.integers(5, 21))
    rows = np.sort(rng.choice(np.arange(5, len(s.t) - 5), count, replace=False))
    order = np.arange(len(s.t))
    extra = [r + 1 if k % 2 else r for k, r in enumerate(rows)]     # the values the copy holds
    index = np.insert(order, rows + 1, extra)
    stamps = np.insert(s.t, rows + 1, s.t[rows])
    s.columns = {c: np.asarray(x)[index] for c, x in s.columns.items()}
    before, s.t = s.t, stamps
    return {"file": s.name, "count": count, "stamps_s": [float(x) for x in before[rows]]}


@quirk("file")
def plant_out_of_order(rec: Recording, rng) -> dict:
    """3-10 rows written 2-10 rows after their place (a buffer flushed late)."""
    s = _file(rec, rng)
    count = int(rng.integers(3, 11))
    rows = np.sort(rng.choice(np.arange(10, len(s.t) - 20, 25), count, replace=False))
    order = list(range(len(s.t)))
    for r in rows[::-1]:
        order.remove(r)
        order.insert(r + int(rng.integers(2, 11)) - 1, r)
    index = np.array(order)
    s.columns = {c: np.asarray(x)[index] for c, x in s.columns.items()}
    s.t = s.t[index]
    return {"file": s.name, "count": count, "rows_moved": [int(r) for r in rows]}


@quirk("file", excludes=CLOCKS)
def plant_clock_jump(rec: Recording, rng) -> dict:
    """The logger's clock stepped by 1-3 s (either way) at a moment: every later stamp of its file moved."""
    s = _file(rec, rng)
    at = float(rng.uniform(0.3, 0.7) * s.t[-1])
    by = float(rng.uniform(1.0, 3.0) * rng.choice([-1.0, 1.0]))
    s.t = np.where(s.t >= at, s.t + by, s.t)
    return {"file": s.name, "at_s": at, "by_s": by}


@quirk("text", layouts=("nmea",))
def plant_nmea_checksum(rec: Recording, rng) -> dict:
    """5-20 GGA sentences with one character changed in transmission, the checksum left as sent
    (https://github.com/ros-drivers/nmea_navsat_driver/issues/150)."""
    s = rec.sheets["gnss"]
    rows = np.sort(rng.choice(np.arange(2, len(s.t) - 2), int(rng.integers(5, 21)), replace=False))
    rec.corrupt = {int(r) for r in rows}
    return {"count": len(rows), "sentence": "GGA", "rows": [int(r) for r in rows]}


# --- composition and writing ----------------------------------------------------------------------------
ORDER = ("reversing_unsigned", "mode_stretches", "heading_no_gyro", "mislabelled_channel", "two_yaw_sources",
         "raw_units", "held_channel", "channel_dropouts", "fix_quality_drop", "one_clock_weak", "units_row",
         "quoted_rows", "decimal_commas", "clock_offset", "leap_seconds", "gps_week_rollover", "clock_jump",
         "duplicate_stamps", "out_of_order", "nmea_checksum", "two_talkers")


def compatible(classes, layout: str) -> bool:
    """The classes fit the layout and none excludes another."""
    return all(layout in CLASSES[c].layouts for c in classes) and not any(
        b in CLASSES[a].excludes for a in classes for b in classes if a != b)


ADDED = ("decimal_commas", "two_talkers")     # drawn apart (ADDED_SHARE each): a seed's draw of the others kept
ADDED_SHARE = 0.2


def draw_classes(rng, layout: str, most: int = 4, among=None, seed: int | None = None) -> list:
    """A random subset of 1..``most`` compatible classes (of ``among``, default all but ADDED) for
    ``layout``. With a ``seed`` and no ``among``, the classes added later (ADDED) are each drawn
    apart with their own generator and added where they fit: every earlier composition of a seed
    stays as it was, one of them added to some."""
    pool = [c for c in (among or [c for c in ORDER if c not in ADDED]) if layout in CLASSES[c].layouts]
    want = int(rng.integers(1, most + 1))
    chosen: list = []
    for c in rng.permutation(pool):
        if len(chosen) < want and compatible(chosen + [str(c)], layout):
            chosen.append(str(c))
    extra = np.random.default_rng([seed, 1]) if among is None and seed is not None else None
    for c in ADDED if extra is not None else ():
        if extra.random() < ADDED_SHARE and compatible(chosen + [c], layout):
            chosen.append(c)
    return [c for c in ORDER if c in chosen]


def compose(seed: int, folder: Path, classes=None, layout: str | None = None, machine: str | None = None,
            duration: float = 90.0, most: int = 4, among=None, added: bool = False) -> dict:
    """Write one composition to ``folder`` and return its truth (Recording.truth; "drive" the
    quirk_drive.Drive under it, on the recording's clock from its start). ``classes``:
    the classes to plant (None: a random compatible subset; [] a clean recording); ``layout``,
    ``machine``: None draws them; ``among``: the classes a random subset is drawn from; ``added``:
    the classes added later (ADDED) drawn too, apart (draw_classes)."""
    rng = np.random.default_rng(seed)
    fitting = [x for x in LAYOUTS if any(x in CLASSES[c].layouts for c in among or ORDER)]
    layout = layout or str(rng.choice(fitting))
    machine = machine or str(rng.choice(sorted(MACHINES)))
    if classes is None:
        classes = draw_classes(rng, layout, most, among, seed if added else None)
    classes = [c for c in ORDER if c in classes]
    if not compatible(classes, layout):
        raise ValueError(f"classes {classes} do not fit the layout {layout!r} together")
    rec = Recording(seed, layout, machine, classes)
    for c in classes:
        if CLASSES[c].stage == "drive":
            CLASSES[c].plant(rec, rng)
    rec.drive = drive_for(rec, rng, duration)
    build_sheets(rec, rng, duration)
    finish_drive_classes(rec)
    for stage in ("channel", "text", "file"):
        for c in classes:
            if CLASSES[c].stage == stage:
                truth = CLASSES[c].plant(rec, rng)
                rec.planted[c] = {**rec.planted.get(c, {}), **truth}
    rec.planted = {c: t for c, t in rec.planted.items() if t}          # a class that found nothing to change
    rec.classes = [c for c in classes if c in rec.planted]
    if any(t.get("signals_needed") for t in rec.planted.values()):
        rec.signals = _mapping(rec)
    write(rec, Path(folder))
    return rec.truth()


def _stamp(t: float, how: str) -> str:
    if how == "datetime":
        when = datetime.datetime.fromtimestamp(START + t, datetime.timezone.utc)
        return when.strftime("%Y-%m-%dT%H:%M:%S.%f")[:-3] + "Z"
    return f"{START + t:.3f}"


def _cell(x, comma: bool = False) -> str:
    if isinstance(x, str):
        return x
    text = "" if not np.isfinite(x) else f"{x:.12g}"
    return text.replace(".", ",") if comma else text


def write(rec: Recording, folder: Path) -> None:
    """Each sheet as a CSV (a units row under the header, every row one quoted field where the
    classes say so)."""
    folder.mkdir(parents=True, exist_ok=True)
    if rec.layout == "nmea":
        write_nmea(rec, rec.sheets["gnss"], folder / "gnss.nmea")
        return
    for s in rec.sheets.values():
        names = list(s.columns)
        rows = [["t", *names]]
        if rec.units_row:
            rows.append([s.units.get(c, "-") for c in ["t", *names]])
        columns = [s.columns[c] for c in names]
        comma = rec.decimal_comma
        for i, t in enumerate(s.t):
            stamp = _stamp(float(t), s.time_format)
            rows.append([stamp.replace(".", ",") if comma and s.time_format == "posix" else stamp,
                         *(_cell(x[i], comma) for x in columns)])
        path = folder / f"{s.name}.csv"
        sep = ";" if comma else ","
        with path.open("w", newline="") as f:
            if rec.quoted:
                f.write("".join('"' + sep.join(r) + '"\n' for r in rows))
            else:
                csv.writer(f, delimiter=sep, lineterminator="\n").writerows(rows)
        if comma:
            rec.planted["decimal_commas"].setdefault("columns", {})[s.name] = sum(
                any("," in r[k] for r in rows[1 + rec.units_row:]) for k in range(len(rows[0])))
        rec.files.append(path)
        steps = np.diff(s.t)
        rec.written[s.name] = {"rows": int(len(s.t)), "step_backs": int(np.sum(steps < 0)),
                               "repeated": int(np.sum(steps == 0))}


def _dm(value: float, width: int) -> str:
    d = int(abs(value))
    return f"{d:0{width}d}{(abs(value) - d) * 60:010.7f}"


def write_nmea(rec: Recording, s: Sheet, path: Path) -> None:
    """The receiver's epochs as GGA (position, fix quality), RMC (speed and course over ground,
    the date) and HDT (the dual antenna's heading, where it has one) sentences."""
    lines = []
    for i, t in enumerate(s.t):
        when = datetime.datetime.fromtimestamp(START + float(t), datetime.timezone.utc)
        hms = when.strftime("%H%M%S.") + f"{when.microsecond // 10000:02d}"
        lat, lon = float(s.columns["lat"][i]), float(s.columns["lon"][i])
        pos = f"{_dm(lat, 2)},{'N' if lat >= 0 else 'S'},{_dm(lon, 3)},{'E' if lon >= 0 else 'W'}"
        for talker in rec.talkers or ("GP",):
            if talker == "GP" and rec.talkers:     # the GPS-only solution beside the combined one
                glat, glon = float(s.columns["gp_lat"][i]), float(s.columns["gp_lon"][i])
                where, quality = f"{_dm(glat, 2)},N,{_dm(glon, 3)},E", 1
            else:
                where, quality = pos, int(s.columns["fix_quality"][i])
            line = sentence(f"{talker}GGA,{hms},{where},{quality},14,0.7,12.0,M,47.0,M,,")
            if i in rec.corrupt and (talker == "GN" or not rec.talkers):   # a digit changed after the checksum
                k = line.index(".", 20) + 3
                line = line[:k] + str((int(line[k]) + 3) % 10) + line[k + 1:]
            lines.append(line)
        rmc = (f"GPRMC,{hms},A,{pos},{s.columns['speed'][i] / (1852 / 3600):.3f},{s.columns['course'][i]:.2f},"
               f"{when.strftime('%d%m%y')},,,A")
        lines.append(sentence(rmc))
        if np.isfinite(s.columns["heading"][i]):
            lines.append(sentence(f"GPHDT,{s.columns['heading'][i]:.2f},T"))
    path.write_text("\n".join(lines) + "\n")
    rec.files.append(path)
    steps = np.diff(s.t)
    rec.written[s.name] = {"rows": int(len(s.t)), "step_backs": int(np.sum(steps < 0)), "repeated": int(np.sum(steps == 0))}
    if rec.talkers:             # the epochs both talkers give readable (a corrupt GN leaves GP alone)
        both = {float(t) for i, t in enumerate(s.t) if i not in rec.corrupt}
        rec.planted["two_talkers"]["readable"] = len(both)
    if "duplicate_stamps" in rec.planted:       # a copy whose GGA or original's is corrupt repeats no readable epoch
        intact = np.array([i not in rec.corrupt for i in range(len(s.t))])
        rec.planted["duplicate_stamps"]["readable"] = int(np.sum(np.diff(s.t[intact]) == 0))
