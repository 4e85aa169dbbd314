"""A short reversal seen by a 1 Hz receiver: a car drives forward, stops, backs up for REVERSE s at
0.3-1.2 m/s (its heading held, its course turned by pi) and drives on without a stop the fixes
can see; its speed is the receiver's unsigned one. The reversal is named at its times whatever the
fixes' rate (a run of reversing votes judged by its duration, not by a count made for 10 Hz)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from agrobot.measurements import LogError
from agrobot.measurements.direction import check_direction
from agrobot.measurements.streams import Streams, gnss_table

START, REVERSE = 160.0, 6.0        # s: the reversal's start and length (truth)


def _drive(fix_hz: float):
    """Streams of the drive: a 50 Hz gyro, fixes at ``fix_hz``, the unsigned speed on the fixes."""
    h = 0.02
    t = np.arange(0.0, 300.0, h)
    rng = np.random.default_rng(4)
    knots = np.arange(0.0, 301.0, 8.0)
    r = np.interp(t, knots, rng.uniform(-0.12, 0.12, len(knots)))
    back = (t >= START) & (t < START + REVERSE)
    stop = np.abs(t - START) < 1.0
    speed = np.where(back, 0.3 + 0.9 * np.sin(math.pi * (t - START) / REVERSE), 8.0)
    speed = np.where(stop, 0.35, speed)
    r = np.where(back | stop, 0.0, r)
    yaw = np.cumsum(r) * h
    signed = np.where(back, -speed, speed)
    east = np.cumsum(signed * np.cos(yaw)) * h
    north = np.cumsum(signed * np.sin(yaw)) * h
    lat0 = 56.1
    lat = lat0 + np.degrees(north / 6.371e6)
    lon = 10.2 + np.degrees(east / (6.371e6 * math.cos(math.radians(lat0))))
    k = max(1, int(round(1.0 / (fix_hz * h))))
    t0 = 1.627e9
    gnss = gnss_table(t0 + t[::k], lat[::k], lon[::k], quality=np.full(len(t[::k]), 1.0), speed=speed[::k])
    signals = {"yaw_rate": (t0 + t, r + 0.002 * rng.standard_normal(len(t))), "v": (t0 + t[::k], speed[::k])}
    return Streams(gnss, signals, {}, set(), {}), t0


class _Options:
    sign_speed = False


@pytest.mark.parametrize("fix_hz", [1.0, 10.0])
def test_a_short_reversal_is_named_at_any_fix_rate(fix_hz):
    streams, t0 = _drive(fix_hz)
    with pytest.raises(LogError, match="reverses at") as err:
        check_direction(streams, _Options(), "car.mf4", t0)
    said = str(err.value).split("reverses at ")[1].split(" (")[0]
    a, b = (float(x) for x in said.removesuffix(" s").split("-"))
    assert abs(a - START) <= 2.0 and abs(b - (START + REVERSE)) <= 2.0, said
    assert "--sign-speed" in str(err.value)


def test_the_same_drive_forward_only_names_no_reversal():
    streams, t0 = _drive(1.0)
    streams.gnss = streams.gnss[streams.gnss["utc"] < t0 + START - 2.0]
    streams.signals = {c: (t[t < t0 + START - 2.0], x[t < t0 + START - 2.0]) for c, (t, x) in streams.signals.items()}
    assert check_direction(streams, _Options(), "car.mf4", t0) == []
