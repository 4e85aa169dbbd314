"""The measured log: one column table, one reader (DESIGN.md, 'Measured data').

A log is a table (CSV or Parquet) with a time column ``t`` [s] and named signals in SI units
(``COLUMNS``); more columns are allowed. Every refusal names the file, the column and what was
expected. Identification, diagnosis and the tests read logs through ``read_log`` only. A log that
``convert`` wrote carries its import's audit (``frame.attrs["audit"]``, measurements.audit),
restored from the Parquet metadata or the ``<name>.import.json`` beside it (measurements.load_log
audits any other table on its own columns).

Imported where used: scipy.ndimage (start-up: 0.035 s CPU on every command, which loads this
module), scipy.integrate (start-up: 0.025 s CPU on every command).
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd

from agrobot.orchestrator.errors import InputError
from agrobot.orchestrator.atomic_files import read_units
from agrobot.orchestrator.source_files import checked_path, regular_file
from agrobot.orchestrator.units import base_unit

# the canonical columns: name -> (SI unit, meaning)
COLUMNS: dict[str, tuple[str, str]] = {
    "t": ("s", "time"),
    "delta_cmd": ("rad", "front wheel angle commanded to the steering"),
    "delta": ("rad", "front wheel angle measured (potentiometer)"),
    "v": ("m/s", "longitudinal speed"),
    "yaw_rate": ("rad/s", "yaw rate (gyro)"),
    "x": ("m", "GPS antenna east of the datum"),
    "y": ("m", "GPS antenna north of the datum"),
}
CANONICAL = tuple(COLUMNS)

# A column whose largest magnitude passes this bound is almost surely in degrees: no Ackermann
# vehicle steers beyond 70 deg (1.22 rad; a car's inner wheel 35-45 deg, a tractor's 50-60 deg;
# only a pivot-steer tricycle's or forklift's wheel goes further, to 80-90 deg: wheel_angle_in_radians)
# or yaws faster than 3 rad/s (172 deg/s).
DEGREE_SUSPECT = {"delta_cmd": (1.22, "rad"), "delta": (1.22, "rad"), "yaw_rate": (3.0, "rad/s"),
                  "odom_yaw_rate": (3.0, "rad/s"), "turn_rate_cmd": (3.0, "rad/s")}


class LogError(InputError, ValueError):
    """A log that cannot be used as it is."""


def read_log(path: str | Path, required: tuple[str, ...] = CANONICAL, resample_jitter: bool = False) -> pd.DataFrame:
    # ``required``: the columns the caller cannot do without (("t",) for a partial log)
    """Load and check a log: columns present and numeric, no NaN or infinity, time in seconds,
    increasing and evenly sampled (a gap is named; clock jitter is refused, or put on an even grid
    with ``resample_jitter``, the ``--resample`` option of the commands), angles in radians
    (degrees are detected and named), speed against the GPS track (check_units)."""
    path = regular_file(checked_path(path, LogError, "log not found"), LogError)
    kind = "Parquet" if path.suffix == ".parquet" else "CSV"
    try:
        frame = pd.read_parquet(path) if kind == "Parquet" else pd.read_csv(path)
        stored = read_units(path)
    except Exception as exc:
        raise LogError(f"{path}: cannot read as {kind}: {exc}") from None
    report = persisted_report(path)          # the import's report, when convert wrote the log
    if isinstance(report.get("declared"), dict):
        frame.attrs["declared"] = dict(report["declared"])      # the units the user declared to convert
    if isinstance(report.get("resolution"), dict):
        frame.attrs["resolution"] = dict(report["resolution"])  # the recording's own quantisation steps
    frame = check_log(frame, str(path), required, resample_jitter)
    audit = report.get("audit", {}).get("findings")
    if isinstance(audit, list):
        frame.attrs["audit"] = list(audit)
    frame.attrs["units"] = log_units(frame, stored)
    return frame


def log_units(frame: pd.DataFrame, stored: dict[str, str] | None = None) -> dict[str, str]:
    """Column -> unit of a log: the canonical columns' SI units (COLUMNS), then what the file
    stores (orchestrator.atomic_files: a Parquet file's metadata, a CSV file's NAME.units.json)."""
    units = {c: COLUMNS[c][0] for c in frame.columns if c in COLUMNS}
    units.update({c: u for c, u in (stored or frame.attrs.get("units", {})).items() if c in frame.columns})
    return units


def persisted_report(path) -> dict:
    """The import report written beside a log (its ``<name>.import.json``, as ``convert`` writes
    it), or {}: reading a log back restores its audit, the units the user declared and the
    signals' resolution (a written log holds no attrs: orchestrator.atomic_files.write_frame)."""
    side = Path(path).with_name(Path(path).stem + ".import.json")
    if not side.is_file():
        return {}
    try:
        report = json.loads(side.read_text())
    except (OSError, ValueError):
        return {}
    return report if isinstance(report, dict) else {}


def persisted_audit(path) -> list | None:
    """The findings written beside a log (persisted_report), or None."""
    found = persisted_report(path).get("audit", {}).get("findings")
    return list(found) if isinstance(found, list) else None


SECONDS_STEP_MAX = 9.5  # slow receivers log every 1-5 s; a millisecond clock steps by 10 and more
MS_STEP_MAX = 2000.0    # a millisecond clock at 0.5-100 Hz steps by 10-2000 (a 1 Hz receiver's, 1000 and a jitter);
                        # a microsecond one at up to 500 Hz by more


def check_log(frame: pd.DataFrame, path: str, required: tuple[str, ...] = CANONICAL,
              resample_jitter: bool = False) -> pd.DataFrame:
    """The checks of read_log on a table already in memory (an imported recording); ``path``
    names it in the messages. ``required`` columns must be there; every canonical column that is
    there is checked the same way (a partial log: the tools say what they cannot judge)."""
    missing = [c for c in required if c not in frame.columns]
    if missing:
        raise LogError(f"{path}: missing columns {missing}; a log needs "
                       + ", ".join(f"{c} [{COLUMNS[c][0]}]" if c in COLUMNS else c for c in required))
    if not any(c in frame.columns for c in CANONICAL[1:]):
        raise LogError(f"{path}: none of the log's columns ({', '.join(CANONICAL[1:])}) is in it; found "
                       f"{', '.join(map(str, frame.columns[:12]))}")
    if len(frame) < 3:
        raise LogError(f"{path}: {len(frame)} rows; a log needs many samples")
    checked = tuple(dict.fromkeys(tuple(required) + tuple(c for c in CANONICAL if c in frame.columns)))
    for c in checked:
        if not pd.api.types.is_numeric_dtype(frame[c]):
            raise LogError(f"{path}: column {c!r} is not numeric (first value {frame[c].iloc[0]!r})")
        for what, bad in (("NaN", frame[c].isna().to_numpy()), ("infinite", np.isinf(frame[c].to_numpy(float)))):
            if bad.any():
                raise LogError(f"{path}: column {c!r} has {int(bad.sum())} {what} values (first at row "
                               f"{int(np.argmax(bad))}, t = {frame['t'].iloc[int(np.argmax(bad))]})")
    if len(frame) < 3:
        raise LogError(f"{path}: {len(frame)} rows; a log needs many samples")
    t = frame["t"].to_numpy(dtype=float)
    dt = np.diff(t)
    if np.any(dt <= 0):
        i = int(np.argmax(dt <= 0))
        raise LogError(f"{path}: column 't' is not increasing at row {i + 1} (t = {t[i]} then {t[i + 1]})")
    step = float(np.median(dt))
    if step >= SECONDS_STEP_MAX:
        unit, factor = ("microseconds", 1e6) if step > MS_STEP_MAX else ("milliseconds", 1e3)
        raise LogError(f"{path}: column 't' steps by {step:.4g} between samples; a vehicle log samples at 0.1-100 Hz, "
                       f"so it looks like {unit} ({factor / step:.3g} Hz): the log must hold seconds (divide t by "
                       f"{factor:g})")
    if dt.max() > 1.5 * step:
        i = int(np.argmax(dt))
        raise LogError(f"{path}: column 't' has a gap of {dt[i]:.4g} s at t = {t[i]:.4g} s (row {i + 1}); "
                       f"expected an even step of {step:.4g} s: cut the log at the gap or fill it")
    grid = {c: resolution(frame[c].to_numpy(float)) for c in ("x", "y") if c in frame}
    if np.max(np.abs(dt - step)) > 0.01 * step:
        if resample_jitter:
            attrs = dict(frame.attrs)
            frame = resample(frame, step)
            frame.attrs.update(attrs)
        else:
            i = int(np.argmax(np.abs(dt - step)))
            raise LogError(f"{path}: column 't' is unevenly sampled: step {dt[i]:.4g} s at row {i + 1}, typical "
                           f"{step:.4g} s; pass --resample to interpolate the log onto an even {step:.4g} s grid")
    for c, (bound, unit) in DEGREE_SUSPECT.items():
        if c in checked:
            peak = robust_peak(frame[c].to_numpy(float))
            if peak > bound and c == "yaw_rate" and (why := yaw_rate_in_radians(frame)):
                frame.attrs.setdefault("notes", []).append(
                    f"column 'yaw_rate' reaches {peak:.3g} rad/s, more than {bound} rad/s, and is read as rad/s: {why}")
            elif peak > bound and c in ("delta", "delta_cmd") and (why := wheel_angle_in_radians(frame, c)):
                frame.attrs.setdefault("notes", []).append(
                    f"column {c!r} reaches {peak:.4g} rad ({math.degrees(peak):.0f} deg), more than {bound} rad, "
                    f"and is read as rad: {why}")
            elif peak > bound and c in frame.attrs.get("declared", {}):
                frame.attrs.setdefault("notes", []).append(declared_warning(
                    c, f"reaches {peak:.4g} (99.5 % of its values within), more than {bound} {unit}{past_widest_lock(c, peak)}",
                    frame.attrs["declared"][c], unit))
            elif peak > bound:
                raise LogError(f"{path}: column {c!r} reaches {peak:.4g} (99.5 % of its values within), more than "
                               f"{bound} {unit}{past_widest_lock(c, peak)}: it looks like degrees{'/s' if unit == 'rad/s' else ''}; the log must "
                               f"hold {unit} (multiply by pi/180 = {math.pi / 180:.6f}: degrees are {180 / math.pi:.1f} times radians; a raw recording: declare the "
                               f"unit, --signal '{c}=...[deg{'/s' if unit == 'rad/s' else ''}]')")
    check_units(frame, path)
    quantised = {c: q for c, q in grid.items() if q > 0}
    if quantised:        # read on the samples as written, before any resampling
        frame.attrs["resolution"] = {**frame.attrs.get("resolution", {}), **quantised}
    return frame


def robust_peak(x: np.ndarray) -> float:
    """The 99.5th percentile of |x| (the largest value for fewer than 200 samples, after the
    median of 3 has removed single glitches)."""
    x = np.abs(np.asarray(x, float))
    x = x[np.isfinite(x)]
    if len(x) == 0:
        return 0.0
    if len(x) >= 200:
        return float(np.percentile(x, 99.5))
    if len(x) >= 3:
        from scipy.ndimage import median_filter

        return float(median_filter(x, size=3, mode="nearest").max())
    return float(x.max())


def chords(gps: np.ndarray, h: float, span: float = 1.0) -> tuple[int, np.ndarray]:
    """(k, d): the GPS displacement over ``span`` seconds centred on sample i + k, d[i] =
    gps[i + 2k] - gps[i]. Chords average the 2 cm noise that point-to-point differences amplify."""
    k = max(1, int(round(0.5 * span / h)))
    return k, gps[2 * k:] - gps[:-2 * k]


def track_span(t: np.ndarray, gps: np.ndarray) -> float:
    """Seconds a chord of the track must span to hold position updates: 1 s, or twice the median
    interval between the positions' changes where they change less often (a receiver at 0.2-1 Hz
    held on a faster grid, a clock that runs slower than the data's). A shorter chord between two
    updates measures a track that stands still. An update is a run of changing rows (a resampled
    track ramps from one fix to the next over the rows between their samples)."""
    moved = np.any(np.diff(gps, axis=0) != 0, axis=1)
    starts = moved & ~np.concatenate(([False], moved[:-1]))
    changes = np.asarray(t, float)[1:][starts]
    if len(changes) < 3:
        return 1.0
    return max(1.0, 2.0 * float(np.median(np.diff(changes))))


def track_chords(frame: pd.DataFrame) -> tuple[float, int, np.ndarray]:
    """(h, k, d): the median row interval and the chords of the track (x, y) that span its
    positions' updates (chords(..., track_span)), the one reading of the track's speed and course."""
    t = frame["t"].to_numpy(float)
    gps = frame[["x", "y"]].to_numpy(float)
    h = float(np.median(np.diff(t)))
    return (h, *chords(gps, h, track_span(t, gps)))


def speed_estimate(frame: pd.DataFrame) -> tuple[np.ndarray | None, str]:
    """(speed [m/s], where from): the wheel speed v, else the receiver's speed over ground
    (gnss_speed), else the speed of the GPS track over its chords (track_chords: "track"); (None, "none")."""
    if "v" in frame:
        return frame["v"].to_numpy(float), "v"
    if "gnss_speed" in frame:
        return frame["gnss_speed"].to_numpy(float), "gnss_speed"
    if {"x", "y"} <= set(frame.columns):
        t = frame["t"].to_numpy(float)
        h, k, d = track_chords(frame)
        speed = np.full(len(t), np.nan)
        speed[k:-k] = np.hypot(d[:, 0], d[:, 1]) / (2 * k * h)
        ok = np.isfinite(speed)
        if ok.sum() >= 2:
            return np.interp(np.arange(len(t)), np.flatnonzero(ok), speed[ok]), "track"
    return None, "none"


def check_units(frame: pd.DataFrame, where: str) -> None:
    """Speed against the speed of the GPS track over its chords (track_chords; when v, x, y are
    logged): 3.6 means km/h; a track that hardly moves while v says it does means x, y are not metres."""
    if not {"t", "v", "x", "y"} <= set(frame.columns) or len(frame) < 10:
        return
    h, k, d = track_chords(frame)
    track = np.hypot(d[:, 0], d[:, 1]) / (2 * k * h)
    v = frame["v"].to_numpy(float)[k:-k]
    fast = v > 0.5
    if fast.sum() < 100:
        return
    ratio = float(np.median(v[fast]) / max(np.median(track[fast]), 1e-9))
    if "v" in frame.attrs.get("declared", {}) and not 0.67 < ratio < 1.5:
        frame.attrs.setdefault("notes", []).append(
            f"warning: column 'v' is {ratio:.2f} times the speed of the GPS track; kept as declared "
            f"[{frame.attrs['declared']['v']}] (the user's word stands): a unit of v, or a time base that runs "
            f"{ratio:.2f} times {'slower' if ratio > 1 else 'faster'} than the data's own clock (a bag recorded while a "
            f"log was replayed: every rate, the yaw rate's included, is then off by that factor)")
        return
    if abs(ratio - 3.6) < 0.4:
        raise LogError(f"{where}: column 'v' is 3.6 times the speed of the GPS track: it looks like km/h; "
                       f"the log must hold m/s (divide v by 3.6)")
    if ratio > 50:
        raise LogError(f"{where}: columns 'x', 'y' move {ratio:.0f} times slower than 'v' says: they look like "
                       f"degrees of latitude/longitude, or they do not follow the tractor at all (noise, a "
                       f"fixed point); the log must hold the GPS position in metres east/north of a datum")
    if not 0.67 < ratio < 1.5:
        raise LogError(f"{where}: column 'v' is {ratio:.2f} times the speed of the GPS track (x, y): "
                       f"check the units of v, x and y (m/s and m), and the time base (a clock that runs at another rate "
                       f"than the data's scales every rate alike)")
    if "yaw_rate" in frame.columns:
        _check_yaw_rate_unit(frame, where, h, k, d)


def _track_turn_ratio(frame: pd.DataFrame, h: float, k: int, d: np.ndarray) -> float | None:
    """Heading change over 2 s, integrated yaw rate against the GPS course (track_chords) while
    moving: the regression slope, 1 in rad/s and 57 in deg/s (None: too little moving)."""
    from scipy.integrate import cumulative_trapezoid

    L = max(1, int(round(2.0 / h)))
    if len(d) <= L + 100:
        return None
    course = np.arctan2(d[:, 1], d[:, 0])
    psi = cumulative_trapezoid(frame["yaw_rate"].to_numpy(float), dx=h, initial=0.0)[k:-k]
    fast = (frame["v"].to_numpy(float) > 0.3)[k:-k]
    dc = np.angle(np.exp(1j * (course[L:] - course[:-L])))
    dp = psi[L:] - psi[:-L]
    ok = fast[L:] & fast[:-L]
    if ok.sum() > 100 and dc[ok] @ dc[ok] > 0:
        return float(dc[ok] @ dp[ok] / (dc[ok] @ dc[ok]))
    return None


# A yaw rate above DEGREE_SUSPECT's bound is still rad/s when the vehicle's motion says so: at
# |v| > MOVING m/s a ground vehicle turns no tighter than MAX_CURVATURE (a 0.4 m radius) and
# no harder than MAX_LATERAL (2 g, beyond any tyre); deg/s would be 57 times either.
MOVING, MAX_CURVATURE, MAX_LATERAL = 0.5, 2.5, 19.6


def yaw_rate_in_radians(frame: pd.DataFrame) -> str | None:
    """The evidence that a fast yaw_rate column is in rad/s, or None: integrated, it turns as the
    track (x, y) turns; else, with the speed v, its curvature |r|/|v| and lateral acceleration
    |v r| stay physical while moving."""
    if not {"t", "v", "yaw_rate"} <= set(frame.columns) or len(frame) < 10:
        return None
    t = frame["t"].to_numpy(float)
    h = float(np.median(np.diff(t)))
    if {"x", "y"} <= set(frame.columns):
        _, k, d = track_chords(frame)
        slope = _track_turn_ratio(frame, h, k, d) if len(d) else None
        if slope is not None and 0.5 < slope < 2.0:
            return f"integrated, it turns {slope:.2f} times as fast as the track (x, y)"
        if slope is not None and slope > 20:
            return None
    v, r = frame["v"].to_numpy(float), frame["yaw_rate"].to_numpy(float)
    moving = np.abs(v) > MOVING
    if moving.sum() < 100:
        return None
    curvature, lateral = robust_peak(r[moving] / v[moving]), robust_peak(r[moving] * v[moving])
    if curvature <= MAX_CURVATURE and lateral <= MAX_LATERAL:
        return (f"while moving (|v| > {MOVING} m/s) it turns no tighter than {1 / curvature:.2g} m radius and "
                f"|v yaw_rate| reaches {lateral:.3g} m/s2 (in deg/s it would be 57 times that)")
    return None


def slope_through_origin(x: np.ndarray, y: np.ndarray) -> float:
    """The least-squares slope of y = s x (x.y / x.x); NaN where x is all zero."""
    return float(x @ y / (x @ x)) if x @ x > 0 else math.nan


# The evidence for a wheel angle past DEGREE_SUSPECT's 70 deg in rad (wheel_angle_in_radians), each bound from the
# physics of a steered wheel and of its sensors:
WIDEST_LOCK = math.pi / 2       # rad: a wheel at 90 deg points across the vehicle, a pivot-steer tricycle's full lock;
                                # past it, it points backwards (delta - pi driven the other way, v < 0): no wheel
                                # angle in rad passes it, and a column that does is in degrees
READING_ERROR = math.radians(0.5)   # rad: a steering angle sensor's zero and linearity error (a potentiometer's)
TAN_ERROR = 0.1                 # the error of tan(delta) a sample used may carry from READING_ERROR
# d tan / tan = d delta / (sin delta cos delta): READING_ERROR makes at most TAN_ERROR of tan below this (85 deg)
TAN_WIDEST = (math.pi - math.asin(2 * READING_ERROR / TAN_ERROR)) / 2
TURNING_ANGLE = 3 * READING_ERROR   # rad: a turn, not the sensor's zero error (1.5 deg)
TURNING_RATE = 0.02             # rad/s: a turn, not a MEMS gyro's uncorrected bias (about 1 deg/s)
MOVING_SPEED = 0.1              # m/s: driving, not standing (measurements.channel_updates.STANDING)
# the widest turn driven must reach where tan delta exceeds delta by about 3 TAN_ERROR (29 % at 0.8 rad = 46 deg):
# there the two readings of the column differ by three times what a reading error makes of tan
EVIDENT_ANGLE = 0.8
WHEELBASES = (0.1, 10.0)        # m: a 1:10 model car's to a long truck's (the --wheelbase range)
MIN_R2 = 0.8                    # the no-slip turn explains a steered vehicle's yaw but for understeer (K v^2 / L of
                                # 10-20 % at the speeds of wide turns), slip and gyro noise: 80 % of its variance


def wheel_angle_in_radians(frame: pd.DataFrame, column: str) -> str | None:
    """The evidence that a wide wheel-angle column (past DEGREE_SUSPECT's 70 deg: a pivot-steer
    tricycle's or forklift's steered wheel turns to 80-90 deg) is in rad, or None: the turns follow
    the no-slip r = v tan(delta) / L of a wheelbase L better than the r = v delta / L that a column in
    degrees (its true angles 57 times smaller) would follow. Each bound from the physics:

    - never past WIDEST_LOCK = pi/2 (robust_peak): at 90 deg a wheel points across the vehicle;
      past it, it points backwards (delta - pi driven with v < 0), so no wheel angle in rad does;
    - samples below TAN_WIDEST (85 deg): d tan / tan = d delta / (sin delta cos delta), so a
      READING_ERROR of 0.5 deg moves tan by TAN_ERROR (10 %) there, and more beyond;
    - above TURNING_ANGLE (1.5 deg, 3 reading errors), |r| above TURNING_RATE (a MEMS gyro's
      uncorrected 1 deg/s), |v| above MOVING_SPEED (standing: channel_updates.STANDING), 100 at least;
    - the widest turn reaches EVIDENT_ANGLE (46 deg), where tan exceeds the angle by 29 %, three
      times what a reading error makes of it: below, the two readings are not told apart;
    - L within WHEELBASES (a 1:10 model car's 0.1 m to a truck's 10 m: --wheelbase's range), and
      R2 >= MIN_R2 (0.8: the no-slip turn less understeer, K v^2 / L of 10-20 %, slip and noise)."""
    if not {"t", "v", "yaw_rate", column} <= set(frame.columns):
        return None
    v, r, w = (frame[c].to_numpy(float) for c in ("v", "yaw_rate", column))
    if robust_peak(w) > WIDEST_LOCK:
        return None
    turning = ((np.abs(v) > MOVING_SPEED) & (np.abs(w) > TURNING_ANGLE) & (np.abs(w) < TAN_WIDEST)
               & (np.abs(r) > TURNING_RATE))
    if turning.sum() < 100 or np.abs(w[turning]).max() < EVIDENT_ANGLE:
        return None
    fits = {}
    for name, x in (("tan", v * np.tan(w)), ("linear", v * w)):
        x, y = x[turning], r[turning]
        slope = slope_through_origin(x, y)
        fits[name] = (slope, 1 - float(np.sum((y - slope * x) ** 2) / np.sum(y ** 2)))
    (slope, r2), (_, r2_linear) = fits["tan"], fits["linear"]
    if slope <= 0 or not WHEELBASES[0] <= 1 / slope <= WHEELBASES[1] or r2 < MIN_R2 or r2 <= r2_linear:
        return None
    return (f"its turns follow yaw_rate = v tan({column}) / L with L = {1 / slope:.3g} m (R2 {r2:.3f}, "
            f"against {r2_linear:.3f} for an angle in degrees)")


OTHER_CAUSES = {"yaw_rate": "a gyro shaken by its mount, or another axis",
                "delta": "a handwheel angle (--steering-ratio divides it)", "delta_cmd": "a handwheel angle (--steering-ratio divides it)"}


def declared_warning(column: str, evidence: str, declared: str, si: str) -> str:
    """The warning for a column the user declared in ``declared`` that ``evidence`` finds too large
    for ``si``: the look of degrees where it was declared in another unit; where it was declared in
    degrees (already converted: a factor pi/180), not a slip of degrees but a value beyond a ground
    vehicle's (OTHER_CAUSES). Kept either way: the user's word stands."""
    b = base_unit(declared)
    if b is not None and math.isclose(b.factor, math.pi / 180, rel_tol=1e-9):
        return (f"warning: column {column!r} {evidence}, although declared in degrees [{declared}] and converted: not "
                f"a slip of degrees; {OTHER_CAUSES.get(column, 'another quantity')}, or another unit? kept as declared "
                f"(the user's word stands)")
    return (f"warning: column {column!r} {evidence}, which looks like degrees{'/s' if si == 'rad/s' else ''}; kept as "
            f"declared [{declared}] (the user's word stands)")


def past_widest_lock(column: str, peak: float) -> str:
    """Why a wheel-angle column reaching ``peak`` cannot be in rad ('' when it may be): past pi/2."""
    if column not in ("delta", "delta_cmd") or peak <= WIDEST_LOCK:
        return ""
    return (f", and past pi/2 = {WIDEST_LOCK:.4g} rad (90 deg), where a steered wheel points across the vehicle: "
            f"no wheel angle in rad passes it (a pivot-steer tricycle's lock is 80-90 deg)")


def _check_yaw_rate_unit(frame: pd.DataFrame, where: str, h: float, k: int, d: np.ndarray) -> None:
    """The track's evidence (_track_turn_ratio): a slope above 20 is deg/s."""
    slope = _track_turn_ratio(frame, h, k, d)
    if slope is not None and slope > 20:
        if "yaw_rate" in frame.attrs.get("declared", {}):
            frame.attrs.setdefault("notes", []).append(declared_warning(
                "yaw_rate", f"turns {slope:.0f} times as fast as the GPS track", frame.attrs["declared"]["yaw_rate"], "rad/s"))
            return
        raise LogError(f"{where}: column 'yaw_rate' turns {slope:.0f} times as fast as the GPS track: "
                       f"it looks like deg/s; the log must hold rad/s (multiply by pi/180)")


def resolution(x: np.ndarray, min_repeat: float = 2.0) -> float:
    """The step q of a quantised signal (its values lie on a grid x0 + k q: a potentiometer's
    counts, a float32 position far from its origin), or 0 when the values are not on a grid.

    q is the smallest gap between distinct values; the signal is quantised when every gap is a
    whole multiple of q (within 2 %) and values repeat (fewer distinct values than samples /
    ``min_repeat``, so that a smooth signal sampled once per level is not taken for a grid)."""
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    levels = np.unique(x)
    if len(levels) < 3 or len(levels) > len(x) / min_repeat:
        return 0.0
    gaps = np.diff(levels)
    q = float(gaps.min())
    if q <= 0 or q < 1e-12 * max(float(np.abs(levels).max()), 1.0):
        return 0.0
    ratio = gaps / q
    return q if float(np.max(np.abs(ratio - np.round(ratio)))) < 0.02 else 0.0


def split(frame: pd.DataFrame, fraction: float) -> tuple[pd.DataFrame, pd.DataFrame]:
    """(first ``fraction`` of the duration, the rest): a fit part and a held-out part."""
    t = frame["t"].to_numpy(dtype=float)
    cut = t[0] + fraction * (t[-1] - t[0])
    return frame[t < cut].reset_index(drop=True), frame[t >= cut].reset_index(drop=True)


def resample(frame: pd.DataFrame, step: float | None = None) -> pd.DataFrame:
    """The log on an even time grid t0, t0 + step, ... (default step: the median interval), every
    numeric column linearly interpolated: for logs whose clock jitters by a fraction of a step."""
    t = frame["t"].to_numpy(dtype=float)
    if len(t) < 2 or np.any(np.diff(t) <= 0):
        raise LogError("resampling needs a time column 't' that increases")
    step = float(np.median(np.diff(t))) if step is None else float(step)
    if step <= 0:
        raise LogError(f"resampling step {step} s must be > 0")
    grid = t[0] + step * np.arange(int(np.floor((t[-1] - t[0]) / step + 1e-9)) + 1)
    columns = {"t": grid}
    for c in frame.columns:
        if c != "t" and pd.api.types.is_numeric_dtype(frame[c]):
            columns[c] = np.interp(grid, t, frame[c].to_numpy(dtype=float))
    return pd.DataFrame(columns)
