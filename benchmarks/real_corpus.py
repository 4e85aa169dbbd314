"""Real machines of five classes, each read twice: by a second method on the raw files (numpy and
pandas, no agrobot) and by the project (agrobot.api.convert's audit, agrobot.api.identify):

    python3 benchmarks/real_corpus.py [--manifest benchmarks/real_corpus.toml] [--only NAME]
        [--timeout SECONDS] [--realdata DIR] [--corpus DIR] [--no-identify]

The recordings, their vehicles, licences, origins and how the project reads each are listed in
benchmarks/real_corpus.toml (docs/real_corpus.md). Per recording and quantity one row: the
reference number, the project's, and whether they agree:

* rate of each key channel: the reference bounds the channel's own updates by its value changes
  (a held value is not an update) and by those plus the repeats its grid explains (rates), beside
  its rows; a fix's fields count together and only while the machine moves (fix_rates); the
  project's is the audit's rate for that column; they agree when it lies in that range, 25 %
  allowed beyond either end.
* reversing: the share of moving time (|v| > 0.2 m/s, by the speed channel where there is one and
  by the fixes' own displacement: a standing receiver's jitter makes a course) driven backwards,
  from a signed speed or from the course against the heading, on the stretch the converted log keeps (reversing_like_log); the
  project's is the share of v < 0 in the converted log.
* yaw/kinematic slope: the regression of the yaw rate on v tan(delta/N)/L (N the steering ratio, L
  the wheelbase as published), |v| > 0.2 m/s, at the lag of the best correlation, on the samples
  whose tyres are linear (kinematic); beside the slope identify's steering gain and understeer
  gradient predict on those samples (steady_slope; agree within 30 %).
* command-to-yaw lag: that lag, found by cross-correlation over -1..1 s: the whole lag, of which
  identify's delay plus its lag is a part (delay_rows: within it, 0.08 s either side; a delay on its
  zero bound does not agree); the audit's response lag beside.
* identify's understeer gradient and held-out fit, the audit's findings and the published figures,
  printed without a verdict.

Every exception of a recording is caught and printed as its row: what fails today is information.
"""
from __future__ import annotations

import argparse
import math
import re
import signal
import sys
import time
import tomllib
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parent.parent
ROOTS = {"realdata": Path("/work/shared/realdata"), "corpus": Path("/work/corpus_data")}
MOVING = 0.2            # m/s: moving, for the reversing share
KINEMATIC_MIN_SPEED = 0.2   # m/s: the slope and the delay are computed above it
NOT_CHANNELS = ("commands", "samples", "clock")   # [recording.reference] lists that are not channels
GRID = 0.02             # s: the common grid of the slope and the cross-correlation
G_ACC = 9.81            # m/s2


# --- the second method: the raw files, read with pandas ---------------------------------------
def _column(frame: pd.DataFrame, name: str) -> np.ndarray:
    """A column by name, or by 0-based index written '#N'."""
    if name.startswith("#"):
        return pd.to_numeric(frame.iloc[:, int(name[1:])], errors="coerce").to_numpy(float)
    return pd.to_numeric(frame[name], errors="coerce").to_numpy(float)


TIME_UNITS = {"[ms]": 1e-3, "[us]": 1e-6, "[ns]": 1e-9}


def _times(folder: Path, spec: str, frame: pd.DataFrame, read) -> np.ndarray:
    """A table's times: 's+ns' (seconds plus nanoseconds), 'FILE:COLUMN' (another file's), a column
    (in seconds, or 'COLUMN[ms]', '[us]', '[ns]')."""
    if spec == "s+ns":
        return _column(frame, "s") + 1e-9 * _column(frame, "ns")
    unit = next((u for u in TIME_UNITS if spec.endswith(u)), None)
    if unit is not None:
        return _times(folder, spec[: -len(unit)], frame, read) * TIME_UNITS[unit]
    if ":" in spec:
        other, col = spec.split(":")
        return _column(read(folder / other), col)
    return _column(frame, spec)


def read_tables(folder: Path, ref: dict) -> dict:
    """channel -> (t, x) in SI from [file, time, column, scale(, offset)] per channel."""
    header = None if ref.get("header") == "none" else "infer"
    sep = r"\s+" if ref.get("sep") == "whitespace" else ","
    cache: dict = {}

    def read(path: Path) -> pd.DataFrame:
        if path not in cache:
            cache[path] = pd.read_csv(path, header=header if header is None else 0, sep=sep)
        return cache[path]

    out = {}
    for name, spec in ref.items():
        if not isinstance(spec, list) or name in NOT_CHANNELS:
            continue
        file, tspec, col, scale, *offset = spec
        frame = read(folder / file)
        t, x = _times(folder, tspec, frame, read), _column(frame, col)
        n = min(len(t), len(x))                  # an input with one row per interval: one row shorter
        t, x = t[:n], (x[:n] + (offset[0] if offset else 0.0)) * scale
        keep = np.isfinite(t) & np.isfinite(x)
        if np.nanmedian(t) > 1e8:                # Unix times: a row of zeros is not a sample
            keep &= t > 1e8
        out[name] = (t[keep], x[keep])
    return out


def _nmea_time(hhmmss: str) -> float:
    return int(hhmmss[:2]) * 3600 + int(hhmmss[2:4]) * 60 + float(hhmmss[4:])


def _degrees(value: str, hemisphere: str) -> float:
    d = float(value[: value.index(".") - 2]) + float(value[value.index(".") - 2:]) / 60
    return -d if hemisphere in "SW" else d


def _from_east(compass_deg: str) -> float:
    """A compass angle [deg, clockwise from north] as an angle [rad] counter-clockwise from east."""
    return math.pi / 2 - math.radians(float(compass_deg))


def read_nmea(path: Path) -> dict:
    """GGA positions and fix quality, RMC/VTG speed and course, HDT/PASHR heading, each sentence
    found by its '$' (two glued on one line are two sentences)."""
    rows: dict[str, list] = {"lat": [], "lon": [], "quality": [], "speed": [], "course": [], "heading": []}
    last = math.nan
    text = path.read_text(errors="replace")
    for s in re.findall(r"\$[A-Z]{2}[A-Z]{3},[^$\r\n]*", text):
        f = s.split("*")[0].split(",")
        kind = f[0][3:]
        try:
            if kind in ("GGA", "RMC", "HDT") or f[0] == "$PASHR":
                last = _nmea_time(f[1]) if kind != "HDT" and f[1] else last
            if kind == "GGA" and f[2]:
                rows["lat"].append((last, _degrees(f[2], f[3])))
                rows["lon"].append((last, _degrees(f[4], f[5])))
                rows["quality"].append((last, float(f[6])))
            elif kind == "RMC" and f[7]:
                rows["speed"].append((last, float(f[7]) * 0.514444))
                if f[8]:
                    rows["course"].append((last, _from_east(f[8])))
            elif kind == "HDT" and f[1]:
                rows["heading"].append((last, _from_east(f[1])))
            elif f[0] == "$PASHR" and f[2]:
                rows["heading"].append((last, _from_east(f[2])))
        except (ValueError, IndexError):
            continue
    return {k: (np.array([a for a, _ in v]), np.array([b for _, b in v])) for k, v in rows.items() if v}


PTN_BYTES = {"A": ("<i4", 1e-7), "B": ("<i4", 1e-7), "C": ("<i4", 1e-3), "D": ("<u1", 1), "E": ("<u2", 0.1),
             "F": ("<u2", 0.1), "G": ("<u1", 1), "H": ("<u4", 1e-3), "I": ("<u2", 1)}


def read_tlg(folder: Path, stem: str) -> dict:
    """An ISO 11783-10 binary time log: per record the time of day [ms] and day, the position
    fields its PTN leaves empty, then N (DLV index, int32 value) pairs."""
    xml = next(p for p in folder.iterdir() if p.stem.upper() == stem.upper() and p.suffix.upper() == ".XML")
    binary = next(p for p in folder.iterdir() if p.stem.upper() == stem.upper() and p.suffix.upper() == ".BIN")
    tim = ET.parse(xml).getroot()
    ptn = [k for k, v in (tim.find("PTN").attrib.items() if tim.find("PTN") is not None else []) if v == ""]
    ddis = [d.get("A") for d in tim.findall("DLV")]
    data, i = binary.read_bytes(), 0
    out: dict[str, list] = {k: [] for k in ["t", *ptn, *(f"DDI {d}" for d in ddis)]}
    while i + 6 <= len(data):
        ms, day = np.frombuffer(data, "<u4", 1, i)[0], np.frombuffer(data, "<u2", 1, i + 4)[0]
        t, i = float(day) * 86400 + ms / 1000, i + 6
        for k in ptn:
            dtype, scale = PTN_BYTES[k]
            out[k].append((t, float(np.frombuffer(data, dtype, 1, i)[0]) * scale))
            i += np.dtype(dtype).itemsize
        n, i = data[i], i + 1
        for _ in range(n):
            out[f"DDI {ddis[data[i]]}"].append((t, float(np.frombuffer(data, "<i4", 1, i + 1)[0])))
            i += 5
    names = {"A": "lat", "B": "lon", "D": "quality", "H": "gnss_time"}
    return {names.get(k, k): (np.array([a for a, _ in v]), np.array([b for _, b in v]))
            for k, v in out.items() if k != "t" and v}


def read_optitrack(path: Path) -> dict:
    """A Motive export (7 lines above the data; Y up): x = X, y = -Z, heading = the rotation about
    Y from the quaternion (x, y, z, w) in columns 3-6."""
    frame = pd.read_csv(path, skiprows=7, header=None)
    t = frame[1].to_numpy(float)
    qx, qy, qz, qw = (frame[k].to_numpy(float) for k in (2, 3, 4, 5))
    yaw = np.arctan2(2 * (qw * qy + qx * qz), 1 - 2 * (qy**2 + qx**2))
    return {"x": (t, frame[6].to_numpy(float)), "y": (t, -frame[8].to_numpy(float)), "heading": (t, yaw)}


def read_rosbag(path: Path, ref: dict) -> dict:
    """channel -> (receive time, field) from [topic, field.path, scale(, offset)], read with the
    rosbags library; with clock = [topic, field, scale to s], each receive time is carried onto that
    topic's values (linear between its messages): the data's own clock in a replayed bag."""
    from rosbags.highlevel import AnyReader

    wanted = {name: spec for name, spec in ref.items() if isinstance(spec, list) and name not in NOT_CHANNELS}
    if "clock" in ref:
        wanted["clock"] = ref["clock"]
    rows: dict[str, list] = {name: [] for name in wanted}
    with AnyReader([path]) as reader:
        topics = {spec[0] for spec in wanted.values()}
        for conn, stamp, raw in reader.messages([c for c in reader.connections if c.topic in topics]):
            msg = reader.deserialize(raw, conn.msgtype)
            for name, (topic, field, scale, *offset) in wanted.items():
                if topic == conn.topic:
                    value = msg
                    for part in field.split("."):
                        value = getattr(value, part)
                    rows[name].append((stamp * 1e-9, (float(value) + (offset[0] if offset else 0.0)) * scale))
    out = {k: (np.array([a for a, _ in v]), np.array([b for _, b in v])) for k, v in rows.items() if v}
    if "clock" in out:
        tb, tv = out.pop("clock")
        out = {k: (np.interp(t, tb, tv), x) for k, (t, x) in out.items()}
    return out


def _group(frame_id: int, extended: bool):
    """A 29-bit identifier's J1939 parameter group (priority and sender free; PDU1's destination
    free), an 11-bit one as it is: a J1939 DBC's message matches any sender."""
    if not extended:
        return ("std", frame_id)
    pf = (frame_id >> 16) & 0xFF
    return ("pgn", (frame_id >> 8) & (0x3FFFF if pf >= 240 else 0x3FF00))


def read_mf4can(path: Path, ref: dict) -> dict:
    """channel -> (frame time, signal) from [message, signal, scale(, offset)]: the CAN frames of an
    MDF4 bus log (asammdf) on ref's bus, decoded with ref's DBC (cantools); a frame whose message
    says it is not valid (a one-bit signal named ...Valid at 0) is left out. Times are POSIX
    seconds on the logger's clock (the file's start time plus the frame's), the clock a converted
    log's stretch is stated on."""
    import cantools
    from asammdf import MDF

    db = cantools.database.load_file(str(path.parent / ref["dbc"]))
    mdf = MDF(str(path))
    ids = mdf.get("CAN_DataFrame.ID")
    data = mdf.get("CAN_DataFrame.DataBytes").samples
    bus = mdf.get("CAN_DataFrame.BusChannel").samples
    wanted = {name: spec for name, spec in ref.items() if isinstance(spec, list) and name not in NOT_CHANNELS}
    by_id = {_group(m.frame_id, m.is_extended_frame): m for m in db.messages
             if m.name in {spec[0] for spec in wanted.values()}}
    ide = mdf.get("CAN_DataFrame.IDE").samples
    rows: dict[str, list] = {name: [] for name in wanted}
    for t, frame_id, raw, b, ext in zip(ids.timestamps, ids.samples.astype(np.int64), data, bus, ide):
        msg = by_id.get(_group(int(frame_id), bool(ext)))
        if msg is None or int(b) != int(ref.get("bus", b)):
            continue
        values = msg.decode(bytes(raw)[:msg.length], decode_choices=False)
        if any(k.endswith("Valid") and v == 0 for k, v in values.items()):
            continue
        for name, (message, sig, scale, *offset) in wanted.items():
            if message == msg.name:
                rows[name].append((float(t), (float(values[sig]) + (offset[0] if offset else 0.0)) * scale))
    start = mdf.header.start_time.timestamp()
    mdf.close()
    return {k: (start + np.array([a for a, _ in v]), np.array([b for _, b in v])) for k, v in rows.items() if v}


def read_reference(rec: dict, roots: dict) -> dict:
    path = roots[rec["root"]] / rec["path"]
    ref = rec["reference"]
    kind = ref["kind"]
    if kind == "tables":
        folder = path.parent if path.is_file() else path
        return read_tables(folder, ref)
    if kind == "nmea":
        return read_nmea(path)
    if kind == "tlg":
        return read_tlg(path, ref["file"])
    if kind == "optitrack":
        return read_optitrack(path)
    if kind == "rosbag":
        return read_rosbag(path, ref)
    if kind == "mf4can":
        return read_mf4can(path, ref)
    if kind == "npchannels":
        return read_npchannels(path, ref)
    raise ValueError(f"reference kind {kind!r}")


# --- the reference numbers --------------------------------------------------------------------
def rates(t: np.ndarray, x: np.ndarray, counted: np.ndarray | None = None) -> tuple[float, float, float]:
    """(rows, fewest updates, most updates) per second over the time the channel covers: the span
    less its gaps (intervals over 3 x the median row interval), so that a gap is not read as a slow
    rate. What the values can show bounds the rate from both sides. Every change is an update: the
    fewest. A repeat is a missed update only where the data can show it: when the change that ends
    its run of repeats is more than one quantum (q, the smallest change of the channel; 1.5 q allows
    for rounding), the signal moved while the value stood; a signal on a coarse grid that moves less
    than a quantum per row repeats at every row sent, so a run ended by one quantum may be all
    updates: the most. ``counted``: the row intervals judged (e.g. the positions' while the machine
    moves)."""
    if len(t) < 3:
        return math.nan, math.nan, math.nan
    dt = np.diff(t)
    covered = dt <= 3 * np.median(dt)
    if counted is not None:
        covered &= counted
    seconds = float(dt[covered].sum())
    if seconds <= 0:
        return math.nan, math.nan, math.nan
    x = np.asarray(x, float).reshape(len(t), -1)
    change = np.any(np.diff(x, axis=0) != 0, axis=1)
    most = change | _quantised_hold(x, change)
    return (int(covered.sum()) / seconds, int(np.count_nonzero(change & covered)) / seconds,
            int(np.count_nonzero(most & covered)) / seconds)


def _quantised_hold(x: np.ndarray, change: np.ndarray) -> np.ndarray:
    """Per row interval: a repeat whose run ends with a change of at most one quantum (rates) on
    every column; False for a run the data never ends."""
    ends = np.flatnonzero(change)
    if not len(ends):
        return np.zeros(len(change), bool)
    steps = np.abs(np.diff(x, axis=0))
    single = np.ones(len(change), bool)
    for k in range(x.shape[1]):
        moved = steps[:, k][steps[:, k] > 0]
        q = float(moved.min()) if len(moved) else math.inf
        single &= steps[:, k] <= 1.5 * q
    end = ends[np.minimum(np.searchsorted(ends, np.arange(len(change))), len(ends) - 1)]
    return ~change & (end >= np.arange(len(change))) & single[end]


def fix_rates(ch: dict) -> dict:
    """The positions' rates, counted as the receiver sends them: one fix updates when any of its
    fields (latitude or longitude, x or y) changes, so a track along a meridian is not a missed
    longitude; and only while the machine moves, because a standing machine's fix may repeat
    (a receiver's static hold, a terminal that keeps the last fix) while a moving one must change.
    A row interval moves when the distance between the fixes before and after its run of repeats,
    over their time, exceeds MOVING (a fix that never changes again stands). Both fields get the
    fix's rates."""
    pair = ("x", "y") if "x" in ch and "y" in ch else ("lat", "lon") if "lat" in ch and "lon" in ch else None
    if pair is None or len(ch[pair[0]][0]) < 3 or not np.array_equal(ch[pair[0]][0], ch[pair[1]][0]):
        return {}
    t = ch[pair[0]][0]
    if pair == ("x", "y"):
        east, north = ch["x"][1], ch["y"][1]
    else:
        _, east, north = local_xy(ch["lat"], ch["lon"])
    change = (np.diff(east) != 0) | (np.diff(north) != 0)
    at = np.r_[0, np.flatnonzero(change) + 1]            # rows that start a new fix
    before = at[np.searchsorted(at, np.arange(len(t) - 1), side="right") - 1]   # the fix each row interval starts in
    nxt = np.searchsorted(at, np.arange(1, len(t)))      # the first new fix at or after each row's end
    after = at[np.minimum(nxt, len(at) - 1)]
    span = np.where(nxt < len(at), t[after] - t[before], np.inf)
    moving = np.hypot(east[after] - east[before], north[after] - north[before]) / span > MOVING
    both = np.column_stack([ch[pair[0]][1], ch[pair[1]][1]])
    r = rates(t, both, counted=moving)
    return {pair[0]: r, pair[1]: r}


def local_xy(lat: tuple, lon: tuple) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """East and north [m] of a position from its first (equirectangular: a field's extent)."""
    t, la = lat
    lo = np.interp(t, *lon)
    r = 6371000.0
    return t, np.radians(lo - lo[0]) * r * math.cos(math.radians(la[0])), np.radians(la - la[0]) * r


def positions(ch: dict):
    """(t, x, y) on the position's own updates (a held position is not a new one), or None."""
    if "x" in ch and "y" in ch:
        t, x = ch["x"]
        y = np.interp(t, *ch["y"])
    elif "lat" in ch and "lon" in ch:
        t, x, y = local_xy(ch["lat"], ch["lon"])
    else:
        return None
    new = np.r_[True, (np.diff(x) != 0) | (np.diff(y) != 0)]
    return t[new], x[new], y[new]


def course_and_speed(ch: dict):
    """The course and the unsigned speed of the positions' own updates, at their midpoints."""
    p = positions(ch)
    if p is None or len(p[0]) < 3:
        return None
    t, x, y = p
    dt = np.diff(t)
    ok = dt > 0
    tm = (t[1:] + t[:-1])[ok] / 2
    return tm, np.arctan2(np.diff(y)[ok], np.diff(x)[ok]), np.hypot(np.diff(x), np.diff(y))[ok] / dt[ok]


def reversing(ch: dict, within: tuple | None = None) -> tuple[float, str]:
    """The share of moving time driven backwards, and how it was found; ``within``: (start, end)
    on the channels' clock, the stretch judged."""
    if within is not None:
        ch = {k: (t[(t >= within[0]) & (t <= within[1])], x[(t >= within[0]) & (t <= within[1])])
              for k, (t, x) in ch.items()}
        ch = {k: v for k, v in ch.items() if len(v[0]) >= 3}
    if "v" in ch:
        t, v = ch["v"]
        moving = np.abs(v) > MOVING
        if moving.any() and (v < 0).any():
            return float(np.mean(v[moving] < 0)), "signed speed"
    cs = course_and_speed(ch)
    if cs is not None and "heading" in ch:
        tm, course, speed = cs
        heading = np.interp(tm, ch["heading"][0], np.unwrap(ch["heading"][1]))
        moving = speed > MOVING
        if "v" in ch:            # standing still, a fix's jitter makes a course: moving only where the speed says so too
            moving &= np.abs(np.interp(tm, ch["v"][0], ch["v"][1])) > MOVING
        if not moving.any():
            return math.nan, "never moving"
        turn = np.exp(1j * (course - heading))[moving]
        mount = np.angle(np.median(turn.real) + 1j * np.median(turn.imag))    # the body axis against the track
        share = float(np.mean(np.abs(np.angle(turn * np.exp(-1j * mount))) > math.pi / 2))
        return share, f"course against heading (mount {math.degrees(mount):.0f} deg taken as forward)"
    if "v" in ch:
        return 0.0, "speed never negative"
    return math.nan, "no speed, no heading"


def yaw_rate_of(ch: dict):
    """(t, r): the gyro, else the derivative of the unwrapped heading on its own updates."""
    if "yaw_rate" in ch:
        return ch["yaw_rate"]
    if "heading" in ch:
        t, h = ch["heading"]
        new = np.r_[True, np.diff(h) != 0]
        t, h = t[new], np.unwrap(h[new])
        return (t[1:] + t[:-1]) / 2, np.diff(h) / np.diff(t)
    return None


def speed_of(ch: dict):
    if "v" in ch:
        return ch["v"]
    cs = course_and_speed(ch)
    return None if cs is None else (cs[0], cs[2])


def kinematic(ch: dict, vehicle: dict) -> dict | None:
    """The yaw rate against v tan(delta/N)/L on a 50 Hz grid (|v| above KINEMATIC_MIN_SPEED):
    the lag of the best correlation in -1..1 s, the correlation there and at zero, and the slope
    there on the samples whose tyres are linear. r = v delta / (L + K v^2) is a linear-tyre law:
    past the tyres' peak the yaw rate is bounded by mu g / v whatever the steering asks, so a slope
    over saturated turns measures the friction, not the steering. A tyre's force (Magic Formula,
    shape 1.3) stays within 5 % of its initial slope up to a third of its peak, and the peak is at
    least the largest lateral acceleration the tyres delivered (99th percentile of |v r|) and at
    least 0.5 g (any ground driven on): the slope is taken where the lateral acceleration the
    steering asks for, v^2 tan(delta/N)/L (the regressor, so that the choice does not bias the
    slope), is at most a third of that; ``linear_v``/``linear_kin``: those samples."""
    delta = ch.get("delta")
    r, v = yaw_rate_of(ch), speed_of(ch)
    if delta is None or r is None or v is None or "wheelbase" not in vehicle:
        return None
    lo = max(delta[0][0], r[0][0], v[0][0])
    hi = min(delta[0][-1], r[0][-1], v[0][-1])
    if hi - lo < 2.0:
        return None
    t = np.arange(lo, hi, GRID)
    n = vehicle.get("steering_ratio", 1.0)
    kin = np.interp(t, *v) * np.tan(np.interp(t, *delta) / n) / vehicle["wheelbase"]
    yaw = np.interp(t, *r)
    ok = np.abs(np.interp(t, *v)) > KINEMATIC_MIN_SPEED
    best = (-2.0, 0)
    corr0 = math.nan
    if np.std(kin[ok]) < 0.02 * np.abs(kin[ok]).mean() + 1e-9:    # a constant input: the ratio of means
        m = ok
        return {"delay": math.nan, "corr": math.nan, "corr0": math.nan, "slope": math.nan,
                "ratio": float(np.mean(yaw[m]) / np.mean(kin[m])), "seconds": float(m.sum() * GRID)}
    for lag in range(-int(1.0 / GRID), int(1.0 / GRID) + 1):
        a, b, m = _shifted(kin, yaw, ok, lag)
        if m.sum() < 20 or np.std(a[m]) == 0 or np.std(b[m]) == 0:
            continue
        c = float(np.corrcoef(a[m], b[m])[0, 1])
        corr0 = c if lag == 0 else corr0
        best = max(best, (c, lag))
    if best[0] == -2.0:
        return None
    a, b, m = _shifted(kin, yaw, ok, best[1])
    speed = _shifted(np.interp(t, *v), yaw, ok, best[1])[0]
    limit = max(float(np.percentile(np.abs(speed * b)[m], 99)), 0.5 * G_ACC) / 3
    linear = m & (np.abs(speed * a) <= limit)
    linear = linear if linear.sum() >= 20 and np.std(a[linear]) > 0 else m
    slope = float(np.polyfit(a[linear], b[linear], 1)[0])
    ratio = float(np.mean(b[m]) / np.mean(a[m])) if abs(np.mean(a[m])) > 1e-3 else math.nan
    return {"delay": best[1] * GRID, "corr": best[0], "corr0": corr0, "slope": slope, "ratio": ratio,
            "seconds": float(m.sum() * GRID), "linear_s": float(linear.sum() * GRID), "linear_g": limit / G_ACC,
            "linear_v": speed[linear], "linear_kin": a[linear], "wheelbase": vehicle["wheelbase"]}


def _shifted(kin, yaw, ok, lag: int):
    """kin(t) against yaw(t + lag): the yaw rate answering lag samples after the input."""
    if lag >= 0:
        return kin[: len(kin) - lag], yaw[lag:], ok[: len(ok) - lag]
    return kin[-lag:], yaw[: len(yaw) + lag], ok[-lag:]


def vertical_axis(ch: dict):
    """(axis, mean reading [m/s2]) of the accelerometer axis (accel_x/_y/_z) whose mean is within
    25 % of g, the others below 0.35 g; None without such channels or evidence."""
    means = {a: float(np.mean(ch[f"accel_{a}"][1])) for a in "xyz" if f"accel_{a}" in ch}
    if len(means) < 3:
        return None
    axis = max(means, key=lambda a: abs(means[a]))
    level = all(abs(m) < 0.35 * 9.81 for a, m in means.items() if a != axis)
    return (axis, means[axis]) if 0.75 * 9.81 <= abs(means[axis]) <= 1.25 * 9.81 and level else None


def _best_lag(a: tuple, b: tuple, span: float = 1.0, step: float = GRID):
    """(lag [s] at which b(t + lag) best follows a(t), correlation there, the grid, a, b)."""
    lo, hi = max(a[0][0], b[0][0]), min(a[0][-1], b[0][-1])
    t = np.arange(lo, hi, step)
    x, y = np.interp(t, *a), np.interp(t, *b)
    n = int(span / step)
    best = (-2.0, 0)
    for lag in range(-n, n + 1):
        u, w = (x[: len(x) - lag], y[lag:]) if lag >= 0 else (x[-lag:], y[: len(y) + lag])
        if np.std(u) > 0 and np.std(w) > 0:
            best = max(best, (float(np.corrcoef(u, w)[0, 1]), lag))
    return best[1] * step, best[0], t, x, y


def second_yaw_source(ch: dict):
    """yaw_rate_2 against yaw_rate: the lag of best correlation (-1..1 s), the correlation, and the
    scale at that lag: the ratio of their standard deviations (reduced major axis: both are noisy),
    beside least squares through the origin (biased low by the first's noise) and the median ratio
    while turning (|yaw_rate| > 0.1 rad/s)."""
    if "yaw_rate" not in ch or "yaw_rate_2" not in ch:
        return None
    lag, corr, t, x, y = _best_lag(ch["yaw_rate"], ch["yaw_rate_2"])
    k = int(round(lag / GRID))
    u, w = (x[: len(x) - k], y[k:]) if k >= 0 else (x[-k:], y[: len(y) + k])
    turning = np.abs(u) > 0.1
    return {"lag": lag, "corr": corr, "scale": float(np.sign(corr) * np.std(w) / np.std(u)),
            "ls": float(np.dot(u, w) / np.dot(u, u)),
            "turning": float(np.median(w[turning] / u[turning])) if turning.sum() > 20 else math.nan}


def speed_against_positions(ch: dict):
    """v against the speed of the positions' own updates: (lag of best correlation within +-5 s
    (positive: the positions' speed later), correlation)."""
    cs = course_and_speed(ch)
    if cs is None or "v" not in ch or len(cs[0]) < 20 or cs[0][-1] - cs[0][0] < 20.0:
        return None                      # under 20 s, a 5 s lag search has no footing
    lag, corr, *_ = _best_lag(ch["v"], (cs[0], cs[2]), span=5.0, step=0.1)
    return lag, corr


def reference_numbers(rec: dict, roots: dict) -> dict:
    """The second method's numbers; [recording.reference] shift moves a channel earlier by a
    latency its publisher measured."""
    ch = read_reference(rec, roots)
    for name, seconds in rec["reference"].get("shift", {}).items():
        ch[name] = (ch[name][0] - seconds, ch[name][1])
    cs = course_and_speed(ch)
    out = {"rates": {k: rates(*v) for k, v in ch.items()} | fix_rates(ch), "reversing": reversing(ch),
           "top_speed": float(np.percentile(cs[2], 99)) if cs is not None and len(cs[2]) else math.nan,
           "kinematic": kinematic(ch, rec.get("vehicle", {})), "channels": ch, "vertical": vertical_axis(ch),
           "second_yaw": second_yaw_source(ch), "speed_lag": speed_against_positions(ch)}
    if "quality" in ch:
        out["quality"] = sorted({int(q) for q in ch["quality"][1]})
    if rec["reference"].get("understeer"):
        lag = (out["kinematic"] or {}).get("delay", 0.0)
        out["understeer"] = understeer_reference(ch, rec.get("vehicle", {}),
                                                 0.0 if lag is None or math.isnan(lag) else lag)
    return out


# --- the project's numbers --------------------------------------------------------------------
def import_options(rec: dict, roots: dict):
    from agrobot.measurements.options import ImportOptions
    from agrobot.measurements.signal_expressions import parse_signal

    c = rec.get("convert", {})
    dbc = c.get("dbc")
    return ImportOptions(signals=[parse_signal(s) for s in c.get("signals", [])], time=c.get("time"),
                         wheelbase=c.get("wheelbase"), steering_ratio=c.get("steering_ratio"),
                         align=c.get("align", "auto"), bus=c.get("bus"), rate=c.get("rate"),
                         sign_speed=bool(c.get("sign_speed", False)),
                         dbc=None if dbc is None else roots[rec["root"]] / Path(rec["path"]).parent / dbc)


def study_path(rec: dict, roots: dict) -> str | None:
    s = rec.get("convert", {}).get("study")
    if s is None:
        return None
    return str(ROOT / s) if (ROOT / s).exists() else str(roots[rec["root"]] / s)


def project_import(rec: dict, roots: dict) -> dict:
    """convert: the audit's rate per log column, its findings, the log's reversing share."""
    from agrobot import api

    done = api.convert(roots[rec["root"]] / rec["path"], options=import_options(rec, roots))
    audit = done.report.get("audit", {})
    channel_rates = {}
    for r in audit.get("channels", []):
        for name in r["channel"].split(", "):
            channel_rates[name] = r["rate_hz"]
    log = done.log
    out = {"rates": channel_rates, "rows_hz": done.report.get("rate_hz"),
           "findings": [f"{f['kind']}{'' if f['resolved'] else '!'} {f['value']:.3g} {f['unit']}".strip()
                        for f in audit.get("findings", [])],
           "found": [(f["kind"], tuple(f.get("channels", [])), f["value"]) for f in audit.get("findings", [])],
           "yaw_source": done.report.get("columns", {}).get("yaw_rate", ""),
           "quirks": list(done.report.get("quirks", [])), "columns": [c for c in log.columns if c != "t"],
           "seconds": float(log["t"].iloc[-1] - log["t"].iloc[0]) if len(log) else 0.0}
    if "v" in log:
        v = log["v"].to_numpy(float)
        moving = np.abs(v) > MOVING
        out["reversing"] = float(np.mean(v[moving] < 0)) if moving.any() else math.nan
    if "fix_quality" in log:
        out["quality"] = sorted({int(q) for q in log["fix_quality"].dropna()})
    used = done.report.get("used") or {}
    if "utc_start_s" in used and out["seconds"] > 0:
        out["stretch"] = (float(used["utc_start_s"]), float(used["utc_start_s"]) + out["seconds"])
    return out


def _value(report: dict, *keys):
    q = report
    for k in keys:
        if not isinstance(q, dict) or k not in q:
            return None
        q = q[k]
    return q.get("value") if isinstance(q, dict) else q


def project_identify(rec: dict, roots: dict) -> dict:
    """identify: delay (+ lag), steering gain and offset, understeer gradient, held-out fit, wheelbase."""
    from agrobot import api

    done = api.identify(str(roots[rec["root"]] / rec["path"]), recording=import_options(rec, roots),
                        study=study_path(rec, roots), plots=False)
    rep = done.report
    return {"method": done.method, "delay": _value(rep, "delay"), "delay_verdict": (rep.get("delay") or {}).get("verdict"), "lag": _value(rep, "parameters", "lag"),
            "steer_gain": _value(rep, "parameters", "steer_gain"),
            "steer_offset": _value(rep, "parameters", "steer_offset"),
            "K": _value(rep, "understeer_gradient"), "fit": _value(rep, "held_out_fit"),
            "K_concluded": (rep.get("understeer_gradient") or {}).get("identifiable", True),
            "wheelbase": _value(rep, "vehicle", "wheelbase"), "input": rep.get("input")}


# --- the table --------------------------------------------------------------------------------
class TimedOut(Exception):
    pass


def _alarm(signum, frame):
    raise TimedOut()


def guarded(what: str, timeout: float, compute, *args):
    """compute(*args), or the text of what it raised (a timeout included)."""
    signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    try:
        return compute(*args)
    except TimedOut:
        return f"{what}: no result within --timeout {timeout:g} s"
    except BaseException as exc:          # noqa: BLE001 - every failure is a row of the table
        if isinstance(exc, KeyboardInterrupt):
            raise
        return f"{what} failed: {type(exc).__name__}: {' '.join(str(exc).split())}"
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)


def _f(x, fmt: str = "{:.3g}") -> str:
    return "-" if x is None or (isinstance(x, float) and math.isnan(x)) else fmt.format(x)


def _agree(ok) -> str:
    return "-" if ok is None else "yes" if ok else "NO"


CANONICAL = {"delta": ("delta", "delta_cmd"), "yaw_rate": ("yaw_rate",), "yaw_rate_2": ("yaw_rate_2", "odom_yaw_rate"), "v": ("v",), "x": ("gnss", "x"),
             "y": ("gnss", "y"), "lat": ("gnss", "lat"), "lon": ("gnss", "lon"), "heading": ("heading",)}


def rate_rows(ref: dict, imp, commands: list, samples: list = ()) -> list[tuple]:
    """A measured channel's rate is its updates', which the values bound from both sides (rates:
    the changes, and the changes plus the repeats a coarse grid explains); a command's, its
    messages' (a repeated command is sent again), and so is a channel declared a sample per
    message (a quantised gyro repeats). They agree when the audit's rate lies in that range, 25 %
    allowed beyond either end (the stamps' jitter)."""
    rows = []
    for name, (rows_hz, fewest, most) in ref["rates"].items():
        names = CANONICAL.get(name)
        if names is None:
            continue
        project = None if isinstance(imp, str) else next((imp["rates"][n] for n in names if n in imp["rates"]), None)
        lo, hi = (rows_hz, rows_hz) if name in commands or name in samples else (fewest, most)
        ok = None if project is None or not hi else 0.75 * lo <= project <= 1.25 * hi
        said = " (a command)" if name in commands else " (a sample per message)" if name in samples else ""
        span = _f(fewest) if _f(fewest) == _f(most) else f"{_f(fewest)}-{_f(most)}"
        rows.append((f"rate {name} [Hz]" + said, f"{span} updates in {_f(rows_hz)} rows", _f(project), _agree(ok)))
    return rows


def steady_slope(k: dict, gain, K) -> float | None:
    """The slope of r on v tan(delta/N)/L that identify's steering gain g and understeer gradient
    K predict on the reference's linear-tyre samples: r = g v delta / (L + K v^2) in steady state,
    so each sample's slope is g L / (L + K v^2), averaged with the weights a least-squares slope
    gives them (the regressor squared); g alone without K."""
    if gain is None:
        return None
    if K is None or not math.isfinite(K) or "linear_v" not in k or not len(k["linear_v"]):
        return float(gain)
    w, L = k["linear_kin"] ** 2, k["wheelbase"]
    return float(gain * np.sum(w * L / (L + K * k["linear_v"] ** 2)) / np.sum(w))


def kinematic_rows(ref: dict, ident, imp=None) -> list[tuple]:
    k = ref["kinematic"]
    if k is None:
        return []
    got = ident if isinstance(ident, dict) else {}
    gain = got.get("steer_gain")
    slope = k["slope"] if not math.isnan(k["slope"]) else k["ratio"]
    predicted = steady_slope(k, gain, got.get("K"))
    linear = f", tyres linear: {k['linear_s']:.0f} s under {k['linear_g']:.2f} g" if "linear_s" in k else ""
    rows = [("yaw / kinematic slope", f"{_f(k['slope'])} (ratio of means {_f(k['ratio'])}, r {_f(k['corr'], '{:.2f}')}, "
             f"{k['seconds']:.0f} s{linear})", f"{_f(predicted)} (steer_gain {_f(gain)}, K {_f(got.get('K'))})",
             _agree(None if predicted is None or math.isnan(slope) else abs(predicted - slope) <= 0.3 * abs(slope)))]
    return rows + delay_rows(k, got, imp)


def delay_rows(k: dict, got: dict, imp) -> list[tuple]:
    """The reference's lag of best correlation is the yaw rate's whole lag behind the kinematic
    demand: any dead time and steering lag plus the vehicle's own yaw response (its tyres and
    inertia: a car's single-track model lags 0.04-0.07 s at 20 km/h), or a clock offset where it is
    negative. identify's delay + lag is the part in front of its model, so it lies between
    min(0, that lag) and that lag (0.08 s allowed either side); a value on its zero bound does not
    agree unless identify states it as an upper limit only ("at most"), and identify's "cannot
    decide" gives no number to compare. The audit's response lag (the same cross-correlation as
    the reference's) is printed beside."""
    found = [_found(imp, ("response_lag",), {"yaw_rate", "v", u}) for u in ("delta", "delta_cmd")]
    lag = next((x for x in found if x is not None), None)
    delay = got.get("delay")
    total = None if delay is None or not math.isfinite(delay) else delay + (got.get("lag") or 0.0)
    verdict = _agree(None if total is None or math.isnan(k["delay"]) else
                     min(0.0, k["delay"]) - 0.08 <= total <= k["delay"] + 0.08)
    bounded = any(w in (got.get("delay_verdict") or "") for w in ("below its upper limit", "at most"))
    if delay is not None and 0 <= delay < 1e-6 and not bounded:
        verdict = "NO (on its zero bound)"        # a verdict never sits on a bound; "at most" is not a value
    said = f" ({got['delay_verdict']})" if got.get("delay_verdict") else ""
    return [("command-to-yaw lag [s]; identify's delay + lag within it",
             f"{_f(k['delay'])} (r at 0 s {_f(k['corr0'], '{:.2f}')})",
             f"delay {_f(delay)} + lag {_f(got.get('lag'))}{said}; audit's response lag {_f(lag)}", verdict)]


def _found(imp, kinds: tuple, channels: set):
    """The value of the audit's first finding of ``kinds`` on exactly ``channels``, or None."""
    if not isinstance(imp, dict):
        return None
    return next((v for k, c, v in imp["found"] if k in kinds and {SECOND.get(x, x) for x in c} == channels), None)


SECOND = {"odom_yaw_rate": "yaw_rate_2"}      # a wheel odometry's turn rate is the second yaw-rate source compared


LAG_KINDS = ("clock_offset", "sensor_latency")


def sensor_rows(ref: dict, imp, shift: dict | None = None) -> list[tuple]:
    """The IMU's vertical axis, a second yaw-rate source's lag and scale, the speed's lag against
    the positions: the reference beside the audit's finding on the same channels. The audit
    measures a lag on the recording as read, before --align moves a channel (its finding names the
    move), while the reference reads the channels after their ``shift`` (the same latency moved
    earlier); so the positions' speed after v is compared after the move on both sides: the
    audit's lag plus the seconds v was moved earlier."""
    rows = []
    if ref["vertical"] is not None:
        axis, mean = ref["vertical"]
        src = imp.get("yaw_source", "") if isinstance(imp, dict) else ""
        got = re.search(r"(angular_velocity\.|AngularRate)([xyzXYZ])", src)
        rows.append(("IMU vertical axis (gravity)", f"{axis} ({mean:+.2f} m/s2)", src or "-",
                     _agree(None if got is None else got.group(2).lower() == axis)))
    if ref["second_yaw"] is not None:
        y = ref["second_yaw"]
        lag = _found(imp, LAG_KINDS, {"yaw_rate", "yaw_rate_2"})
        rows.append(("yaw_rate_2 after yaw_rate [s]", f"{y['lag']:.2f} (r {y['corr']:.2f})", _f(lag),
                     _agree(None if lag is None else abs(lag - y["lag"]) <= 0.08)))
        scale = _found(imp, ("scale_disagreement", "ambiguous_channel"), {"yaw_rate", "yaw_rate_2"})
        rows.append(("yaw_rate_2 / yaw_rate", f"{y['scale']:.3g} (least squares {y['ls']:.3g}, turning {_f(y['turning'])})",
                     _f(scale), _agree(None if scale is None else abs(scale - y["scale"]) <= 0.1 * abs(y["scale"]))))
    if ref["speed_lag"] is not None:
        lag, corr = ref["speed_lag"]
        got = _found(imp, LAG_KINDS, {"v", "gnss_speed"})          # the audit's: v after gnss_speed
        moved = (shift or {}).get("v", 0.0)
        got = None if got is None else -got + moved
        said = f" (found {_f(got - moved)}, v moved {moved:g} s earlier)" if got is not None and moved else ""
        rows.append(("positions' speed after v [s]", f"{lag:.1f} (r {corr:.2f})", _f(got) + said,
                     _agree(None if got is None else abs(got - lag) <= 0.5)))
    return rows


POSIX_KINDS = ("tables", "rosbag", "mf4can")    # readers whose times can be POSIX (NMEA: time of day; TLG: 1980 days)


def reversing_like_log(ref: dict, imp, kind: str) -> tuple[float, str]:
    """The reference's reversing share on the stretch the converted log keeps (the project's share
    is the log's, and convert keeps one run: a reversal outside it is not in the log), where both
    clocks are POSIX (the log's stretch is stated in UTC; the reference's reader one of POSIX_KINDS
    with times above 1e8 s); else over the whole recording."""
    stretch = imp.get("stretch") if isinstance(imp, dict) else None
    times = [t for t, _ in ref["channels"].values() if len(t)]
    if stretch is None or kind not in POSIX_KINDS or not times or np.median(np.concatenate(times)) < 1e8:
        return ref["reversing"]
    share, how = reversing(ref["channels"], within=stretch)
    start = min(float(t[0]) for t in times)
    return share, f"{how}; on the stretch convert keeps, {stretch[0] - start:.0f}-{stretch[1] - start:.0f} s after the first sample"


def recording_rows(rec: dict, roots: dict, timeout: float, identify: bool) -> list[tuple]:
    ref = guarded("reference", timeout, reference_numbers, rec, roots)
    if isinstance(ref, str):
        return [("reference", ref, "-", "-")]
    imp = guarded("convert", timeout, project_import, rec, roots)
    rows = rate_rows(ref, imp, rec["reference"].get("commands", []), rec["reference"].get("samples", []))
    share, how = reversing_like_log(ref, imp, rec["reference"]["kind"])
    project = None if isinstance(imp, str) else imp.get("reversing")
    rows.append(("reversing [% of moving]", f"{_f(100 * share, '{:.1f}')} ({how})", _f(None if project is None else 100 * project, "{:.1f}"),
                 _agree(None if project is None or math.isnan(share) else abs(project - share) <= 0.02)))
    if "quality" in ref:
        rows.append(("fix quality values", str(ref["quality"]), str(imp.get("quality", "-")) if isinstance(imp, dict) else "-",
                     _agree(None if not isinstance(imp, dict) or "quality" not in imp else imp["quality"] == ref["quality"])))
    rows.append(("top speed [m/s] (99 %, positions)", _f(ref["top_speed"]), "-", "-"))
    rows += sensor_rows(ref, imp, rec["reference"].get("shift"))
    ident = guarded("identify", timeout, project_identify, rec, roots) if identify else "not run (--no-identify)"
    rows += kinematic_rows(ref, ident, imp) + understeer_rows(ref, ident)
    if isinstance(ident, dict):
        rows.append(("identify: K [rad/(m/s2)]; fit [%]; L [m]", "-",
                     f"{_f(ident['K'])}; {_f(ident['fit'], '{:.0f}')}; {_f(ident['wheelbase'])} ({ident['method']}, "
                     f"input {ident['input']}, offset {_f(ident['steer_offset'])} rad)", "-"))
    else:
        rows.append(("identify", "-", ident, "-"))
    rows.append(("audit findings (! unresolved)", "-", imp if isinstance(imp, str) else
                 "; ".join(imp["findings"]) or "none", "-"))
    if isinstance(imp, dict) and imp["quirks"]:
        rows.append(("import quirks", "-", "; ".join(imp["quirks"]), "-"))
    rows.append(("published", rec["reference"].get("published", "-"), "-", "-"))
    return rows


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--manifest", type=Path, default=ROOT / "benchmarks" / "real_corpus.toml")
    p.add_argument("--only", help="the recording of this name (or names containing it)")
    p.add_argument("--timeout", type=float, default=300.0, help="seconds per step of a recording")
    p.add_argument("--realdata", type=Path, default=ROOTS["realdata"])
    p.add_argument("--corpus", type=Path, default=ROOTS["corpus"])
    p.add_argument("--no-identify", action="store_true", help="the audit and the references only")
    args = p.parse_args(argv)
    roots = {"realdata": args.realdata, "corpus": args.corpus}
    recs = tomllib.loads(args.manifest.read_text())["recording"]
    recs = [r for r in recs if not args.only or args.only in r["name"]]
    if not recs:
        print(f"error: --only {args.only}: no recording of that name in {args.manifest}", file=sys.stderr)
        return 2
    print("| recording | class | quantity | reference (numpy, raw files) | project | agrees |\n|---|---|---|---|---|---|")
    for rec in recs:
        start = time.perf_counter()
        if not (roots[rec["root"]] / rec["path"]).exists():
            rows = [("files", f"missing: {roots[rec['root']] / rec['path']}", "-", "-")]
        else:
            rows = recording_rows(rec, roots, args.timeout, not args.no_identify)
        for q, r, pj, a in rows:
            cells = (rec["name"], rec["class"], q, r, pj, a)
            print("| " + " | ".join(str(c).replace("|", "/").replace("\n", " ") for c in cells) + " |", flush=True)
        print(f"{rec['name']}: {time.perf_counter() - start:.0f} s", file=sys.stderr, flush=True)
    return 0


# --- numpy channel folders, the understeer gradient and the lateral acceleration -----------------
UNDERSTEER_MIN_SPEED = 5.0      # m/s: the steady-state regression's speeds (delta - L r / v is noise below)
UNDERSTEER_LATERAL = 4.0        # m/s2: the regression's |a_y| (the linear range of a road tyre)


def read_npchannels(folder: Path, ref: dict) -> dict:
    """channel -> (t, x) in SI from [channel folder, column, scale(, offset)]: the ``t`` and
    ``value`` arrays numpy.save wrote in that folder (np.load; a value of one column or several)."""
    out = {}
    for name, spec in ref.items():
        if not isinstance(spec, list) or name in NOT_CHANNELS:
            continue
        sub, column, scale, *offset = spec
        t, v = np.load(folder / sub / "t"), np.load(folder / sub / "value")
        x = v.reshape(len(v), -1)[:, column].astype(float)
        out[name] = (t.astype(float), (x + (offset[0] if offset else 0.0)) * scale)
    return out


def understeer_reference(ch: dict, vehicle: dict, lag: float) -> dict | None:
    """The steady-state regression delta/N - L r / v = K a_y + c (a_y = v r) by least squares on a
    50 Hz grid, the yaw rate taken ``lag`` s after the steering (the kinematic lag of best
    correlation), |v| above UNDERSTEER_MIN_SPEED and |a_y| below UNDERSTEER_LATERAL: K, its 95 %
    interval, c; and the 99.9th percentile of |a_y| over the moving samples."""
    if not all(k in ch for k in ("delta", "yaw_rate", "v")) or "wheelbase" not in vehicle:
        return None
    lo = max(ch[k][0][0] for k in ("delta", "yaw_rate", "v"))
    hi = min(ch[k][0][-1] for k in ("delta", "yaw_rate", "v")) - max(lag, 0.0)
    t = np.arange(lo, hi, GRID)
    v, r = np.interp(t, *ch["v"]), np.interp(t + lag, *ch["yaw_rate"])
    delta = np.interp(t, *ch["delta"]) / vehicle.get("steering_ratio", 1.0)
    moving = np.abs(v) > UNDERSTEER_MIN_SPEED
    if moving.sum() < 100:
        return None
    ay = v * r
    m = moving & (np.abs(ay) < UNDERSTEER_LATERAL)
    y = delta[m] - vehicle["wheelbase"] * r[m] / v[m]
    a = np.column_stack([ay[m], np.ones(m.sum())])
    coef, *_ = np.linalg.lstsq(a, y, rcond=None)
    resid = y - a @ coef
    cov = np.linalg.inv(a.T @ a) * float(resid @ resid) / max(len(y) - 2, 1)
    # samples 0.02 s apart are not independent: the interval is widened by sqrt(samples per second)
    k_sd = math.sqrt(cov[0, 0]) * math.sqrt(1.0 / GRID)
    return {"K": float(coef[0]), "K_sd": k_sd, "offset": float(coef[1]), "seconds": float(m.sum() * GRID),
            "ay_peak": float(np.percentile(np.abs(ay[moving]), 99.9))}


def understeer_rows(ref: dict, ident) -> list[tuple]:
    """The reference's K and peak lateral acceleration beside identify's K (agree within 30 % or
    within the reference's 95 % interval; a K identify does not conclude is not compared)."""
    if "understeer" not in ref:
        return []
    u = ref["understeer"]
    if u is None:
        return [("understeer gradient K [rad/(m/s2)]", "-", "-", "-")]
    got = ident.get("K") if isinstance(ident, dict) else None
    concluded = got is None or ident.get("K_concluded", True)
    ok = None if got is None or not concluded else (abs(got - u["K"]) <= max(0.3 * abs(u["K"]), 1.96 * u["K_sd"]))
    return [("lateral acceleration [m/s2] (99.9 %, |v| > 5 m/s)", _f(u["ay_peak"]), "-", "-"),
            ("understeer gradient K [rad/(m/s2)] (steady-state regression)",
             f"{u['K']:.3g} +- {1.96 * u['K_sd']:.2g} (offset {u['offset']:.2g} rad, |a_y| < {UNDERSTEER_LATERAL:g}, "
             f"{u['seconds']:.0f} s)", _f(got) if concluded else f"not concluded (fitted {_f(got)})", _agree(ok))]


if __name__ == "__main__":
    sys.exit(main())
