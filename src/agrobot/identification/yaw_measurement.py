"""What measures the yaw: a gyro's ``yaw_rate``, else a heading differenced on its own updates.

Without a gyro the yaw rate is derived, in this order of preference, from

- ``heading``: a dual-antenna heading, the yaw angle psi [rad], counter-clockwise positive (the
  yaw rate's sign);
- the GNSS course atan2(dy, dx) of the positions ``x``, ``y`` [m] on chords of 0.5 m at
  ``course_speed`` (m position updates), where the vehicle moves forward above ``course_speed``
  (``v`` must be positive there: a reversing vehicle's course is its heading + 180 deg),
  differenced over m updates. Unless told, ``course_speed`` is the log's own (course_floor): a
  course over a chord of length D from positions of white noise sigma across the track has the
  noise sqrt(2) sigma / D [rad], so chords of COURSE_TIME s keep it within COURSE_NOISE above

      v_min = sqrt(2) sigma / (COURSE_NOISE COURSE_TIME),   course_speed = min(COURSE_SPEED, v_min)

  (sigma: measurements.position_source.track_noise, at least the positions' rounding, their smallest step / sqrt 12);
  a tractor-class receiver (sigma of 2 cm) keeps the 1 m/s of before, a motion-capture track
  (millimetres) reads its course at a few cm/s.

Each is read on its own updates (the rows where its value changes; a 5 Hz heading held in 20 Hz
rows has a quarter of the rows' information), never on the rows::

    r_k = (psi_k+1 - psi_k) / (t_k+1 - t_k)   at (t_k + t_k+1) / 2     (psi unwrapped)

and interpolated linearly onto the rows: a yaw rate averaged over about two update intervals,
without delay. Noise model: the heading's white noise sigma_psi from its third differences on its
updates (var(d3) = 20 sigma_psi^2; the motion's jerk is far smaller), so the derived yaw rate on
the rows has variance sigma_psi^2 / dt_u^2 on average over the interpolation (dt_u its update
interval). The model's yaw rate is averaged alike before it is compared (``kernel``: what the
derivation does to the true yaw rate). Latency: an update is stamped on the first row that carries it, up to one row late; a
receiver's own latency adds to the fitted delay (the two are not told apart).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from agrobot.measurements import LogError
from agrobot.measurements.position_source import track_noise

COURSE_SPEED = 1.0          # m/s: the GNSS course is read above this speed at most (course_speed changes it)
COURSE_CHORD = 0.5          # m: the course is read on chords at least this long at course_speed
COURSE_TIME = COURSE_CHORD / COURSE_SPEED      # s: a chord's duration at course_speed
COURSE_NOISE = 0.05         # rad: the course noise sqrt(2) sigma / chord the default course_speed keeps within


@dataclass(frozen=True)
class YawMeasurement:
    """Which measurement measures the yaw, its own update rate and its noise on the rows."""

    kind: str                     # "gyro", "dual-antenna heading", "GNSS course"
    update_hz: float
    noise: float                  # rad/s: the yaw rate's white noise on the rows (nan: not known)
    latency: float                # s: the stamping latency of its updates (up to one row)
    update_times: np.ndarray | None = None    # its yaw-rate samples' times (None: every row)
    course_speed: float | None = None
    chord_updates: int = 1                    # a course: the updates a chord spans
    course_choice: str = ""                   # a course: how course_speed was chosen (course_floor)

    @property
    def text(self) -> str:
        if self.kind == "gyro":
            return "yaw measured by: gyro yaw_rate"
        speed = f" above {self.course_speed:.3g} m/s moving forward (course_speed changes it)" if self.course_speed else ""
        return (f"yaw measured by: {self.kind}{speed}, {self.update_hz:.3g} Hz updates, differenced on its own updates "
                f"(yaw-rate noise {self.noise:.2g} rad/s on the rows; stamped up to {1e3 * self.latency:.0f} ms late, "
                f"a receiver latency is in the fitted delay); no gyro yaw_rate in the log"
                + (f"; {self.course_choice}" if self.course_choice else ""))

    def kernel(self, h: float) -> np.ndarray | None:
        """The weights (odd length, sum 1) on a grid of step ``h`` with which the derived yaw rate
        averages the true one: a gyro none; a heading differenced over its update interval dt_u and
        interpolated between its midpoints, a box of dt_u convolved with a triangle of half-width dt_u;
        a course of chords T = m dt_u long differenced over T, a triangle of half-width T."""
        if self.kind == "gyro" or not math.isfinite(self.update_hz):
            return None
        dt = 1.0 / self.update_hz
        fine = dt / 50.0
        if self.kind == "GNSS course":
            span = self.chord_updates * dt
            s = np.arange(-span, span + fine / 2, fine)
            w = np.maximum(0.0, 1.0 - np.abs(s) / span)
        else:
            s = np.arange(-dt, dt + fine / 2, fine)
            w = np.convolve(np.maximum(0.0, 1.0 - np.abs(s) / dt), np.ones(int(round(dt / fine))), mode="same")
        half = int(s[-1] // h)
        if half < 1:
            return None
        k = np.interp(np.arange(-half, half + 1) * h, s, w)
        return k / k.sum()

    def as_dict(self) -> dict:
        return {"kind": self.kind, "update_hz": self.update_hz, "noise": self.noise, "latency": self.latency,
                "course_speed": self.course_speed, "course_choice": self.course_choice, "text": self.text}


def own_updates(x: np.ndarray) -> np.ndarray:
    """Indices of the rows where a held channel takes a new value (the first row included)."""
    x = np.asarray(x, float)
    return np.flatnonzero(np.r_[True, x[1:] != x[:-1]] & np.isfinite(x))


def _noise(psi: np.ndarray) -> float:
    """sigma_psi from the third differences of the updates (robust: the median absolute value)."""
    d3 = np.diff(psi, 3)
    return float(np.median(np.abs(d3)) / 0.6745 / math.sqrt(20.0)) if len(d3) > 10 else float("nan")


def _rates(t: np.ndarray, psi: np.ndarray, max_step: float):
    """(times, yaw rates) of successive samples of an angle, at their midpoints; pairs further apart
    than ``max_step`` are left out."""
    psi = np.unwrap(psi)
    dt = np.diff(t)
    ok = (dt > 0) & (dt <= max_step)
    return (0.5 * (t[1:] + t[:-1]))[ok], (np.diff(psi) / np.where(dt > 0, dt, 1.0))[ok]


def _on_rows(t_rows: np.ndarray, tr: np.ndarray, r: np.ndarray, max_step: float) -> np.ndarray:
    """The yaw rate on the rows, linear between its samples; nan further than ``max_step`` from one."""
    out = np.interp(t_rows, tr, r)
    k = np.clip(np.searchsorted(tr, t_rows), 1, len(tr) - 1)
    near = np.minimum(np.abs(t_rows - tr[k - 1]), np.abs(tr[k] - t_rows)) <= max_step
    return np.where(near & (t_rows >= tr[0] - max_step) & (t_rows <= tr[-1] + max_step), out, np.nan)


def from_heading(frame: pd.DataFrame, where: str) -> tuple[np.ndarray, YawMeasurement]:
    t = frame["t"].to_numpy(float)
    psi = frame["heading"].to_numpy(float)
    finite = psi[np.isfinite(psi)]
    if len(finite) and np.max(np.abs(finite)) > 2 * math.pi + 0.1:
        raise LogError(f"{where}: column 'heading' reaches {np.max(np.abs(finite)):.4g}: expected radians "
                       f"(the yaw angle; declare its unit deg to convert a heading in degrees)")
    k = own_updates(psi)
    if len(k) < 10:
        raise LogError(f"{where}: column 'heading' takes {len(k)} distinct value(s) in {len(psi)} rows: it never "
                       f"updates; expected a heading that changes as the vehicle turns (or a gyro yaw_rate)")
    dt_u = float(np.median(np.diff(t[k])))
    h = float(np.median(np.diff(t)))
    tr, r = _rates(t[k], psi[k], 3.0 * dt_u)
    rows = _on_rows(t, tr, r, 1.5 * dt_u)
    sigma = _noise(np.unwrap(psi[k]))
    return rows, YawMeasurement("dual-antenna heading", 1.0 / dt_u, sigma / dt_u, h if dt_u > 1.5 * h else 0.0, tr)


def course_floor(t: np.ndarray, x: np.ndarray, y: np.ndarray) -> tuple[float, str]:
    """(course_speed [m/s], how it was chosen): min(COURSE_SPEED, sqrt(2) sigma / (COURSE_NOISE
    COURSE_TIME)), sigma the positions' white noise across the track (module docstring); COURSE_SPEED
    when too few moving fixes tell their noise."""
    noise = track_noise(t, x, y)
    if noise is None:
        return COURSE_SPEED, (f"course_speed {COURSE_SPEED:g} m/s: too few moving fixes to read the positions' "
                              f"own noise (--course-speed changes it)")
    sigma = max(float(noise["across"]), noise["rounding"])
    need = math.sqrt(2.0) * sigma / (COURSE_NOISE * COURSE_TIME)
    speed = min(COURSE_SPEED, need)
    said = (f"course_speed {speed:.3g} m/s from the positions' own noise ({1e3 * sigma:.3g} mm across the track "
            f"at {noise['hz']:.3g} Hz): chords of {COURSE_TIME:g} s at {need:.3g} m/s keep the course noise "
            f"sqrt(2) sigma / chord within {COURSE_NOISE:g} rad")
    if need > COURSE_SPEED:
        said += (f", held at the {COURSE_SPEED:g} m/s default (its course noise "
                 f"{math.sqrt(2.0) * sigma / (COURSE_SPEED * COURSE_TIME):.2g} rad)")
    else:
        said += f"; passed over the {COURSE_SPEED:g} m/s default"
    return speed, said + " (--course-speed changes it)"


def from_course(frame: pd.DataFrame, where: str, course_speed: float | None = None
                ) -> tuple[np.ndarray, YawMeasurement]:
    """The course of chords of at least course_speed COURSE_TIME at ``course_speed`` (m updates
    apart; None: course_floor), its rate over m updates: a yaw rate averaged over 2 m updates
    (positions' noise sigma_p gives a course noise sqrt(2) sigma_p / chord)."""
    t = frame["t"].to_numpy(float)
    x, y = frame["x"].to_numpy(float), frame["y"].to_numpy(float)
    k = np.union1d(own_updates(x), own_updates(y))
    if len(k) < 10:
        raise LogError(f"{where}: columns 'x', 'y' take {len(k)} distinct positions: they never update; expected "
                       f"positions that follow the drive (or a gyro yaw_rate, or a heading)")
    choice = ""
    if course_speed is None:
        course_speed, choice = course_floor(t[k], x[k], y[k])
    dt_u = float(np.median(np.diff(t[k])))
    m = max(1, int(math.ceil(COURSE_TIME / dt_u - 1e-9))) if choice else \
        max(1, int(math.ceil(COURSE_CHORD / (course_speed * dt_u))))
    tk, dx, dy = 0.5 * (t[k][m:] + t[k][:-m]), x[k][m:] - x[k][:-m], y[k][m:] - y[k][:-m]
    speed = np.hypot(dx, dy) / (t[k][m:] - t[k][:-m])
    if "v" in frame:             # a signed speed says forward; an unsigned one is taken as forward (said)
        speed = np.minimum(speed, np.interp(tk, t, frame["v"].to_numpy(float)))
    fwd = speed >= course_speed
    if fwd.sum() < 10 + m:
        own = float(np.median(speed)) if len(speed) else 0.0
        longer = (f"--course-speed {own:.2g}, its median speed, reads it on chords of {COURSE_CHORD:g} m, "
                  f"{COURSE_CHORD / own:.2g} s; " if choice and 0 < own < course_speed else "lower course_speed, ")
        raise LogError(f"{where}: the positions x, y move forward at {course_speed:.3g} m/s or more on {int(fwd.sum())} "
                       f"updates: too few to read the GNSS course (" + (f"{choice}; " if choice else "")
                       + f"{longer}or log a gyro or a heading)")
    course = np.unwrap(np.arctan2(dy, dx))
    ok = fwd[m:] & fwd[:-m]
    tr, r = (0.5 * (tk[m:] + tk[:-m]))[ok], ((course[m:] - course[:-m]) / (tk[m:] - tk[:-m]))[ok]
    rows = _on_rows(t, tr, r, 1.5 * m * dt_u)
    sigma = _noise(course[fwd][::m])
    h = float(np.median(np.diff(t)))
    return rows, YawMeasurement("GNSS course", 1.0 / dt_u, sigma / (m * dt_u), h if dt_u > 1.5 * h else 0.0, tr,
                                course_speed, m, choice)


def with_yaw_rate(frame: pd.DataFrame, where: str, course_speed: float | None = None
                  ) -> tuple[pd.DataFrame, YawMeasurement | None]:
    """(the log with a ``yaw_rate``, what measured it): the gyro's when the log has one (or a yaw
    rate derived before, frame.attrs["yaw_measurement"]), else derived from ``heading``, else from
    the course of ``x``, ``y`` above ``course_speed`` (None: the log's own, course_floor); (the log,
    None) when it has none of them or a gyro under another name. A derived yaw rate is nan
    where its measurement says nothing (a slow stretch for the course)."""
    known = frame.attrs.get("yaw_measurement")
    if "yaw_rate" in frame:
        return frame, known or YawMeasurement("gyro", float("nan"), float("nan"), 0.0)
    if any(str(c).replace("_", "").replace("-", "").replace(" ", "").lower() == "yawrate" for c in frame.columns):
        return frame, None           # a gyro under another name (YawRate): the caller says to rename it
    if "heading" in frame:
        rows, m = from_heading(frame, where)
    elif {"x", "y"} <= set(frame.columns):
        rows, m = from_course(frame, where, course_speed)
    else:
        return frame, None
    out = frame.assign(yaw_rate=rows)
    out.attrs = {**frame.attrs, "yaw_measurement": m}
    return out, m


def check_sign(r: np.ndarray, asked: np.ndarray, where: str, measured: YawMeasurement) -> None:
    """A derived yaw rate turning against the steering (correlation with v u below -0.3 where both
    move) is a heading counted clockwise (a compass heading): refused, said how to give it."""
    if measured.kind == "gyro":
        return
    ok = np.isfinite(r) & np.isfinite(asked) & (np.abs(asked) > 0)
    if ok.sum() < 50 or np.std(r[ok]) == 0 or np.std(asked[ok]) == 0:
        return
    rho = float(np.corrcoef(r[ok], asked[ok])[0, 1])
    if rho < -0.3:
        column = "'heading'" if measured.kind == "dual-antenna heading" else "'x', 'y'"
        raise LogError(f"{where}: column {column}: the yaw rate from the {measured.kind} turns against the steering "
                       f"(correlation {rho:.2f} with v x steering): expected the yaw angle counter-clockwise "
                       f"(from east toward north); a compass heading (clockwise from north) is pi/2 - heading")
