"""A recording's streams on one grid: gaps, runs, the run or span used, and the log's columns.

Gaps: a stream silent for more than 3 of its periods and ``max_gap`` (``--max-gap``, default
0.5 s; 0.2 s at least) splits the recording, and so does a silence of every stream at once; a
shorter gap of one stream is bridged (linear; a set-point held) and named by the audit
(measurements.audit). Runs are the stretches where the vehicle drives (|speed| above ``min_speed``, stops
shorter than ``min_stop`` bridged) with every stream present. One run is used: the longest, the
``run``-th, or a ``time_range`` (seconds from the recording's first sample); the report says which.
A run keeps the standstill either side of it (a gyro's bias is read there) unless
``trim_standstill`` (``--trim-standstill``).
Positions go to a local east/north plane about the run's first fix (pymap3d, WGS-84). Measured
signals are interpolated linearly onto the log's grid; the set-points are held (the last frame).

Imported where used: pymap3d (the hardware extra).
"""
from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pandas as pd

from .audit import minimum
from .log import CANONICAL, LogError
from .modes import decoded
from .options import ImportOptions
from .streams import Streams, gnss_speed, iso

GAP_PERIODS, GAP_MIN = 3.0, 0.2
MAX_SAMPLES = 5e7      # rows of one log grid (a day at 500 Hz): more is a damaged clock, not a recording
SENT_WITH_ROW = 1e-3   # s: a set-point sent up to this after a grid time is in force at it (held)
STANDSTILL_KEPT = 60.0  # s of standstill kept at most either side of a run: a gyro's bias is read in 2 s, and the
                        # nearest minute holds the bias of the run's temperature, not a long idle's
HELD_GAP = 1.0        # s: a set-point is sent when it changes, or now and then; in force until the next
DISCRETE = ("fix_quality", "mode", "engaged", "gear", "direction")   # codes: held at their own times, never interpolated


def gaps(t: np.ndarray, what: str, origin: float, least: float = GAP_MIN) -> list[dict]:
    """Silences longer than GAP_PERIODS typical periods and ``least`` seconds."""
    if len(t) < 2:
        return []
    dt = np.diff(t)
    limit = max(GAP_PERIODS * float(np.median(dt)), least)
    return [{"stream": what, "start": float(t[i] - origin), "end": float(t[i + 1] - origin),
             "duration": float(dt[i])} for i in np.flatnonzero(dt > limit)]


def _covered(t: np.ndarray, grid: np.ndarray, least: float = GAP_MIN) -> np.ndarray:
    """True where ``grid`` lies within a stretch of ``t`` without a gap."""
    if len(t) < 2:
        return np.zeros(len(grid), bool)
    limit = max(GAP_PERIODS * float(np.median(np.diff(t))), least)
    i = np.clip(np.searchsorted(t, grid, side="right"), 1, len(t) - 1)
    return (grid >= t[0]) & (grid <= t[-1]) & (t[i] - t[i - 1] <= limit)


def _stretches(mask: np.ndarray) -> list[tuple[int, int]]:
    """[start, end) index pairs of the True stretches."""
    edges = np.diff(np.concatenate([[0], mask.astype(int), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


def last_update(times: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The index of the last of the increasing ``times`` at or before each t (-1 before the first)."""
    return np.searchsorted(times, t, side="right") - 1


def held(grid: np.ndarray, t: np.ndarray, values: np.ndarray) -> np.ndarray:
    """The value in force at each grid time: the last one sent at or before it (SENT_WITH_ROW
    tolerance); NaN before the first (the source has said nothing yet)."""
    i = last_update(t, grid + SENT_WITH_ROW)
    out = np.asarray(values, float)[np.clip(i, 0, max(len(t) - 1, 0))]
    return np.where(i >= 0, out, np.nan)


def within(grid: np.ndarray, t: np.ndarray, values: np.ndarray, least: float = GAP_MIN) -> np.ndarray:
    """``values`` at ``t`` interpolated linearly onto ``grid``, NaN where the source is silent: outside
    its span, or between two samples further apart than GAP_PERIODS of its periods and ``least``."""
    ok = np.isfinite(values)
    t, values = t[ok], values[ok]
    if len(t) < 2:
        return np.full(len(grid), np.nan)
    j = np.clip(np.searchsorted(t, grid), 1, len(t) - 1)
    said = np.minimum(np.abs(t[j] - grid), np.abs(t[j - 1] - grid)) <= 1e-3      # a sample at the grid time
    return np.where(_covered(t, grid, least) | said, np.interp(grid, t, values), np.nan)


def _grid_step(streams: Streams, options: ImportOptions) -> float:
    """The log's period: --rate, else the GNSS epoch period, else the fastest canonical signal's
    (at most 50 Hz); to the millisecond, so that a float median does not let the grid creep."""
    if options.rate:
        return 1.0 / options.rate
    if streams.gnss is not None:
        return max(round(float(np.median(np.diff(streams.gnss["utc"].to_numpy(float)))), 3), 0.001)
    periods = [float(np.median(np.diff(t))) for c, (t, _) in streams.signals.items() if c in CANONICAL and len(t) > 1]
    periods = periods or [float(np.median(np.diff(t))) for t, _ in streams.signals.values() if len(t) > 1]
    return max(round(min(periods), 3), 0.02)


def _faster_than_rows(streams: Streams, options: ImportOptions, step: float) -> str | None:
    """The note of a default grid (no --rate: the GNSS epoch rate, else at most 50 Hz) below the
    canonical signals' own update rates (at least twice the rows' with a GNSS, above them without):
    what the rows leave out and the --rate that keeps it."""
    if options.rate:
        return None
    fast = {c: 1.0 / float(np.median(np.diff(t))) for c, (t, _) in streams.signals.items()
            if c in CANONICAL and len(t) > 2 and np.median(np.diff(t)) > 0}
    least = 2.0 / step if streams.gnss is not None else 1.05 / step
    fast = {c: hz for c, hz in fast.items() if hz >= least}
    if not fast:
        return None
    keep = min(200.0, max(round(hz) for hz in fast.values()))
    head = (f"rows at the GNSS epoch rate {1.0 / step:.3g} Hz (the default)" if streams.gnss is not None else
            f"rows at {1.0 / step:.3g} Hz (the default without a GNSS: the fastest channel's rate, at most 50 Hz)")
    return (head + ": " + ", ".join(f"{c} ({hz:.3g} Hz)" for c, hz in sorted(fast.items(), key=lambda kv: -kv[1]))
            + f" sampled at it, their updates between rows left out; --rate {keep:g} keeps them")


class OwnSamples(dict):
    """column -> (its own sample times on the log's clock, values), lists (JSON, as pandas writes
    attrs to parquet): read-only, shared as it is by the frames derived from the log (pandas copies
    and compares attrs: not the lists)."""

    def __deepcopy__(self, memo):
        return self

    def __eq__(self, other):
        return self is other

    __hash__ = object.__hash__


def assemble(source: Path, streams: Streams, options: ImportOptions) -> tuple[pd.DataFrame, dict]:
    """The log on its grid for the run or range ``options`` choose, and the report of it: every
    canonical column the recording holds, then the extras (the receiver's speed, fix quality,
    heading and position error, and any other mapped signal); the missing columns are named."""
    gnss, sig, report = streams.gnss, streams.signals, copy.deepcopy(streams.report)
    times = _timed(source, streams)
    u0 = float(gnss["utc"].iloc[0]) if gnss is not None else min(float(t[0]) for _, t in times)
    step = _grid_step(streams, options)
    note = _faster_than_rows(streams, options, step)
    if note:
        report.setdefault("notes", []).append(note)
    bridge = max(GAP_MIN, float(options.max_gap))
    least = {name: max(HELD_GAP if name in streams.held else GAP_MIN, bridge) for name, _ in times}
    report["gaps"] = sum((gaps(t, name, u0, least[name]) for name, t in times), [])
    grid = _grid(source, times, u0, step)
    covered = _covered_grid(grid, times, least, u0, streams, report)
    speed = _speed(grid, streams, report)
    long_runs = _runs(grid, u0, step, covered, speed, options, report)
    pick, used = _choose(source, grid, u0, covered, long_runs, report, options)
    pick, used = with_standstill(pick, used, grid - u0, covered, speed, options)
    report["used"] = {**used, "duration": float(pick.sum() * step), "utc_start": iso(grid[pick][0]),
                      "utc_start_s": float(grid[pick][0])}
    t = grid[pick]
    columns: dict[str, np.ndarray] = {"t": step * np.arange(len(t))}      # whole steps: no rounding creep
    for c in CANONICAL[1:]:
        if c in sig:
            columns[c] = held(t, *sig[c]) if c in streams.held else np.interp(t, *sig[c])
    if gnss is not None:
        columns.update(_receiver_columns(t, streams, report))
    for c, (tc, vc) in sig.items():
        if c not in columns:
            columns[c] = held(t, tc, vc) if c in streams.held or c in DISCRETE else within(t, tc, vc, bridge)
            if c in streams.labels:         # a mode channel's text values
                columns[c] = decoded(columns[c], streams.labels[c])
            if c == "heading":              # an angle, unwrapped on its stamps: wrapped to (-pi, pi]
                columns[c] = np.angle(np.exp(1j * columns[c]))
    report["rate_hz"] = 1.0 / step
    report["resolution"] = {c: float(streams.resolution.get(c, 0.0)) for c in list(sig) + ["x", "y"]
                            if c in sig or c in streams.resolution}
    present = [c for c in CANONICAL if c in columns]
    report["present"] = present + [c for c in columns if c not in CANONICAL]
    why = report.get("can", {}).get("columns_without_a_signal", {})
    report["missing"] = {c: why.get(c, _missing_reason(c, report)) for c in CANONICAL if c not in columns}
    order = present + [c for c in columns if c not in CANONICAL]
    frame = pd.DataFrame(columns)[order]
    # the canonical channels' own samples on the log's clock (their rows hold or interpolate them), the
    # fixes' positions among them
    own = {c: ((sig[c][0] - t[0]).tolist(), np.asarray(sig[c][1], float).tolist())
           for c in dict.fromkeys((*streams.held, *CANONICAL[1:])) if c in sig}
    frame.attrs["own_samples"] = OwnSamples({**own, **(_fix_positions(t[0], streams) if gnss is not None else {})})
    return frame, report


def _timed(source: Path, streams: Streams) -> list[tuple[str, np.ndarray]]:
    """(name, times) of the streams that set the log's span and its gaps: the positions and the
    canonical columns (an extra column, logged now and then, is held or interpolated within that
    span); every signal when the recording holds none of those."""
    gnss, sig = streams.gnss, streams.signals
    times = ([("gnss", gnss["utc"].to_numpy(float))] if gnss is not None else []) + \
        [(c, t) for c, (t, _) in sig.items() if c in CANONICAL]
    times = times or [(c, t) for c, (t, _) in sig.items()]
    if not times:
        raise LogError(f"{source}: nothing with a time stamp in it")
    return times


def _grid(source: Path, times: list, u0: float, step: float) -> np.ndarray:
    """The log's grid: u0 + k step for every whole k within the span all ``times`` share
    [max of the starts, min of the ends]; refused when they share less than two steps, or more
    than MAX_SAMPLES of them (a damaged clock)."""
    lo, hi = max(float(t[0]) for _, t in times), min(float(t[-1]) for _, t in times)
    if hi - lo < 2 * step:
        spans = ", ".join(f"{name} {t[0] - u0:.1f}-{t[-1] - u0:.1f} s" for name, t in times)
        raise LogError(f"{source}: the streams overlap for {max(hi - lo, 0):.3g} s ({spans}); nothing to align")
    if (hi - lo) / step > MAX_SAMPLES:
        spans = ", ".join(f"{name} {iso(t[0])} to {iso(t[-1])}" for name, t in times)
        raise LogError(f"{source}: the streams span {hi - lo:.4g} s ({spans}): {(hi - lo) / step:.3g} samples at "
                       f"{1 / step:g} Hz, above {MAX_SAMPLES:.0e}; a time stamp far from the others, or choose a span "
                       f"with --time-range or a lower --rate")
    return u0 + step * np.arange(math.ceil((lo - u0) / step - 1e-9), math.floor((hi - u0) / step + 1e-9) + 1)


def _covered_grid(grid: np.ndarray, times: list, least: dict, u0: float, streams: Streams,
                  report: dict) -> np.ndarray:
    """True where the grid may be used: not within a break (named in report["gaps"] and
    report["splits"]), inside every stream's stretch without a gap longer than its ``least``, and
    not where every stream is silent at once (a split, however short)."""
    covered = np.ones(len(grid), bool)
    for b in streams.breaks:                  # never bridged: the samples on either side are not one step apart
        i0 = int(np.searchsorted(grid, b["start"], side="right"))
        covered[i0:max(int(np.searchsorted(grid, b["end"], side="right")), i0 + 1)] = False
        report["gaps"].append({"stream": f"{b['stream']} (split: {b.get('kind', 'clock step back')})",
                               "start": float(b["start"] - u0), "end": float(b["end"] - u0),
                               "duration": float(b["end"] - b["start"])})
    if streams.breaks:
        report["splits"] = [b["why"] for b in streams.breaks]
    silent = np.ones(len(grid), bool)             # every stream silent at once: split, however short
    for name, t in times:
        covered &= _covered(t, grid, least[name])
        silent &= ~_covered(t, grid, HELD_GAP if name in streams.held else GAP_MIN)
    return covered & ~silent


def _speed(grid: np.ndarray, streams: Streams, report: dict) -> np.ndarray | None:
    """The speed on the grid that tells driving from standing: the column v, else the receiver's
    speed over ground, else none (report["runs_by"] says which)."""
    gnss, sig = streams.gnss, streams.signals
    if "v" in sig:
        v, report["runs_by"] = np.interp(grid, *sig["v"]), "the speed column v"
    elif gnss is not None:
        v, report["runs_by"] = np.interp(grid, gnss["utc"], gnss_speed(gnss, streams.breaks)), "the receiver's speed over ground"
    else:
        v, report["runs_by"] = None, "no speed in the recording: every stretch without a gap is a run"
    return v


def _runs(grid: np.ndarray, u0: float, step: float, covered: np.ndarray, v: np.ndarray | None,
          options: ImportOptions, report: dict) -> list[dict]:
    """The runs, numbered from 1: the stretches driving (|v| > min_speed; a stop shorter than
    min_stop bridged; every stretch without a gap when there is no speed) with every stream
    present, at least min_run long; none that long: the longest, when the minimum's floor allows
    it (measurements.audit.minimum, a note)."""
    moving = np.abs(v) > options.min_speed if v is not None else np.ones(len(grid), bool)   # reversing drives too
    report["driving_s"] = float(moving.sum() * step)
    report["silent_while_driving_s"] = float((moving & ~covered).sum() * step)
    for a, b in _stretches(~moving):                 # short stops do not end a run
        if 0 < a and b < len(grid) and (b - a) * step < options.min_stop:
            moving[a:b] = True
    runs = []
    for a, b in _stretches(moving & covered):
        runs.append({"start": float(grid[a] - u0), "end": float(grid[b - 1] - u0), "duration": float((b - a) * step),
                     "mean_speed": float(v[a:b].mean()) if v is not None else math.nan, "utc_start": iso(grid[a])})
    long_runs = [r for r in runs if r["duration"] >= options.min_run]
    if not long_runs and runs:            # the minimum is guidance down to its floor (measurements.audit.minimum)
        best = max(runs, key=lambda r: r["duration"])
        try:
            warning = minimum(best["duration"], options.min_run, "the longest run", "s")
        except LogError:
            warning = None
        if warning:
            long_runs = [best]
            report.setdefault("notes", []).append(warning)
    for i, r in enumerate(long_runs, 1):
        r["run"] = i
    report["runs"] = long_runs
    report["short_runs_ignored"] = len(runs) - len(long_runs)
    return long_runs


def with_standstill(pick: np.ndarray, used: dict, t: np.ndarray, covered: np.ndarray, v: np.ndarray | None,
                    options: ImportOptions) -> tuple[np.ndarray, dict]:
    """A run's samples with the standstill either side of it (|v| <= min_speed, every stream present,
    up to the next driving or gap, STANDSTILL_KEPT at most): a gyro's bias and a steering offset are
    measured standing still (identification.ordinary_driving._standstill_bias); ``--trim-standstill``
    leaves it out. Said in ``used["how"]`` either way; a time range or a stretch chosen without a run
    is kept as it is."""
    if not used["how"].startswith("run") or v is None or len(t) < 2:
        why = "no speed to find it by" if used["how"].startswith("run") else "the stretch was chosen as it is"
        return pick, _nothing_trimmed(used, options, why)
    idx = np.flatnonzero(pick)
    a, b = int(idx[0]), int(idx[-1]) + 1
    step = float(t[1] - t[0])
    most = int(STANDSTILL_KEPT / step)
    still = covered & (np.abs(v) <= options.min_speed)
    lo, hi = a, b
    while lo > max(0, a - most) and still[lo - 1]:
        lo -= 1
    while hi < min(len(t), b + most) and still[hi]:
        hi += 1
    before, after = (a - lo) * step, (hi - b) * step
    if not before and not after:
        return pick, _nothing_trimmed(used, options, "no standstill beside the run")
    if options.trim_standstill:
        return pick, {**used, "how": f"{used['how']}, the standstill either side ({before:.1f} s before, "
                                     f"{after:.1f} s after) left out (--trim-standstill)"}
    out = np.zeros(len(pick), bool)
    out[lo:hi] = True
    return out, {**used, "start": float(t[lo]), "end": float(t[hi - 1]), "standstill_kept": [before, after],
                 "how": f"{used['how']} with the standstill either side ({before:.1f} s before, {after:.1f} s after, "
                        f"{STANDSTILL_KEPT:g} s at most: "
                        f"a gyro bias and a steering offset are measured standing still; --trim-standstill leaves "
                        f"it out)"}


def _nothing_trimmed(used: dict, options: ImportOptions, why: str) -> dict:
    """``used`` with, when --trim-standstill was asked and nothing was left out, why (never silent)."""
    return {**used, "how": f"{used['how']} (--trim-standstill: nothing left out: {why})"} if options.trim_standstill else used


def _receiver_columns(t: np.ndarray, streams: Streams, report: dict) -> dict[str, np.ndarray]:
    """The receiver's columns at ``t``: x, y east and north of the first fix (pymap3d's
    geodetic -> ENU on WGS-84; the datum in the report), its own (Doppler) speed as gnss_speed or,
    without one, the track's as track_speed, fix_quality held where the receiver gives it (else not written, a note),
    heading (unwrapped, interpolated within its own updates, NaN where it is silent,
    wrapped to (-pi, pi]) and position_std where given."""
    import pymap3d

    gnss = streams.gnss
    columns: dict[str, np.ndarray] = {}
    utc = gnss["utc"].to_numpy(float)
    lat, lon, height = (np.interp(t, utc, gnss[k]) for k in ("lat", "lon", "height"))
    datum = (float(lat[0]), float(lon[0]), float(height[0]))
    columns["x"], columns["y"], _ = pymap3d.geodetic2enu(lat, lon, height, *datum, deg=True)
    report["datum"] = {"latitude_deg": datum[0], "longitude_deg": datum[1], "height_m": datum[2]}
    if np.isfinite(gnss["speed"].to_numpy(float)).mean() > 0.5:      # the receiver's own (Doppler) speed
        columns["gnss_speed"] = np.interp(t, utc, gnss_speed(gnss, streams.breaks))
    else:                                                              # none: the track's, named so
        columns["track_speed"] = np.interp(t, utc, gnss_speed(gnss, streams.breaks))
    quality = gnss["quality"].to_numpy(float)
    if np.isfinite(quality).any():                     # the receiver's word, held; NaN where it says nothing
        columns["fix_quality"] = held(t, utc, quality)
    else:
        report.setdefault("notes", []).append("fix_quality: the recording does not give the receiver's fix quality: "
                                              "not written")
    for extra in ("heading", "position_std"):
        if extra in gnss and np.isfinite(gnss[extra]).sum() >= 2:
            ok = np.isfinite(gnss[extra].to_numpy(float))
            x = gnss[extra].to_numpy(float)[ok]
            columns[extra] = within(t, utc[ok], np.unwrap(x) if extra == "heading" else x)
            if extra == "heading":
                columns[extra] = np.angle(np.exp(1j * columns[extra]))
    return columns


def _fix_positions(t0: float, streams: Streams) -> dict:
    """x, y at the fixes' own stamps (on the log's clock, from ``t0``): as _receiver_columns reads
    them, east and north of the first row's position, of which the rows are the interpolation."""
    import pymap3d

    gnss = streams.gnss
    utc = gnss["utc"].to_numpy(float)
    datum = tuple(float(np.interp(t0, utc, gnss[k])) for k in ("lat", "lon", "height"))
    x, y, _ = pymap3d.geodetic2enu(gnss["lat"].to_numpy(float), gnss["lon"].to_numpy(float),
                                   gnss["height"].to_numpy(float), *datum, deg=True)
    stamps = (utc - t0).tolist()
    return {"x": (stamps, np.asarray(x, float).tolist()), "y": (stamps, np.asarray(y, float).tolist())}


def _standstill_or_silence(report: dict) -> str:
    """Standstill told from silence: how long the vehicle drives, and how much of that a stream is silent."""
    driving, silent = report.get("driving_s", 0.0), report.get("silent_while_driving_s", 0.0)
    if driving <= 0:
        return "the vehicle stands still throughout (a standstill, not a silence)"
    if silent <= 0:
        return f"the vehicle drives {driving:.1f} s in all, in stretches too short"
    return (f"the vehicle drives {driving:.1f} s, {silent:.1f} s of it with a stream silent longer than --max-gap "
            f"(a silence, not a standstill: a larger --max-gap bridges it)")


def _missing_reason(column: str, report: dict) -> str:
    if column in ("x", "y"):
        return ("no positions: no NMEA with a fix, no NavSatFix topic, no TLG position (map a CAN, table or "
                "bag position with --signal lat=...[deg] --signal lon=...[deg], or x=... y=... in metres)")
    return {"delta_cmd": "no steering command in the recording (map one with --signal delta_cmd=...)",
            "delta": "no wheel-angle measurement in the recording (map one with --signal delta=...; a handwheel "
                     "angle with --steering-ratio)",
            "v": "no wheel speed in the recording (the receiver's speed, where there is one, is gnss_speed)",
            "yaw_rate": "no yaw rate (gyro) in the recording (map one with --signal yaw_rate=...)"}[column]


def _choose(source: Path, grid: np.ndarray, u0: float, covered: np.ndarray, long_runs: list, report: dict,
            options: ImportOptions) -> tuple[np.ndarray, dict]:
    """The samples used: a --time-range (refused across a gap), the --run-th run, or the longest."""
    if options.time_range is not None:
        a, b = options.time_range
        pick = (grid - u0 >= a) & (grid - u0 <= b)
        if pick.sum() < 10:
            raise LogError(f"{source}: --time-range {a:g} {b:g}: the recording runs from 0 to "
                           f"{grid[-1] - u0:.1f} s after its start; the range holds {int(pick.sum())} samples")
        holes = pick & ~covered
        if holes.any():
            g = [x for x in report["gaps"] if x["end"] > a and x["start"] < b]
            raise LogError(f"{source}: --time-range {a:g} {b:g} crosses a gap"
                           + (f" ({g[0]['stream']} silent from {g[0]['start']:.2f} to {g[0]['end']:.2f} s)" if g else "")
                           + "; choose a range within one run, or bridge a channel's gap with a larger --max-gap "
                           f"(now {options.max_gap:g} s) (runs: "
                           + ", ".join(f"{r['start']:.1f}-{r['end']:.1f} s" for r in long_runs) + ")")
        return pick, {"how": "time range", "start": float(a), "end": float(b)}
    if not long_runs:
        stretches = [(a, b) for a, b in _stretches(covered) if b - a >= 3]
        if options.run is not None or not stretches:
            raise LogError(f"{source}: no run of {options.min_run:g} s or more with the vehicle driving (speed above "
                           f"{options.min_speed:g} m/s) and every stream present: {_standstill_or_silence(report)}"
                           + ("; gaps: " + ", ".join(f"{g['stream']} {g['start']:.1f}-{g['end']:.1f} s" for g in report['gaps'][:5])
                              if report["gaps"] else ""))
        a, b = max(stretches, key=lambda ab: ab[1] - ab[0])
        pick = np.zeros(len(grid), bool)
        pick[a:b] = True
        report.setdefault("notes", []).append(
            f"no run of {options.min_run:g} s or more with the vehicle driving (above {options.min_speed:g} m/s) and "
            f"every stream present ({_standstill_or_silence(report)}): the longest stretch without a gap is used; a "
            f"diagnosis needs the vehicle driving")
        return pick, {"how": "the longest stretch without a gap (no run long enough: " + _standstill_or_silence(report) + ")",
                      "start": float(grid[a] - u0), "end": float(grid[b - 1] - u0)}
    if options.run is not None and not 1 <= options.run <= len(long_runs):
        raise LogError(f"{source}: --run {options.run}: the recording has {len(long_runs)} run(s): "
                       + ", ".join(f"{r['run']}: {r['start']:.1f}-{r['end']:.1f} s" for r in long_runs))
    r = long_runs[options.run - 1] if options.run else max(long_runs, key=lambda r: r["duration"])
    pick = (grid - u0 >= r["start"] - 1e-9) & (grid - u0 <= r["end"] + 1e-9)
    return pick, {"how": f"run {r['run']}" + ("" if options.run else " (the longest)"), "run": r["run"],
                  "start": r["start"], "end": r["end"]}
