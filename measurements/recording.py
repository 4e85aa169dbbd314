"""A raw field recording as one measured log, and a report of how: the readers' dispatcher.

The readers (measurements.raw_nmea, raw_can, rosbag, isoxml_log, tables) each turn their files
into Streams (measurements.streams); this module chooses them by the files it finds, merges NMEA
with CAN on one clock, finds the quirks (measurements.quirks: spikes, position quantisation) and
puts everything on one grid. No reader imports it.

Time base: the receiver's UTC where there is one (a fix is valid at its epoch's time), else the
source's own clock (a logger's boot-time clock is reported as such, never as a 1970 date). Clocks:

- NMEA host stamps: host = U0 + a + b (utc - U0), fitted as the lower envelope of the points (a
  linear programme: every stamp is at or after the line, the sum of distances least), because
  a sentence arrives after its epoch, never before. Drift is b - 1; the latency of each sentence
  beyond the envelope is named (median, 95 %, max). With |a| < ``SYNCED`` the host clock is taken
  to keep UTC and a is the least NMEA latency; otherwise a is mostly the clock's own offset, and
  the least latency cannot be told from it (taken as 0, said so).
- CAN timestamps on the same host clock (their span overlaps the NMEA host stamps): mapped by the
  same line. Otherwise (a logger with its own clock, or NMEA without host stamps) the CAN clock
  is aligned by its content: the CAN speed against the GNSS speed, cross-correlated in windows
  (offset and drift from a line through the windows' lags); a GPS latency cannot be told from a
  clock offset then, and the report says so.

Gaps (a stream silent for more than 3 of its periods and 0.2 s, or without a fix) split the
recording; runs are the stretches where the vehicle drives (|speed| above ``min_speed``, stops
shorter than ``min_stop`` bridged) with every stream present. One run is used: the longest, the
``run``-th, or a ``time_range`` (seconds from the recording's first sample); the report says which.
Positions go to a local east/north plane about the run's first fix (pymap3d, WGS-84). Measured
signals are interpolated linearly onto the log's grid; the set-points are held (the last frame).
"""
from __future__ import annotations

import copy
import math
from collections import Counter
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd

from orchestrator.resolver import resolve

from .log import CANONICAL, LogError, check_log, read_log, resolution
from .quirks import position_quantisation, spike_note, spikes
from .raw_can import CAN_SUFFIXES, CANRecording, choose_sources, load_dbc, merge, read_can_file, series, signal_names
from .raw_nmea import looks_like_nmea, read_nmea_file
from .signals import evaluate, unknown_name
from .streams import Streams, gnss_table, iso
from .tables import TABLE_SUFFIXES

NMEA_SUFFIXES = (".nmea", ".gps", ".nma")
SYNCED = 0.5          # s: a host clock this close to GPS time is taken to keep UTC
HELD = ("delta_cmd", "speed_cmd")  # set-points: held between frames, not interpolated
GAP_PERIODS, GAP_MIN = 3.0, 0.2
HELD_GAP = 1.0        # s: a set-point is sent when it changes, or now and then; in force until the next


@dataclass
class ImportOptions:
    """How to read a recording (the ``convert``/``identify``/``diagnose`` options)."""

    dbc: Path | None = None                     # None: the project's agrobot_tractor.dbc
    signals: list = field(default_factory=list)  # SignalSpec per column (measurements.signals)
    wheelbase: float | None = None              # m: curvature <-> wheel angle (None: the study's, else 1.4)
    rate: float | None = None                   # Hz of the log (default: the GNSS epoch rate)
    run: int | None = None                      # 1-based index of the run to use
    time_range: tuple[float, float] | None = None   # s from the first sample
    min_speed: float = 0.2                      # m/s: driving
    min_stop: float = 3.0                       # s: a shorter stop does not end a run
    min_run: float = 10.0                       # s: shorter runs are listed, not used
    steering_ratio: float | None = None         # recorded steering angles / road-wheel angles (None: the study's, else 1)
    bus: str | None = None                      # the CAN bus to read (candump's can0, a Vector channel)
    time: str | None = None                     # a table's time column(s) (measurements.tables.parse_time)
    keep_spikes: bool = False                   # keep the samples found to be spikes (they are named either way)

    def for_vehicle(self, study=None) -> "ImportOptions":
        """These options with what they leave open taken from the study's [vehicle] table
        (steering_ratio, wheelbase), else its yaw plant's l_f + l_r, else the paper tractor's."""
        vehicle = (study.section("vehicle") if study is not None else None) or {}
        wheelbase = self.wheelbase or vehicle.get("wheelbase")
        model = resolve(study) if wheelbase is None and study is not None else None
        if model is not None and model.find(role="yaw_plant"):
            p = model.parameters(model.find(role="yaw_plant")[0])
            wheelbase = float(p.get("l_f", 1.0)) + float(p.get("l_r", 0.4))
        return replace(self, wheelbase=float(wheelbase or 1.4),
                       steering_ratio=float(self.steering_ratio or vehicle.get("steering_ratio", 1.0)))

    @property
    def maps_a_table(self) -> bool:
        """Options that only a table import uses: a table given with them is not a log as it is."""
        return bool(self.signals) or self.time is not None


BAG_SUFFIXES = (".bag", ".db3", ".mcap")
KINDS = ("nmea", "can", "bag", "isoxml", "table")


def is_recording(source: Path) -> bool:
    """A folder, or a file that is a raw recording rather than a table (CSV/Parquet)."""
    source = Path(source)
    suffix = source.suffix.lower()
    return source.is_dir() or suffix in NMEA_SUFFIXES + CAN_SUFFIXES + BAG_SUFFIXES + (".txt", ".xml", ".bin")


def recording_files(source: Path) -> dict[str, list[Path]]:
    """The files of a folder or the one file, by kind (KINDS): NMEA (a ``.log``/``.txt`` holding
    sentences counts), CAN logs, ROS bags (ROS 1 ``.bag``, ROS 2 ``.db3``/``.mcap`` or a rosbag2
    folder with metadata.yaml), ISO 11783-10 TaskData (TASKDATA.XML, or TLGnnnnn.xml/.bin) and
    tables (CSV, TSV, Parquet)."""
    source = Path(source)
    if not source.exists():
        raise LogError(f"{source}: no such file or folder")
    kinds: dict[str, list[Path]] = {k: [] for k in KINDS}
    if source.is_dir() and (source / "metadata.yaml").is_file():
        kinds["bag"].append(source)                   # a rosbag2 folder is one bag
        return kinds
    files = sorted(p for p in source.iterdir() if p.is_file()) if source.is_dir() else [source]
    for p in files:
        suffix, name = p.suffix.lower(), p.name.upper()
        if suffix in NMEA_SUFFIXES or (suffix in (".log", ".txt") and looks_like_nmea(p)):
            kinds["nmea"].append(p)
        elif suffix in CAN_SUFFIXES:
            kinds["can"].append(p)
        elif suffix in BAG_SUFFIXES:
            kinds["bag"].append(p)
        elif name == "TASKDATA.XML" or (name.startswith("TLG") and suffix in (".xml", ".bin")):
            kinds["isoxml"].append(p)
        elif suffix in TABLE_SUFFIXES:
            kinds["table"].append(p)
    if source.is_dir():
        kinds["bag"] += [d for d in sorted(source.iterdir()) if d.is_dir() and (d / "metadata.yaml").is_file()]
    return kinds

# --- clocks ----------------------------------------------------------------------------------
def lower_envelope(u: np.ndarray, h: np.ndarray) -> tuple[float, float]:
    """(a, b) of the line a + b u below every point (u_i, h_i) with the least summed distance."""
    from scipy.optimize import linprog

    if len(u) < 3 or np.ptp(u) <= 0:
        return float(np.min(h - u)), 1.0
    scale = float(np.ptp(u))
    x = (u - u[0]) / scale
    # maximise sum(a + b x_i) subject to a + b x_i <= h_i
    res = linprog(c=[-len(x), -float(x.sum())], A_ub=np.column_stack([np.ones_like(x), x]), b_ub=h,
                  bounds=[(None, None), (None, None)], method="highs")
    if not res.success:
        slope = 1.0
        return float(np.min(h - slope * (u - u[0]))), slope
    a, b = res.x
    return float(a - b * u[0] / scale), float(b / scale)


def content_lag(t_ref: np.ndarray, x_ref: np.ndarray, t_other: np.ndarray, x_other: np.ndarray,
                step: float = 0.02, window: tuple[float, float] | None = None, search: float | None = None) -> tuple[float, float]:
    """(tau, rho): x_other(t) follows x_ref(t + tau) best (cross-correlation of the mean-removed
    signals on a common ``step`` grid, refined by a parabola through the peak); ``window``
    limits the other signal's time span, ``search`` the lags around 0 (s)."""
    lo, hi = (t_other[0], t_other[-1]) if window is None else window
    grid_o = np.arange(lo, hi, step)
    if len(grid_o) < 20:
        return math.nan, 0.0
    xo = np.interp(grid_o, t_other, x_other)
    xo = xo - xo.mean()
    span = search if search is not None else (t_ref[-1] - t_ref[0]) + (hi - lo)
    grid_r = np.arange(lo - span, hi + span + step, step)
    xr = np.interp(grid_r, t_ref, x_ref, left=np.nan, right=np.nan)
    valid = np.isfinite(xr)
    xr = np.where(valid, xr - np.nanmean(xr), 0.0)
    from scipy.signal import correlate

    num = correlate(xr, xo, mode="valid", method="fft")
    count = correlate(valid.astype(float), np.ones_like(xo), mode="valid", method="fft")
    energy = correlate(xr ** 2, np.ones_like(xo), mode="valid", method="fft")
    ok = count > 0.5 * len(xo)
    rho = np.where(ok, num / np.sqrt(np.maximum(energy, 1e-12) * (xo @ xo)), -np.inf)
    k = int(np.argmax(rho))
    if not np.isfinite(rho[k]):
        return math.nan, 0.0
    frac = 0.0
    if 0 < k < len(rho) - 1 and np.isfinite(rho[k - 1]) and np.isfinite(rho[k + 1]):
        den = rho[k - 1] - 2 * rho[k] + rho[k + 1]
        frac = 0.5 * (rho[k - 1] - rho[k + 1]) / den if den < 0 else 0.0
    return float(grid_r[0] - lo + (k + frac) * step), float(rho[k])




# --- streams -----------------------------------------------------------------------------------
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


def _held(grid: np.ndarray, t: np.ndarray, values: np.ndarray) -> np.ndarray:
    """The value in force at each grid time: the last one sent at or before it (1 ms tolerance)."""
    i = np.clip(np.searchsorted(t, grid + 1e-3, side="right") - 1, 0, len(t) - 1)
    return values[i]



# --- the readers ---------------------------------------------------------------------------------
def _streams(source: Path, options: ImportOptions) -> Streams:
    kinds = recording_files(source)
    if kinds["bag"]:
        from .rosbag import bag_streams

        streams = bag_streams(kinds["bag"], options, source)
    elif kinds["isoxml"]:
        from .isoxml_log import timelog_streams

        streams = timelog_streams(kinds["isoxml"], options, source)
    elif kinds["nmea"] or kinds["can"]:
        streams = _nmea_can_streams(source, options, kinds)
    elif kinds["table"]:
        from .tables import table_streams

        streams = table_streams(kinds["table"], options, source)
    else:
        raise LogError(f"{source}: no recording in it: expected NMEA files (*.nmea, *.gps, or a .log/.txt holding "
                       f"sentences), CAN logs (*.log candump, *.asc, *.blf, *.trc), a ROS bag (*.bag, *.db3, *.mcap, "
                       f"or a rosbag2 folder), an ISO 11783-10 TaskData (TASKDATA.XML with TLG files) or tables "
                       f"(*.csv, *.tsv, *.parquet)")
    ignored = [p.name for k in ("table",) for p in kinds[k] if streams.report.get("files", {}).get(k) is None]
    if ignored and kinds["table"] and streams.report.get("files", {}).get("table") is None:
        streams.report.setdefault("notes", []).append(f"tables beside the recording not read: {', '.join(ignored[:6])}")
    return _steered(_quirks(_positions(streams, source), options), options)


def _positions(streams: Streams, source: Path) -> Streams:
    """lat/lon columns (a table's, a custom topic's, a CAN GNSS message's) as the receiver's fixes."""
    sig = streams.signals
    if streams.gnss is None and "lat" in sig and "lon" in sig:
        t, lat = sig.pop("lat")
        lon = np.interp(t, *sig.pop("lon"))
        height = np.interp(t, *sig.pop("height")) if "height" in sig else None
        ok = np.isfinite(lat) & np.isfinite(lon) & ((np.abs(lat) > 0) | (np.abs(lon) > 0))
        if ok.sum() < 2:
            raise LogError(f"{source}: the lat/lon columns hold {int(ok.sum())} positions")
        bad = ok & ((np.abs(lat) > 90) | (np.abs(lon) > 180))
        if bad.any():
            raise LogError(f"{source}: lat/lon {lat[bad][0]:g}, {lon[bad][0]:g} are not degrees of latitude/longitude "
                           f"(expected |lat| <= 90, |lon| <= 180; a projected CRS in metres maps to x/y)")
        streams.gnss = gnss_table(t[ok], lat[ok], lon[ok], None if height is None else height[ok])
        streams.report.setdefault("columns", {}).update({
            "x": "lat/lon -> east of the run's first fix (pymap3d)", "y": "lat/lon -> north of the run's first fix"})
    elif "lat" in sig or "lon" in sig:
        have = "lat" if "lat" in sig else "lon"
        raise LogError(f"{source}: a {have} column without its {'lon' if have == 'lat' else 'lat'}: positions need both")
    return streams


def _quirks(streams: Streams, options: ImportOptions) -> Streams:
    """Spikes found (and masked unless kept) in every measured signal; position quantisation
    read on the raw fixes."""
    report = streams.report
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
            + (" ..." if s["count"] > 5 else "") + f" (values {', '.join(f'{v:.4g}' for v in s['values'][:3])}; "
            f"typical {s['typical_range'][0]:.4g} to {s['typical_range'][1]:.4g}): "
            + ("kept (--keep-spikes)" if s["kept"] else "masked (--keep-spikes keeps them)") for s in found)
    if streams.gnss is not None:
        q = position_quantisation(streams.gnss["lat"].to_numpy(float), streams.gnss["lon"].to_numpy(float))
        if q is not None:
            report["position_quantisation"] = q
            report.setdefault("quirks", []).append(q["note"])
            streams.resolution["x"], streams.resolution["y"] = q["east_m"], q["north_m"]
    for column, (t, x) in streams.signals.items():
        streams.resolution.setdefault(column, resolution(x))
    return streams


def _nmea_can_streams(source: Path, options: ImportOptions, kinds: dict[str, list[Path]]) -> Streams:
    nmea_files, can_files = kinds["nmea"], kinds["can"]
    dbc_name = str(options.dbc) if options.dbc else "the project's agrobot_tractor.dbc"
    db, dbc_report = load_dbc(options.dbc) if can_files else (None, None)
    nmea = [read_nmea_file(p) for p in nmea_files]
    cans = [read_can_file(p, db, options.bus) for p in can_files]
    report: dict = {"source": str(source), "files": {"nmea": [str(n.path) for n in nmea], "can": [str(c.path) for c in cans]},
                    "dbc": dbc_name if cans else None, "notes": [x for n in nmea for x in n.notes]}
    if dbc_report is not None:
        report["dbc_load"] = dbc_report.as_dict()
    gnss, epochs, u0 = None, None, None
    if nmea:
        epochs = pd.concat([n.epochs for n in nmea]).sort_values("utc").drop_duplicates("utc").reset_index(drop=True)
        fix = epochs["quality"].to_numpy() > 0
        if fix.sum() < 2 and not cans:
            raise LogError(f"{source}: {int(fix.sum())} GNSS epochs with a fix ({len(epochs)} epochs); a recording of "
                           f"NMEA alone needs positions")
        counts: Counter = Counter()
        for n in nmea:
            counts.update(n.counts)
        quality = epochs["quality"].value_counts().sort_index()
        report["nmea"] = {"epochs": int(len(epochs)), "with_fix": int(fix.sum()),
                          "by_quality": {str(int(k)): int(v) for k, v in quality.items()},
                          "rate_hz": float(1.0 / np.median(np.diff(epochs["utc"]))) if len(epochs) > 1 else math.nan,
                          "sentences": dict(counts)}
        if fix.sum() >= 2:
            gnss = epochs.loc[fix].reset_index(drop=True)
            u0 = float(gnss["utc"].iloc[0])
            report["first_fix_utc"] = iso(u0)
        else:
            report["notes"].append(f"the NMEA holds {int(fix.sum())} epochs with a fix: no positions")
    raw: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    units: dict[str, str] = {}
    if cans:
        raw, units = _can_signals(source, cans, db, dbc_name, options, report)
    report["columns"] = dict(units)
    if gnss is not None:
        report["columns"].update({"x": "NMEA GGA latitude/longitude -> east of the run's first fix (pymap3d)",
                                  "y": "NMEA GGA latitude/longitude -> north of the run's first fix (pymap3d)",
                                  "t": "receiver UTC (GGA), s from the run's start"})
    if raw and gnss is not None:
        report["clocks"], to_utc = _clocks(epochs, raw, u0, gnss)
        raw = {c: (to_utc(t), v) for c, (t, v) in raw.items()}
    elif raw:
        lo = min(float(t[0]) for t, _ in raw.values())
        report["clocks"] = {"reference": "the CAN logger's clock (no NMEA with a fix: not GPS time)"
                                         + ("" if lo > 1e8 else "; it counts from the logger's start, not a date"),
                            "can_clock": {"method": "the time base itself", "offset_s": 0.0, "drift_ppm": 0.0,
                                          "posix": lo > 1e8}}
        report["columns"]["t"] = "the CAN logger's timestamps, s from the run's start"
    else:
        report["clocks"] = {"reference": "receiver UTC (NMEA GGA time and RMC/ZDA date)"}
    return Streams(gnss, raw, report, set(HELD) & set(raw), {})


def _can_signals(source: Path, cans: list[CANRecording], db, dbc_name: str, options: ImportOptions, report: dict):
    """Column -> (logger time, values in the column's unit) of every column the DBC (or --signal) gives, and how."""
    sources, unmapped, guessed = choose_sources(db, dbc_name, list(options.signals))
    report["can"] = {"frames": int(sum(c.counts["frames"] for c in cans)),
                     "decoded": int(sum(c.counts["decoded"] for c in cans)),
                     "unknown_ids": dict(sum((c.unknown_ids for c in cans), Counter()).most_common(8)),
                     "not_decoded": int(sum(c.counts["frames that do not decode"] for c in cans)),
                     "buses": dict(sum((c.buses for c in cans), Counter())),
                     "messages": {}, "columns_without_a_signal": unmapped}
    for c in cans:
        report["can"].setdefault("outside_declared_range", {}).update(c.outside_range)
        report["can"].setdefault("j1939_not_available", {}).update(c.not_available)
    if options.bus is not None:
        report["can"]["bus"] = options.bus
    frames = merge(cans)
    known = signal_names(db)
    raw, units = {}, {}
    given_columns = {g.column for g in options.signals}
    for column, spec in sources.items():
        found = {}
        for name in spec.names:
            s = series(db, frames, name)
            if s is None:
                raise unknown_name(f"{source} (DBC {dbc_name})", spec, name, known)
            found[name] = s
        short = [n for n, s in found.items() if len(s.t) < 10]
        if short:
            what = (f"the CAN logs hold {len(found[short[0]].t)} frames with {short[0]} (column {column!r}, DBC "
                    f"{dbc_name}); messages found: {', '.join(sorted(frames)[:12]) or 'none'}"
                    + (f"; unknown identifiers: {', '.join(report['can']['unknown_ids'])}" if report['can']['unknown_ids'] else ""))
            if column in given_columns:
                raise LogError(f"{source}: {what}")
            report["can"]["columns_without_a_signal"][column] = what
            continue
        t, values, text = evaluate(spec, found, f"{source} (DBC {dbc_name})", options.wheelbase or 1.4)
        raw[column] = (t, values)
        units[column] = text + ("; matched by name and unit (--signal to choose another)" if column in guessed else "")
        for name in spec.names:
            message = name.rsplit(".", 1)[0]
            tm = frames[message]["t"].to_numpy(float)
            report["can"]["messages"][message] = {"frames": int(len(tm)),
                                                  "rate_hz": float(1.0 / np.median(np.diff(tm))) if len(tm) > 1 else math.nan}
    if not raw:
        unknown = report["can"]["unknown_ids"]
        raise LogError(f"{source}: no CAN frame decodes to a column of the log with {dbc_name} "
                       f"({report['can']['decoded']} of {report['can']['frames']} frames decoded"
                       + (f"; unknown identifiers: {', '.join(unknown)}" if unknown else "")
                       + "); give the vehicle's DBC with --dbc, and map signals with --signal COLUMN=Message.Signal")
    return raw, units


def _steered(streams: Streams, options: ImportOptions) -> Streams:
    """Handwheel angles to road-wheel angles: delta and delta_cmd divided by the steering ratio."""
    if not options.steering_ratio or options.steering_ratio == 1.0:
        return streams
    for column in ("delta_cmd", "delta"):
        if column in streams.signals:
            t, v = streams.signals[column]
            streams.signals[column] = (t, v / options.steering_ratio)
            streams.resolution[column] = streams.resolution.get(column, 0.0) / options.steering_ratio
            streams.report.setdefault("columns", {})[column] = (streams.report.get("columns", {}).get(column, column)
                                                                 + f"; / steering ratio {options.steering_ratio:g} "
                                                                   f"(handwheel -> road wheel)")
    return streams


def _gnss_speed(gnss: pd.DataFrame) -> np.ndarray:
    """Speed over ground per epoch: RMC/VTG where given, else from 1 s position chords."""
    speed = gnss["speed"].to_numpy(float)
    if np.isfinite(speed).mean() > 0.5:
        return np.interp(gnss["utc"], gnss["utc"][np.isfinite(speed)], speed[np.isfinite(speed)])
    north = np.radians(gnss["lat"].to_numpy() - gnss["lat"].iloc[0]) * 6.371e6      # a sphere is enough for a speed
    east = np.radians(gnss["lon"].to_numpy() - gnss["lon"].iloc[0]) * 6.371e6 * math.cos(math.radians(gnss["lat"].iloc[0]))
    return np.hypot(np.gradient(east, gnss["utc"]), np.gradient(north, gnss["utc"]))


def _clocks(epochs: pd.DataFrame, raw: dict, u0: float, gnss: pd.DataFrame):
    """The clocks' report and the map from CAN time to UTC."""
    out: dict = {"reference": "receiver UTC (NMEA GGA time and RMC/ZDA date)"}
    host = epochs["host"].to_numpy(float)
    utc = epochs["utc"].to_numpy(float)
    have_host = np.isfinite(host)
    can_lo = min(float(t[0]) for t, _ in raw.values())
    can_hi = max(float(t[-1]) for t, _ in raw.values())
    line = None
    if have_host.sum() >= 10:
        u, h = utc[have_host], host[have_host]
        a, b = lower_envelope(u - u0, h - u0)
        late = (h - u0) - (a + b * (u - u0))
        synced = abs(a) < SYNCED
        out["nmea_host_clock"] = {
            "offset_s": a, "drift_ppm": (b - 1.0) * 1e6,
            "interpretation": ("the host clock keeps GPS time (offset below 0.5 s): the offset is the least NMEA "
                               "latency" if synced else
                               "the host clock is off GPS time by the offset; the least NMEA latency cannot be told "
                               "from it and is taken as 0"),
            "nmea_latency_s": {"least": a if synced else 0.0, "median": float(np.median(late)) + (a if synced else 0.0),
                               "p95": float(np.percentile(late, 95)) + (a if synced else 0.0),
                               "max": float(late.max()) + (a if synced else 0.0)}}
        if can_hi > h.min() - 60 and can_lo < h.max() + 60:
            line = (0.0, 1.0) if synced else (a, b)
    if line is not None:
        a, b = line
        out["can_clock"] = {"method": "same host clock as the NMEA stamps", "offset_s": a, "drift_ppm": (b - 1.0) * 1e6}
        return out, (lambda t: u0 + (t - u0 - a) / b)
    # an independent clock: align the CAN speed on the GNSS speed
    if "v" not in raw:
        raise LogError("the CAN log's clock is not the NMEA host clock and the CAN log carries no speed to align it on "
                       "the GNSS speed: record NMEA with host timestamps on the CAN logger's clock, or a speed on CAN")
    t_can, v_can = raw["v"]
    speed = _gnss_speed(gnss)
    t_ref = gnss["utc"].to_numpy(float)
    start = t_ref[0] - t_can[0]                   # both clocks started together, then the content decides
    tau, rho = content_lag(t_ref, speed, t_can + start, v_can)
    tau += start
    if not math.isfinite(tau) or rho < 0.5:
        raise LogError(f"the CAN log's clock ({iso(can_lo)} ...) is not the NMEA "
                       f"host clock and its speed does not match the GNSS speed (best correlation {rho:.2f}): cannot "
                       f"place the CAN data in time; record NMEA with host timestamps on the CAN logger's clock")
    windows, lags = [], []
    for lo in np.arange(t_can[0], t_can[-1] - 60.0, 60.0):
        lag, r = content_lag(t_ref, speed, t_can + tau, v_can, window=(lo + tau, lo + tau + 120.0), search=2.0)
        lag_abs = tau + lag if math.isfinite(lag) else math.nan
        if r > 0.8 and math.isfinite(lag_abs):
            windows.append(lo + 60.0)
            lags.append(lag_abs)
    drift = 0.0
    if len(windows) >= 5:          # a drift only where the windows' lags resolve it (slope > 3 standard errors)
        x = np.array(windows) - t_can[0]
        fit, cov = np.polyfit(x, lags, 1, cov=True)
        if abs(fit[0]) > 3.0 * math.sqrt(max(cov[0, 0], 0.0)):
            drift, tau = float(fit[0]), float(fit[1])
    t_start = float(t_can[0])

    def tau_at(t):
        return tau + drift * (t - t_start)
    out["can_clock"] = {"method": "independent clock, aligned by the CAN speed against the GNSS speed "
                                  "(a GPS latency cannot be told from this offset)",
                        "offset_s": float(tau), "drift_ppm": drift * 1e6, "correlation": rho, "windows": len(windows)}
    return out, (lambda t: t + tau_at(t))




def import_recording(source: str | Path, options: ImportOptions | None = None) -> tuple[pd.DataFrame, dict]:
    """(canonical log t, delta_cmd, delta, v, yaw_rate, x, y; the import report)."""
    options = (options or ImportOptions()).for_vehicle()
    return _assemble(Path(source), _checked(Path(source), options), options)


def import_runs(source: str | Path, options: ImportOptions | None = None) -> list[tuple[pd.DataFrame, dict]]:
    """Every run of a recording as (log, report), the files read once."""
    source, options = Path(source), (options or ImportOptions()).for_vehicle()
    streams = _checked(source, options)
    first = _assemble(source, streams, options)
    return [first if r["run"] == first[1]["used"].get("run") else _assemble(source, streams, replace(options, run=r["run"]))
            for r in first[1]["runs"]]


def _checked(source: Path, options: ImportOptions) -> Streams:
    if options.rate is not None and not 1.0 <= options.rate <= 200.0:
        raise LogError(f"--rate {options.rate:g}: expected 1 to 200 Hz")
    return _streams(source, options)


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


def _assemble(source: Path, streams: Streams, options: ImportOptions) -> tuple[pd.DataFrame, dict]:
    """The log on its grid for the run or range ``options`` choose, and the report of it: every
    canonical column the recording holds, then the extras (the receiver's speed, fix quality,
    heading and position error, and any other mapped signal); the missing columns are named."""
    gnss, sig, report = streams.gnss, streams.signals, copy.deepcopy(streams.report)
    # the streams that set the log's span and its gaps: the positions and the canonical columns
    # (an extra column, logged now and then, is held or interpolated within that span)
    times = ([("gnss", gnss["utc"].to_numpy(float))] if gnss is not None else []) + \
        [(c, t) for c, (t, _) in sig.items() if c in CANONICAL]
    times = times or [(c, t) for c, (t, _) in sig.items()]
    if not times:
        raise LogError(f"{source}: nothing with a time stamp in it")
    u0 = float(gnss["utc"].iloc[0]) if gnss is not None else min(float(t[0]) for _, t in times)
    step = _grid_step(streams, options)
    lo, hi = max(float(t[0]) for _, t in times), min(float(t[-1]) for _, t in times)
    least = {name: HELD_GAP if name in streams.held else GAP_MIN for name, _ in times}
    report["gaps"] = sum((gaps(t, name, u0, least[name]) for name, t in times), [])
    if hi - lo < 2 * step:
        spans = ", ".join(f"{name} {t[0] - u0:.1f}-{t[-1] - u0:.1f} s" for name, t in times)
        raise LogError(f"{source}: the streams overlap for {max(hi - lo, 0):.3g} s ({spans}); nothing to align")
    grid = u0 + step * np.arange(math.ceil((lo - u0) / step - 1e-9), math.floor((hi - u0) / step + 1e-9) + 1)
    covered = np.ones(len(grid), bool)
    for name, t in times:
        covered &= _covered(t, grid, least[name])
    if "v" in sig:
        v, report["runs_by"] = np.interp(grid, *sig["v"]), "the speed column v"
    elif gnss is not None:
        v, report["runs_by"] = np.interp(grid, gnss["utc"], _gnss_speed(gnss)), "the receiver's speed over ground"
    else:
        v, report["runs_by"] = None, "no speed in the recording: every stretch without a gap is a run"
    moving = np.abs(v) > options.min_speed if v is not None else np.ones(len(grid), bool)   # reversing drives too
    for a, b in _stretches(~moving):                 # short stops do not end a run
        if 0 < a and b < len(grid) and (b - a) * step < options.min_stop:
            moving[a:b] = True
    runs = []
    for a, b in _stretches(moving & covered):
        runs.append({"start": float(grid[a] - u0), "end": float(grid[b - 1] - u0), "duration": float((b - a) * step),
                     "mean_speed": float(v[a:b].mean()) if v is not None else math.nan, "utc_start": iso(grid[a])})
    long_runs = [r for r in runs if r["duration"] >= options.min_run]
    for i, r in enumerate(long_runs, 1):
        r["run"] = i
    report["runs"] = long_runs
    report["short_runs_ignored"] = len(runs) - len(long_runs)
    pick, used = _choose(source, grid, u0, covered, long_runs, report, options)
    report["used"] = {**used, "duration": float(pick.sum() * step), "utc_start": iso(grid[pick][0]),
                      "utc_start_s": float(grid[pick][0])}
    t = grid[pick]
    columns: dict[str, np.ndarray] = {"t": step * np.arange(len(t))}      # whole steps: no rounding creep
    for c in CANONICAL[1:]:
        if c in sig:
            columns[c] = _held(t, *sig[c]) if c in streams.held else np.interp(t, *sig[c])
    if gnss is not None:
        import pymap3d

        utc = gnss["utc"].to_numpy(float)
        lat, lon, height = (np.interp(t, utc, gnss[k]) for k in ("lat", "lon", "height"))
        datum = (float(lat[0]), float(lon[0]), float(height[0]))
        columns["x"], columns["y"], _ = pymap3d.geodetic2enu(lat, lon, height, *datum, deg=True)
        report["datum"] = {"latitude_deg": datum[0], "longitude_deg": datum[1], "height_m": datum[2]}
        if np.isfinite(gnss["speed"].to_numpy(float)).mean() > 0.5:      # the receiver's own (Doppler) speed
            columns["gnss_speed"] = np.interp(t, utc, _gnss_speed(gnss))
        else:                                                              # none: the track's, named so
            columns["track_speed"] = np.interp(t, utc, _gnss_speed(gnss))
        columns["fix_quality"] = _held(t, utc, gnss["quality"].to_numpy(float))
        for extra in ("heading", "position_std"):
            if extra in gnss and np.isfinite(gnss[extra]).sum() >= 2:
                ok = np.isfinite(gnss[extra].to_numpy(float))
                x = gnss[extra].to_numpy(float)[ok]
                columns[extra] = np.interp(t, utc[ok], np.unwrap(x) if extra == "heading" else x)
                if extra == "heading":
                    columns[extra] = np.angle(np.exp(1j * columns[extra]))
    for c, (tc, vc) in sig.items():
        if c not in columns:
            columns[c] = _held(t, tc, vc) if c in streams.held else np.interp(t, tc, vc)
    report["rate_hz"] = 1.0 / step
    report["resolution"] = {c: float(streams.resolution.get(c, 0.0)) for c in list(sig) + ["x", "y"]
                            if c in sig or c in streams.resolution}
    present = [c for c in CANONICAL if c in columns]
    report["present"] = present + [c for c in columns if c not in CANONICAL]
    why = report.get("can", {}).get("columns_without_a_signal", {})
    report["missing"] = {c: why.get(c, _missing_reason(c, report)) for c in CANONICAL if c not in columns}
    order = present + [c for c in columns if c not in CANONICAL]
    return pd.DataFrame(columns)[order], report


def _missing_reason(column: str, report: dict) -> str:
    if column in ("x", "y"):
        return "no positions: no NMEA with a fix, no NavSatFix topic, no TLG position"
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
                           + "; choose a range within one run (runs: "
                           + ", ".join(f"{r['start']:.1f}-{r['end']:.1f} s" for r in long_runs) + ")")
        return pick, {"how": "time range", "start": float(a), "end": float(b)}
    if not long_runs:
        stretches = [(a, b) for a, b in _stretches(covered) if b - a >= 3]
        if options.run is not None or not stretches:
            raise LogError(f"{source}: no run of {options.min_run:g} s or more with the vehicle driving (speed above "
                           f"{options.min_speed:g} m/s) and every stream present"
                           + ("; gaps: " + ", ".join(f"{g['stream']} {g['start']:.1f}-{g['end']:.1f} s" for g in report['gaps'][:5])
                              if report["gaps"] else ""))
        a, b = max(stretches, key=lambda ab: ab[1] - ab[0])
        pick = np.zeros(len(grid), bool)
        pick[a:b] = True
        report.setdefault("notes", []).append(
            f"no run of {options.min_run:g} s or more with the vehicle driving (above {options.min_speed:g} m/s): "
            f"the longest stretch without a gap is used; a diagnosis needs the vehicle driving")
        return pick, {"how": "the longest stretch without a gap (the vehicle does not drive)",
                      "start": float(grid[a] - u0), "end": float(grid[b - 1] - u0)}
    if options.run is not None and not 1 <= options.run <= len(long_runs):
        raise LogError(f"{source}: --run {options.run}: the recording has {len(long_runs)} run(s): "
                       + ", ".join(f"{r['run']}: {r['start']:.1f}-{r['end']:.1f} s" for r in long_runs))
    r = long_runs[options.run - 1] if options.run else max(long_runs, key=lambda r: r["duration"])
    pick = (grid - u0 >= r["start"] - 1e-9) & (grid - u0 <= r["end"] + 1e-9)
    return pick, {"how": f"run {r['run']}" + ("" if options.run else " (the longest)"), "run": r["run"],
                  "start": r["start"], "end": r["end"]}


def describe(report: dict) -> str:
    """A few lines for the terminal: files, clocks, gaps, runs, what was used, what is missing."""
    files = report["files"]
    parts = [f"{len(v)} {k} file(s)" for k, v in files.items() if v]
    lines = [f"recording {report['source']}: {', '.join(parts) or 'no files'}"
             + (f", DBC {report['dbc']}" if report.get("dbc") else "")]
    c = report.get("clocks", {})
    if "nmea_host_clock" in c:
        h = c["nmea_host_clock"]
        lat = h["nmea_latency_s"]
        lines.append(f"  host clock - GPS time: {h['offset_s']:+.4f} s, drift {h['drift_ppm']:+.1f} ppm; NMEA latency "
                     f"median {1e3 * lat['median']:.1f} ms, 95% {1e3 * lat['p95']:.1f} ms, max {1e3 * lat['max']:.1f} ms")
    if "can_clock" in c:
        k = c["can_clock"]
        lines.append(f"  CAN clock: {k['method']}; offset {k['offset_s']:+.4f} s, drift {k['drift_ppm']:+.1f} ppm")
    elif c.get("reference"):
        lines.append(f"  time base: {c['reference']}")
    g = report["gaps"]
    lines.append(f"  gaps: {len(g)}" + (": " + ", ".join(f"{x['stream']} {x['start']:.2f}-{x['end']:.2f} s"
                                                         for x in g[:4]) + (" ..." if len(g) > 4 else "") if g else ""))
    lines.append("  runs: " + (", ".join(f"{r['run']}: {r['start']:.1f}-{r['end']:.1f} s"
                                          + (f" ({r['mean_speed']:.2f} m/s)" if math.isfinite(r["mean_speed"]) else "")
                                          for r in report["runs"][:8]) or "none")
                 + (f" ... ({len(report['runs'])} runs)" if len(report["runs"]) > 8 else ""))
    u = report["used"]
    lines.append(f"  used: {u['how']}, {u['start']:.2f}-{u['end']:.2f} s after the start ({u['utc_start']}), "
                 f"{u['duration']:.1f} s at {report['rate_hz']:g} Hz")
    lines.append(f"  columns: {', '.join(report.get('present', []))}")
    load = report.get("dbc_load") or {}
    if load.get("repairs") or load.get("messages_left_out"):
        left = load.get("messages_left_out", {})
        lines.append(f"  DBC: {load['loader']}; " + ", ".join(f"{k} ({v})" for k, v in load.get("repairs", {}).items())
                     + (f"; left out: {', '.join(list(left)[:6])}{' ...' if len(left) > 6 else ''}" if left else ""))
    outside = report.get("can", {}).get("outside_declared_range", {})
    for name, o in list(outside.items())[:6]:
        lines.append(f"  plausibility: {name}: {o['outside']} of {o['of']} values outside the DBC's declared "
                     f"[{o['declared'][0]:g}|{o['declared'][1]:g}] (seen {o['seen'][0]:.4g} to {o['seen'][1]:.4g}; kept)")
    for quirk in report.get("quirks", []):
        lines.append(f"  quirk: {quirk}")
    for note in report.get("notes", []):
        lines.append(f"  note: {note}")
    for column, why in report.get("missing", {}).items():
        lines.append(f"  missing {column}: {why}")
    return "\n".join(lines)


def load_log(source: str | Path, required: tuple[str, ...] = ("t",), resample_jitter: bool = False,
             recording=None) -> tuple[pd.DataFrame, dict | None]:
    """(log, import report): a table (CSV/Parquet) through read_log, or a raw field recording
    (a folder of NMEA files and CAN logs, or one such file) through
    measurements.recording.import_recording with ``recording`` (ImportOptions), then the same
    checks. The report is None for a table."""
    source = Path(source)
    if not is_recording(source) and not (recording is not None and recording.maps_a_table):
        return read_log(source, required, resample_jitter), None
    frame, report = import_recording(source, recording)
    where = f"{source} ({report['used']['how']}, {report['used']['start']:.1f}-{report['used']['end']:.1f} s)"
    frame = check_log(frame, where, required, resample_jitter)
    frame.attrs["resolution"] = dict(report.get("resolution", {}))
    return frame, report


def positions(source: str | Path, options: ImportOptions | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
    """(times [s], latitude, longitude [deg], report) of every fix of a recording, whole (no run
    chosen): the track a field is made of."""
    source = Path(source)
    options = (options or ImportOptions()).for_vehicle()
    streams = _checked(source, options)
    if streams.gnss is None:
        raise LogError(f"{source}: no positions in it (NMEA with a fix, a NavSatFix topic, a TLG position, or "
                       f"lat/lon columns: --signal lat=TABLE.COLUMN --signal lon=TABLE.COLUMN)")
    g = streams.gnss
    report = streams.report
    width = [v for c, (_, v) in streams.signals.items() if c.startswith("ddi0067")]   # ISO 11783 actual working width, mm
    if width and np.isfinite(width[0]).any():
        report["working_width_m"] = float(np.nanmedian(width[0])) / 1000.0
    return g["utc"].to_numpy(float), g["lat"].to_numpy(float), g["lon"].to_numpy(float), report
