"""The readers' common vocabulary: what a recording holds, before it becomes a log.

A reader (NMEA, CAN, ROS bag, ISO 11783-10 time log, tables) turns its files into ``Streams``:
the receiver's fixes, if any, and named signals, each on its own time stamps, in SI units, with
the import report so far. ``measurements.recording`` chooses the reader and puts the streams on
one grid; no reader imports it. A ``Series`` is one raw signal as a source holds it (its own
times, its values in the source's unit, that unit when the source states one), the operand of a
``--signal`` expression (measurements.signal_expressions). A ``Reader`` is one recording format
as the converter, the listing and the help see it; measurements.recording_readers holds them in their
order of precedence.
"""
from __future__ import annotations

import datetime
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

HELD = ("delta_cmd", "speed_cmd")  # set-points: held between frames, not interpolated
# POSIX seconds before this (1973-03-03) are not dates: a clock counting from the logger's boot
BOOT_CLOCK_LIMIT = 1e8
SPEED_CHORD = 0.2     # s: a track's speed from fixes at least this far either side


@dataclass
class Series:
    """One signal as the source holds it: increasing times [s], values in ``unit`` (None: the
    source states none), and where it came from; ``wrap`` the modulus of an integer counter
    stored in a fixed width (2^16 for int16 and uint16), None where the source gives no width."""

    t: np.ndarray
    values: np.ndarray
    unit: str | None
    label: str
    wrap: float | None = None


@dataclass
class Streams:
    """What a recording holds, on one time base (POSIX seconds where the source knows them):
    ``gnss`` the receiver's epochs with a fix (utc, lat, lon, height, quality, speed, course and
    where given heading, position_std), or None; ``signals`` column -> (time, SI values); ``held``
    the set-points among them; ``resolution`` each signal's step read on its own samples;
    ``breaks`` the spans a run must not bridge (a clock that stepped back, a position jump);
    ``groups`` each signal's source (file, topic, bus): the channels that share a clock;
    ``clocks`` group -> the clock its times are on where groups share one (the topics of a bag on
    its receive clock); a group not named is a clock of its own."""

    gnss: pd.DataFrame | None
    signals: dict[str, tuple[np.ndarray, np.ndarray]]
    report: dict
    held: set = field(default_factory=set)
    resolution: dict = field(default_factory=dict)
    breaks: list = field(default_factory=list)      # {stream, start, end (POSIX s), why}: never joined across
    groups: dict = field(default_factory=dict)      # column -> the file, topic or bus it came from (one clock)
    labels: dict = field(default_factory=dict)      # column -> the text values of a mode channel's codes
    clocks: dict = field(default_factory=dict)      # group -> the clock groups share (a bag's receive clock)


class Reader:
    """One recording format. ``kind`` names its files (the import report's ``files``), ``name``
    and ``files`` are how the help names it (every suffix among ``files``), ``listed`` what
    ``--list`` shows of it; ``suffixes`` are every suffix it may claim, by the name alone or by
    the content. ``raw``: a file of it alone is a raw recording (False: a table, read as a log
    when it is one); ``streamed``: its files are read as streams (the larger size limit), not
    whole. Which reader gets a file, and which reader's files make the recording, is decided by
    the order of measurements.recording_readers.READERS."""

    kind: str = ""
    name: str = ""
    files: str = ""
    listed: str = ""
    suffixes: tuple[str, ...] = ()
    raw: bool = True
    streamed: bool = False

    def claims(self, path: Path) -> bool:
        """Whether ``path`` (a file, or a folder inside the recording or the recording itself)
        is of this format; by default a file with one of the suffixes."""
        return path.suffix.lower() in self.suffixes and not path.is_dir()

    def streams(self, files: dict[str, list[Path]], options, source: Path) -> "Streams":
        """The recording's streams from its files of this kind (``files``: every kind's, by kind)."""
        raise NotImplementedError

    def listing(self, paths: list[Path], options, source: Path) -> list[str]:
        """``convert --list``: what the files of this kind hold, as lines."""
        raise NotImplementedError


def gnss_table(t, lat, lon, height=None, quality=None, speed=None, position_std=None) -> pd.DataFrame:
    """The receiver's epochs in the layout Streams.gnss has (NaN where the source gives nothing)."""
    n = len(t)

    def col(x, fill):
        return np.full(n, fill, float) if x is None else np.asarray(x, float)
    return pd.DataFrame({"utc": np.asarray(t, float), "lat": np.asarray(lat, float), "lon": np.asarray(lon, float),
                         "height": col(height, 0.0), "quality": col(quality, math.nan), "speed": col(speed, math.nan),
                         "course": math.nan, "heading": math.nan, "position_std": col(position_std, math.nan)})


def iso(posix: float) -> str:
    """A time stamp as a person reads it: an ISO 8601 UTC date for POSIX seconds, or seconds
    since the logger started for a boot-time clock (a 1970 date would mislead)."""
    if not math.isfinite(posix):
        return "unknown"
    if abs(posix) < BOOT_CLOCK_LIMIT:
        return f"{posix:.3f} s on the logger's clock (since its start, not a date)"
    try:
        when = datetime.datetime.fromtimestamp(posix, datetime.timezone.utc)
    except (ValueError, OverflowError, OSError):
        return f"{posix:.6g} s (beyond the calendar: not a date)"
    return when.isoformat(timespec="milliseconds").replace("+00:00", "Z")


def is_boot_clock(t: np.ndarray) -> bool:
    """Stamps that count from a logger's start rather than from 1970."""
    t = np.asarray(t, float)
    return len(t) > 0 and float(np.nanmax(np.abs(t))) < BOOT_CLOCK_LIMIT


def gnss_speed(gnss: pd.DataFrame, breaks: list | None = None) -> np.ndarray:
    """Speed over ground per epoch: RMC/VTG where given, else from position chords (central
    differences over k fixes either side, k fixes spanning at least SPEED_CHORD s, within each
    stretch between ``breaks``, never across one: a fix's time known to a fraction of its period
    then barely moves the speed)."""
    speed = gnss["speed"].to_numpy(float)
    utc = gnss["utc"].to_numpy(float)
    if np.isfinite(speed).mean() > 0.5:
        return np.interp(utc, utc[np.isfinite(speed)], speed[np.isfinite(speed)])
    north = np.radians(gnss["lat"].to_numpy() - gnss["lat"].iloc[0]) * 6.371e6      # a sphere is enough for a speed
    east = np.radians(gnss["lon"].to_numpy() - gnss["lon"].iloc[0]) * 6.371e6 * math.cos(math.radians(gnss["lat"].iloc[0]))
    out = np.zeros(len(utc))
    cuts = np.searchsorted(utc, [b["start"] for b in breaks or ()], side="right")
    k = max(1, int(round(SPEED_CHORD / float(np.median(np.diff(utc)))))) if len(utc) > 1 else 1
    for a, b in zip(np.concatenate([[0], cuts]), np.concatenate([cuts, [len(utc)]])):
        if b - a >= 2:
            out[a:b] = _chord_speed(utc[a:b], east[a:b], north[a:b], min(k, (b - a - 1) // 2 or 1))
    return out


def _chord_speed(t: np.ndarray, east: np.ndarray, north: np.ndarray, k: int) -> np.ndarray:
    """|d(east, north)/dt| by central chords of k samples either side (one-sided at the ends)."""
    n = len(t)
    i = np.arange(n)
    lo, hi = np.clip(i - k, 0, n - 1), np.clip(i + k, 0, n - 1)
    dt = np.maximum(t[hi] - t[lo], 1e-9)
    return np.hypot(east[hi] - east[lo], north[hi] - north[lo]) / dt
