"""Quirks of real recordings, found with robust statistics and named rather than misread.

- Spikes: a sample (or a run of up to ``SPIKE_WIDTH`` samples, or of up to ``BURST_SECONDS`` where the
  signal is sampled faster: no measured wheel angle, speed or yaw rate rises by half its range, holds
  and falls back within 0.15 s, each edge in one sample) far from the running median of its
  neighbours (a window of twice the run plus one: 7 samples, more at high rates),
  |x - median| > d = max(10 x 1.4826 MAD, half the signal's 1-99 % range, 1e-6 max |x|: its rounding),
  more than d from the samples just before and after it, which agree with each other within d:
  the signal leaves and comes back in one sample, a glitch, not a fast manoeuvre (a real peak
  rises through its neighbours; a step is followed by the median and does not come back). They are counted,
  named with their times and masked (dropped before interpolation) unless kept.
- Ranges: the degrees heuristic and every 'reaches' check read the 99.5th percentile of |x|
  (``robust_peak``), so that a few glitches do not make a signal look like degrees.
- Position quantisation: latitude/longitude stored as float32 (a step of about 0.4-0.9 m at
  mid-latitudes) or written with few decimals sit on a grid; the step is read on the raw fixes,
  before any interpolation or resampling could hide it, and carried as x/y resolution.

Imported where used: scipy.ndimage (start-up: 0.035 s CPU on every command, which loads this module
through the reader registry).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from .channel_updates import keep_updates
from .log import LogError, resolution
from .options import ImportOptions
from .streams import Streams, gnss_table, iso

SPIKE_WIDTH = 3
BURST_SECONDS = 0.15               # s: the longest glitch run at high sample rates (module docstring)
SPIKE_SIGMAS = 10.0
SPIKE_RANGE_FRACTION = 0.5
SPIKE_ROUNDING = 1e-6              # of the signal's magnitude: a deviation below it is rounding (float32's is 6e-8)
EARTH_RADIUS = 6_371_000.0
POSITION_SPEED = 100.0             # m/s between two fixes: faster than any ground vehicle, a fix out of place
POSITION_NOISE = 10.0              # m: a step within this is the receiver's noise at any rate
QUANTISATION_REPORTED = 0.01       # m: a position step below this is not worth a note


def spikes(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Indices of the spike samples of x (see the module's rule)."""
    from scipy.ndimage import median_filter

    x = np.asarray(x, float)
    n = len(x)
    if n < 4 * SPIKE_WIDTH + 3:
        return np.array([], int)
    step = float(np.median(np.diff(t))) if len(t) > 1 else 0.0
    width = max(SPIKE_WIDTH, int(BURST_SECONDS / step + 1e-9)) if step > 0 else SPIKE_WIDTH
    width = min(width, (n - 3) // 4)
    window = 2 * width + 1
    med = median_filter(x, size=window, mode="nearest")
    r = x - med
    mad = 1.4826 * float(np.median(np.abs(r - np.median(r))))
    lo, hi = np.percentile(x, [1, 99])
    scale = float(np.nanmax(np.abs(x))) if np.isfinite(x).any() else 0.0
    threshold = max(SPIKE_SIGMAS * mad, SPIKE_RANGE_FRACTION * float(hi - lo), SPIKE_ROUNDING * scale)
    if threshold <= 0:
        return np.array([], int)
    candidates = np.abs(r) > threshold
    out = []
    i = 0
    while i < n:
        if not candidates[i]:
            i += 1
            continue
        j = i
        while j < n and candidates[j]:
            j += 1
        if j - i <= width and 0 < i and j < n:
            before, after, run = x[i - 1], x[j], x[i:j]
            near = min(np.abs(run - before).min(), np.abs(run - after).min())
            if abs(before - after) < threshold and near > threshold:
                out.extend(range(i, j))
        i = j
    return np.array(out, int)


def spike_note(column: str, t: np.ndarray, x: np.ndarray, index: np.ndarray, t0: float, kept: bool) -> dict:
    """The report entry of a column's spikes: count, times from the start, values."""
    return {"column": column, "count": int(len(index)), "kept": kept,
            "times_s": [round(float(t[i] - t0), 3) for i in index[:10]],
            "values": [float(x[i]) for i in index[:10]],
            "typical_range": [float(v) for v in np.percentile(np.delete(x, index), [1, 99])]}


def float32_step(values: np.ndarray) -> float:
    """The float32 spacing at these values when every one of them is a float32, or the shortest
    text of one (a CSV writer's float32 column) (0: not so)."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    if len(v) < 3 or np.all(v == np.round(v)):
        return 0.0
    as32 = v.astype(np.float32)
    exact = np.array_equal(as32.astype(float), v)
    shortest = exact or all(float(str(a)) == b for a, b in zip(as32[:2000], v[:2000]))   # written as float32 text
    if not shortest:
        return 0.0
    return float(np.spacing(np.float32(np.max(np.abs(v)))))


def position_quantisation(lat: np.ndarray, lon: np.ndarray) -> dict | None:
    """{north_m, east_m, how} of raw latitude/longitude fixes on a grid, or None."""
    lat, lon = np.asarray(lat, float), np.asarray(lon, float)
    if len(lat) < 3:
        return None
    how = "latitude/longitude stored as float32"
    q_lat, q_lon = float32_step(lat), float32_step(lon)
    if not (q_lat and q_lon):
        how = "latitude/longitude on a grid (few decimals)"
        q_lat, q_lon = resolution(lat, 1.5), resolution(lon, 1.5)
    if not (q_lat or q_lon):
        return None
    north = math.radians(q_lat) * EARTH_RADIUS
    east = math.radians(q_lon) * EARTH_RADIUS * math.cos(math.radians(float(np.nanmedian(lat))))
    if max(north, east) < QUANTISATION_REPORTED:
        return None
    return {"north_m": north, "east_m": east, "how": how,
            "note": f"positions are quantised: steps of {north:.2f} m north and {east:.2f} m east ({how}); judged on "
                    f"the raw fixes, a resampled or interpolated log does not remove it"}


def _own_speed(sig: dict, t: np.ndarray, notes: list) -> np.ndarray | None:
    """The receiver's own speed over ground (a ``gnss_speed`` column) at the fixes' times ``t``,
    taken out of the signals: the fixes carry it, as a receiver's sentences carry theirs, so that
    the runs, the stops and the course are judged by it (never by the chords of a track that
    wanders at a standstill); None without one. A speed over ground is never negative: a negative
    value is a receiver's "no value" (a phone's -1), left out with the NaNs, counted in ``notes``."""
    if "gnss_speed" not in sig:
        return None
    ts, v = (np.asarray(x, float) for x in sig.pop("gnss_speed"))
    negative = int(np.sum(v < 0))
    if negative:
        notes.append(f"gnss_speed: {negative} negative value(s) (min {float(np.nanmin(v)):.3g}), a receiver's 'no "
                     f"value' (a speed over ground is never negative), left out: the speed there is interpolated "
                     f"from its neighbours")
    ok = np.isfinite(v) & (v >= 0)
    return np.interp(t, ts[ok], v[ok]) if ok.sum() >= 2 else None


def fixes_from_columns(streams: Streams, source: Path) -> Streams:
    """lat/lon columns (a table's, a custom topic's, a CAN GNSS message's) as the receiver's fixes."""
    sig = streams.signals
    if streams.gnss is None and "lat" in sig and "lon" in sig:
        streams.groups.setdefault("gnss", streams.groups.get("lat", "gnss"))     # the fixes keep their file's clock
        t, lat = sig.pop("lat")
        lon = np.interp(t, *sig.pop("lon"))
        height = np.interp(t, *sig.pop("height")) if "height" in sig else None
        speed = _own_speed(sig, t, streams.report.setdefault("notes", []))
        ok = np.isfinite(lat) & np.isfinite(lon) & ((np.abs(lat) > 0) | (np.abs(lon) > 0))
        if ok.sum() < 2:
            raise LogError(f"{source}: the lat/lon columns ({streams.report.get('columns', {}).get('lat', 'lat')}, "
                           f"{streams.report.get('columns', {}).get('lon', 'lon')}) hold {int(ok.sum())} positions: "
                           f"every value is 0 or not a number; expected latitude and longitude in degrees")
        bad = ok & ((np.abs(lat) > 90) | (np.abs(lon) > 180))
        if bad.any():
            raise LogError(f"{source}: lat/lon {lat[bad][0]:g}, {lon[bad][0]:g} are not degrees of latitude/longitude "
                           f"(expected |lat| <= 90, |lon| <= 180; a projected CRS in metres maps to x/y)")
        streams.gnss = gnss_table(t[ok], lat[ok], lon[ok], None if height is None else height[ok],
                                  speed=None if speed is None else speed[ok])
        streams.report.setdefault("columns", {}).update({
            "x": "lat/lon -> east of the run's first fix (pymap3d)", "y": "lat/lon -> north of the run's first fix"})
    elif "lat" in sig or "lon" in sig:
        have = "lat" if "lat" in sig else "lon"
        raise LogError(f"{source}: a {have} column without its {'lon' if have == 'lat' else 'lat'}: positions need both")
    return streams


def find_quirks(streams: Streams, options: ImportOptions) -> Streams:
    """Held channels reduced to their updates (measurements.channel_updates); spikes found (and
    masked unless kept) in every measured signal; position quantisation read on the raw fixes."""
    report = streams.report
    keep_updates(streams, report.get("source", "the recording"))
    t0 = min([float(t[0]) for t, _ in streams.signals.values() if len(t)]
              + ([float(streams.gnss["utc"].iloc[0])] if streams.gnss is not None else []), default=0.0)
    found = []
    for column, (t, x) in list(streams.signals.items()):
        if column in streams.held or column in ("fix_quality",) or len(x) < 20:
            continue
        index = spikes(t, x)
        if len(index):
            found.append(spike_note(column, t, x, index, t0, options.keep_spikes))
            if not options.keep_spikes:
                keep = np.ones(len(t), bool)
                keep[index] = False
                streams.signals[column] = (t[keep], x[keep])
    if found:
        report["spikes"] = found
        report.setdefault("quirks", []).extend(
            f"{s['count']} spike(s) in {s['column']} at {', '.join(f'{v:.2f}' for v in s['times_s'][:5])} s"
            + (" ..." if s["count"] > 5 else "") + f" (values {', '.join(f'{v:.4g}' for v in s['values'][:5])}"
            + (" ..." if len(s["values"]) > 5 else "") + "; "
            f"typical {s['typical_range'][0]:.4g} to {s['typical_range'][1]:.4g}): "
            + ("kept (--keep-spikes)" if s["kept"] else "masked (--keep-spikes keeps them)") for s in found)
    if streams.gnss is not None:
        streams.gnss = _checked_fixes(streams, t0)
        if len(streams.gnss) < 2:                  # no track left: the other channels may still be used
            had = report.get("impossible_fixes", {}).get("count", 0)
            if not streams.signals:
                raise LogError(f"{report.get('source', 'the recording')}: {len(streams.gnss)} usable fix(es): "
                               f"{had} with impossible coordinates (expected |lat| <= 90, |lon| <= 180), and no other "
                               f"channel to make a log of")
            report.setdefault("quirks", []).append(f"{len(streams.gnss)} usable fix(es) ({had} impossible): no "
                                                   f"positions; the other channels are used")
            streams.gnss = None
    if streams.gnss is not None:
        q = position_quantisation(streams.gnss["lat"].to_numpy(float), streams.gnss["lon"].to_numpy(float))
        if q is not None:
            report["position_quantisation"] = q
            report.setdefault("quirks", []).append(q["note"])
            streams.resolution["x"], streams.resolution["y"] = q["east_m"], q["north_m"]
    for column, (t, x) in streams.signals.items():
        streams.resolution.setdefault(column, resolution(x))
    return streams


def _checked_fixes(streams: Streams, t0: float) -> pd.DataFrame:
    """The receiver's fixes without impossible coordinates (|lat| > 90, |lon| > 180, not finite)
    and position spikes (masked, named); a position jump splits the recording (a break)."""
    g = streams.gnss
    report = streams.report
    lat, lon, t = (g[c].to_numpy(float) for c in ("lat", "lon", "utc"))
    impossible = ~(np.isfinite(lat) & np.isfinite(lon) & (np.abs(lat) <= 90) & (np.abs(lon) <= 180))
    if impossible.any():
        i = np.flatnonzero(impossible)
        report.setdefault("quirks", []).append(
            f"{len(i)} fix(es) with impossible coordinates (latitude {lat[i[0]]:g}, longitude {lon[i[0]]:g} deg; "
            f"expected |lat| <= 90, |lon| <= 180) at {', '.join(f'{t[k] - t0:.2f}' for k in i[:5])} s"
            + (" ..." if len(i) > 5 else "") + ": masked")
        report["impossible_fixes"] = {"count": int(len(i)), "times_s": [float(t[k] - t0) for k in i[:50]]}
        g = g.loc[~impossible].reset_index(drop=True)
        lat, lon, t = lat[~impossible], lon[~impossible], t[~impossible]
    if len(t) < 3:
        return g
    spike, jumps, speed = position_outliers(t, lat, lon)
    if spike.any():
        i = np.flatnonzero(spike)
        report.setdefault("quirks", []).append(
            f"{len(i)} position spike(s) (a fix that leaves the track and comes back; implied speed up to "
            f"{float(np.max(speed[i])):.3g} m/s, above {POSITION_SPEED:g} m/s) at "
            f"{', '.join(f'{t[k] - t0:.2f}' for k in i[:5])} s" + (" ..." if len(i) > 5 else "") + ": masked")
        report["position_spikes"] = {"count": int(len(i)), "times_s": [float(t[k] - t0) for k in i[:50]],
                                     "max_speed_m_s": float(np.max(speed[i]))}
    for a, b in jumps:
        if any(k["start"] <= t[a] + 1e-6 and k["end"] >= t[b] - 1e-6 for k in streams.breaks):
            continue                                   # the clock's own step, already split there
        d = EARTH_RADIUS * math.hypot(math.radians(lat[b] - lat[a]),
                                      math.radians(lon[b] - lon[a]) * math.cos(math.radians(float(lat[a]))))
        why = (f"the position jumps {d:.4g} m in {t[b] - t[a]:.3g} s ({d / max(t[b] - t[a], 1e-3):.3g} m/s, above "
               f"{POSITION_SPEED:g} m/s) at {t[b] - t0:.2f} s and stays: the recording is split there")
        streams.breaks.append({"stream": "gnss", "start": float(t[a]), "end": float(t[b]), "why": why,
                               "kind": "position jump"})
    return g.loc[~spike].reset_index(drop=True) if spike.any() else g


def position_outliers(t: np.ndarray, lat: np.ndarray, lon: np.ndarray) -> tuple[np.ndarray, list, np.ndarray]:
    """(spike mask, jumps [(last fix before, first fix after)], implied speed into each fix [m/s]):
    a fix farther from the last good one than POSITION_SPEED x dt + POSITION_NOISE is out; up to
    SPIKE_WIDTH such fixes in a row followed by one back on the track are spikes, more are a jump
    (the track goes on from there)."""
    north = np.radians(lat - lat[0]) * EARTH_RADIUS
    east = np.radians(lon - lon[0]) * EARTH_RADIUS * math.cos(math.radians(float(lat[0])))
    dt = np.maximum(np.diff(t), 1e-3)
    speed = np.concatenate([[0.0], np.hypot(np.diff(east), np.diff(north)) / dt])
    spike = np.zeros(len(t), bool)
    if not np.any(np.hypot(np.diff(east), np.diff(north)) > POSITION_SPEED * dt + POSITION_NOISE):
        return spike, [], speed
    jumps, good, out = [], 0, []
    for i in range(1, len(t)):
        far = math.hypot(east[i] - east[good], north[i] - north[good]) > POSITION_SPEED * (t[i] - t[good]) + POSITION_NOISE
        if not far:
            spike[out] = True
            good, out = i, []
        elif len(out) >= SPIKE_WIDTH:               # it does not come back: a jump, the track goes on from there
            jumps.append((good, out[0]))
            good, out = i, []
        else:
            out.append(i)
    spike[out] = True                       # the last fixes never came back: masked, not trusted
    return spike, jumps, speed


def time_spikes(t: np.ndarray) -> np.ndarray:
    """True at a record whose time is more than J = max(10 typical steps, 1 s) from both its
    neighbours' while they are within J of each other (at the ends: from its one neighbour, the
    next two agreeing)."""
    d = np.diff(t)
    ahead = d[d > 0]
    jump = max(10.0 * float(np.median(ahead)) if len(ahead) else 0.0, 1.0)
    far = np.abs(d) > jump
    lone = np.zeros(len(t), bool)
    if len(t) >= 3:
        lone[1:-1] = far[:-1] & far[1:] & (np.abs(t[2:] - t[:-2]) <= jump)
        lone[0] = far[0] and not far[1]
        lone[-1] = far[-1] and not far[-2]
    return lone


def ordered_in_time(frame: pd.DataFrame, label: str, notes: list[str], same: tuple = ("lat", "lon"),
                    stream: str = "gnss", what: str = "line") -> tuple[pd.DataFrame, list[dict]]:
    """(records in time order, breaks) of records in file order (``utc`` POSIX s, ``line`` the
    file's line or record number, ``what`` says which). A lone record whose time is far from both
    its neighbours', which agree, is a damaged stamp (masked, counted). A record dated at or before
    one already read is either a repeat (same time and ``same`` values: the log written twice;
    dropped and counted) or the clock stepping back;
    those are masked until the time passes the latest one read, named with their count, line and
    times, and the span becomes a break that no run bridges (a splice would join positions that
    are seconds apart as if they were one step apart)."""
    t = frame["utc"].to_numpy(float)
    if len(t) < 2 or bool(np.all(np.diff(t) > 0)):
        return frame, []
    where = frame["line"].to_numpy() if "line" in frame else np.arange(len(t))
    lone = time_spikes(t)
    if lone.any():
        i = np.flatnonzero(lone)
        notes.append(f"{label}: {len(i)} record(s) with a time far from both neighbours' (a damaged time stamp, "
                     f"e.g. {iso(t[i[0]])} between {iso(t[i[0] - 1]) if i[0] > 0 else '-'} and "
                     f"{iso(t[i[0] + 1]) if i[0] + 1 < len(t) else '-'}), the first at {what} {where[i[0]]}: masked")
        frame, t, where = frame.loc[~lone].reset_index(drop=True), t[~lone], where[~lone]
        if len(t) < 2 or bool(np.all(np.diff(t) > 0)):
            return frame, []
    latest = np.maximum.accumulate(t)
    behind = np.zeros(len(t), bool)
    behind[1:] = t[1:] <= latest[:-1]
    keys = [c for c in ("utc", *same) if c in frame]
    repeat = behind & frame.round(9).duplicated(subset=keys, keep="first").to_numpy()
    stepped = behind & ~repeat
    if repeat.any():
        i = int(np.argmax(repeat))
        notes.append(f"{label}: {int(repeat.sum())} record(s) repeat earlier ones (same time and position; the log "
                     f"written twice?), the first at {what} {where[i]}: dropped")
    breaks = []
    ahead = np.diff(t)[np.diff(t) > 0]
    period = float(np.median(ahead)) if len(ahead) else 0.0
    edges = np.diff(np.concatenate([[0], stepped.astype(int), [0]]))
    for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
        before = float(latest[a - 1])
        after = float(t[b]) if b < len(t) else float(t[a:b].max())
        why = (f"the clock steps back {before + period - t[a]:.3g} s at {what} {where[a]} (from {iso(before)} to {iso(t[a])}): "
               f"{b - a} record(s) dated before ones already read are masked, and the recording is split there")
        breaks.append({"stream": stream, "start": before, "end": max(after, before), "why": f"{label}: {why}",
                       "masked": int(b - a)})
    return frame.loc[~behind].reset_index(drop=True), breaks
