"""Yaw-dynamics identification from ordinary driving: an output-error fit in the time domain.

Model (the study's single-track model, LPV in the measured speed v)::

    w(t)      = g u(t - tau) + delta_0            wheel angle asked: steering input u (the measured
                                                  wheel angle delta, else the command delta_cmd),
                                                  delay tau, gain g (1 for a measured angle), offset
    T dd/dt   = w - d                             steering lag T: the wheel angle d the tyres see
    single-track yaw dynamics driven by d at v    (components.models.tyre: linear tyres, or the
                                                  simplified Magic Formula with friction mu, shape C)
    r_gyro    = gamma + b                         gyro bias b

Free: the cornering coefficients c_f = C_f / F_zf and c_r = C_r / F_zr (cornering stiffness per
unit axle load, 1/rad), tau, T, b, delta_0, g (command input only), the front relaxation length
sigma_f (a set may give it; identify fits it: held, a value 10 % off pulls K by about 1 %), and
mu, C for the saturation effect; m, I, l_f, l_r and the rear relaxation length are the study's. In these terms the understeer
gradient (delta = L / R + K a_y in steady cornering) is K = (1 / c_f - 1 / c_r) / g_0, whatever
the mass and CG position (g_0 = 9.81 m/s2).

The log is cut into segments of driving (v above ``min_speed``, no clock gap), each simulated from
a kinematic state with a burn-in before the samples it is scored on; every third segment is held
out. The segments are simulated by a compiled kernel (single_track_kernel: C, one row after
another; the reference is the Python path, every row stepped together): with linear tyres each
sample by the model's exact discretisation at the sample's mean speed (no step-size bias), with
the Magic Formula by ROS2 substeps of at most ``max_substep``; and the fit uses at most
``max_fit_seconds`` of segments spread over the log: the cost grows linearly with the log's length
at most. Least squares (scipy, bounded); intervals from the
Jacobian, inflated by n / n_eff for the residuals' autocorrelation.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd
from scipy.ndimage import convolve1d
from scipy.optimize import least_squares, lsq_linear

from agrobot.estimation import (FitResult, Parameter, effective_size, forward_jacobian, solution_covariance,
                                updates_on)
from agrobot.measurements.own_samples import interpolates, interpolation_weights
from agrobot.measurements.runs import SENT_WITH_ROW, last_update
from agrobot.measurements.streams import HELD
from agrobot.orchestrator.errors import InputError

from agrobot.components.models.tyre import GAMMA_ROS2, N_STATES, axle_loads, rates
from agrobot.components.models.yaw_dynamics import GRAVITY, TractorParameters
from agrobot.components.tractor_yaw_plant import steer_input

from . import single_track_kernel



class NotEnoughDriving(InputError, ValueError):
    """The log holds too little driving to identify the yaw dynamics (the reason says how much more)."""


class BadInputHold(InputError, ValueError):
    """An input hold not among auto, zoh and linear."""


AUTO, ZOH, LINEAR = "auto", "zoh", "linear"      # how the input is read between its samples (--input-hold)


@dataclass
class HeldInput:
    """A set-point held between its updates: from ``times[k]`` (increasing, s) the value
    ``values[k]`` is in force (before the first: the first)."""

    times: np.ndarray
    values: np.ndarray
    _start: np.ndarray = field(init=False, repr=False, compare=False)     # the integral at each update, summed once

    def __post_init__(self):
        self._start = np.r_[0.0, np.cumsum(self.values[:-1] * np.diff(self.times))]

    def at(self, t: np.ndarray) -> np.ndarray:
        """The value in force at t: the last update at or before it."""
        return self.values[self._in_force(t)]

    def _in_force(self, t: np.ndarray) -> np.ndarray:
        """The index of the update in force at t (before the first: the first)."""
        return np.clip(last_update(self.times, t), 0, len(self.values) - 1)

    def integral(self, t: np.ndarray) -> np.ndarray:
        """int_{times[0]}^t of the held value (before the first update: the first value)."""
        k = self._in_force(t)
        return self._start[k] + self.values[k] * (t - self.times[k])


@dataclass
class DrivingLog:
    """The log on an even grid: steering input u, speed v, gyro r; ``run`` numbers the
    stretches without a clock gap; ``held``: the input's own updates when it is a set-point held
    between them (zero-order hold), None when it is a sampled signal (linear between samples)."""

    t: np.ndarray
    u: np.ndarray
    v: np.ndarray
    r: np.ndarray
    run: np.ndarray
    h: float
    input_name: str
    notes: list[str] = field(default_factory=list)
    measured: np.ndarray | None = None         # where r is measured (a course: not on slow stretches)
    update_times: np.ndarray | None = None     # the yaw measurement's own update times (None: every sample)
    kernel: np.ndarray | None = None           # the averaging a derived yaw rate applies (None: a gyro's)
    held: HeldInput | None = None              # a set-point input's updates (None: linear between samples)
    sampled: np.ndarray | None = None          # (N, 2B + 1): the yaw measurement on samples i-B..i+B (yaw_sampling)
    lean: np.ndarray | None = None             # gravity's lateral share g sin(bank) [m/s2] (ground_lean; None: untold)

    def as_measured(self, r: np.ndarray, idx: np.ndarray | None = None) -> np.ndarray:
        """A yaw rate (.., L) along its last axis as the measurement sees it (``kernel``; ``sampled``:
        on the samples ``idx`` (.., L), None: the whole log)."""
        if self.kernel is not None:
            r = convolve1d(r, self.kernel[::-1], axis=-1, mode="nearest")
        if self.sampled is None:
            return r
        L, B = r.shape[-1], (self.sampled.shape[1] - 1) // 2
        rows = self.sampled[np.arange(L) if idx is None else idx]          # (.., L, 2B + 1)
        return sum(rows[..., o + B] * np.take(r, np.clip(np.arange(L) + o, 0, L - 1), axis=-1) for o in range(-B, B + 1))

    def updates_in(self, segs: "Segments", mask: np.ndarray | None = None) -> int | None:
        """How many of the yaw measurement's own updates fall on the scored samples (None: one
        per sample)."""
        keep = segs.scored if mask is None else segs.scored & mask
        return updates_on(self.update_times, self.t, self.h, segs.idx[keep])

    @property
    def a_y(self) -> np.ndarray:
        """Measured lateral acceleration of steady turning, v r [m/s2]."""
        return self.v * self.r

    def run_start(self) -> np.ndarray:
        first = np.r_[True, self.run[1:] != self.run[:-1]]
        return self.t[first][np.cumsum(first) - 1]

    def run_end(self) -> np.ndarray:
        last = np.r_[self.run[1:] != self.run[:-1], True]
        return self.t[last][::-1][np.cumsum(last[::-1]) - 1][::-1]

    def delayed_input(self, tau: float) -> np.ndarray:
        """u(t - tau) on every sample, per run, clipped to the run's first and last samples; a
        negative tau (a clock offset: the response stamped before its input) reads ahead. A held
        input: the update in force at t - tau (the last at or before it), else linear between samples."""
        if tau == 0:
            return self.u
        tq = np.clip(self.t - tau, self.run_start(), self.run_end())
        if self.held is not None:
            return self.held.at(tq)
        return np.interp(tq + self.run * 1e6, self.t + self.run * 1e6, self.u)

    def hold_phases(self, tau: float) -> np.ndarray:
        """A held input's step from sample j to j + 1 as one switch: w_j for the first phi_j h, then
        w_j+1 (phi_j in [0, 1], 1: no switch), phi_j the one that keeps the step's mean of the held
        u(t - tau) (exact for one update in the step). The last sample of a run: 1."""
        start, end = self.run_start(), self.run_end()
        a = np.clip(self.t - tau, start, end)
        b = np.clip(self.t + self.h - tau, start, end)
        below = np.clip(start - (self.t - tau), 0.0, self.h)          # the step's time read at the run's ends
        above = np.clip(self.t + self.h - tau - end, 0.0, self.h)
        held = self.held
        mean = (held.integral(b) - held.integral(a) + held.at(start) * below + held.at(end) * above) / self.h
        w0, w1 = held.at(a), held.at(b)
        jump = w1 - w0
        safe = np.abs(jump) > 1e-12 * np.maximum(np.abs(w0) + np.abs(w1), 1e-300)
        phi = np.where(safe, (w1 - mean) / np.where(safe, jump, 1.0), 1.0)
        phi = np.clip(phi, 0.0, 1.0)
        phi[np.r_[self.run[1:] != self.run[:-1], True]] = 1.0
        return phi


def even_grid(frame: pd.DataFrame, input_name: str, max_rate: float = 50.0, gap: float | None = None,
              update_times: np.ndarray | None = None, hold: str = LINEAR) -> DrivingLog:
    """Interpolate each gap-free stretch of the log onto an even clock (its median step, no finer
    than ``max_rate``: a faster log is averaged over the coarser step first); a step longer than
    ``gap`` (default max(0.5 s, 5 median steps)) splits; a yaw rate not measured (nan) is 0 and
    marked in ``measured``. ``hold`` (input_hold): a held input, a set-point held between its
    updates, is read at the grid as the update in force (held_updates), never averaged into a ramp."""
    t = frame["t"].to_numpy(float)
    dt = np.diff(t)
    step = float(np.median(dt))
    h = max(step, 1.0 / max_rate)
    updates, said = input_hold(frame, input_name, hold)
    if updates is not None and len(updates.times) > 1 and float(np.median(np.diff(updates.times))) < h * 0.99:
        # a step holds one switch of a held input (hold_phases): the most rows within its update interval
        coarsest, h = h, step * max(1, math.floor(float(np.median(np.diff(updates.times))) / step + 1e-9))
        if h < coarsest * (1 - 1e-9):
            said += (f"; the clock set to {1 / h:.3g} Hz, its update rate, finer than the {max_rate:g} Hz the fit keeps to "
                     f"otherwise (max_rate, passed over: a step holds at most one switch of the held input); "
                     f"--input-hold linear keeps {max_rate:g} Hz")
    gap = gap or max(0.5, 5 * step)
    cuts = np.flatnonzero(dt > gap) + 1
    notes = []
    if len(cuts):
        notes.append(f"{len(cuts)} clock gap(s) longer than {gap:.3g} s: the log is cut there")
    jitter = float(np.std(dt[dt <= gap]) / step) if len(dt) else 0.0
    if jitter > 0.05 or h > step * 1.01:
        notes.append(f"samples interpolated onto an even {1 / h:.3g} Hz clock (median step {step * 1e3:.3g} ms, "
                     f"jitter {100 * jitter:.0f} %)")
    notes.append(said)
    parts = {"t": [], "u": [], "v": [], "r": [], "run": []}
    for k, (a, b) in enumerate(zip(np.r_[0, cuts], np.r_[cuts, len(t)])):
        if b - a < 2:
            continue
        grid = t[a] + h * np.arange(int(math.floor((t[b - 1] - t[a]) / h + 1e-9)) + 1)
        parts["t"].append(grid)
        k_avg = int(round(h / step))
        for key, col in (("u", input_name), ("v", "v"), ("r", "yaw_rate")):
            x = frame[col].to_numpy(float)[a:b]
            if key == "u" and updates is not None:
                continue
            if k_avg > 1 and b - a > k_avg:         # a coarser clock: average over its step first (no aliasing)
                x = np.convolve(np.pad(x, (k_avg // 2, k_avg - 1 - k_avg // 2), mode="edge"), np.ones(k_avg) / k_avg,
                                mode="valid")
            parts[key].append(np.interp(grid, t[a:b], x))
        parts["run"].append(np.full(len(grid), k))
    if updates is not None:          # an average over k steps reads the time its window centres on: alike
        k_avg = int(round(h / step))
        updates = HeldInput(updates.times + step * (k_avg // 2 - (k_avg - 1) / 2), updates.values)
        parts["u"] = [updates.at(g) for g in parts["t"]]
    arrays = {k: np.concatenate(v) for k, v in parts.items()}
    measured = np.isfinite(arrays["r"])
    log = DrivingLog(arrays["t"], arrays["u"], arrays["v"], np.where(measured, arrays["r"], 0.0), arrays["run"], h,
                     input_name, notes, measured, update_times, held=updates)
    own = (frame.attrs.get("own_samples") or {}).get("yaw_rate")
    if own is not None and update_times is None:
        log.sampled, said = yaw_sampling(log, np.asarray(own[0], float), np.asarray(own[1], float), t)
        notes.append(said)
    elif frame.attrs.get("own_samples_dropped") and update_times is None:
        notes.append(f"yaw rate: its own sampling not modelled ({frame.attrs['own_samples_dropped']})")
    return log


def input_hold(frame: pd.DataFrame, input_name: str, hold: str = AUTO) -> tuple[HeldInput | None, str]:
    """(the input's updates when it is held between them, else None; the note that says so).
    ``zoh``: held, on its own update stamps where the log carries them (frame.attrs["own_samples"],
    a recording's import), else from its rows (held_updates: rows that are its stamps); ``linear``:
    linear between rows; ``auto``: a set-point (measurements.streams.HELD) held on its own stamps
    when they keep a steady rate (steady_stamps), else linear: a log's rows quantize a set-point's updates (each somewhere since the row before),
    and the linear ramp between rows is the expectation of a switch spread evenly over that step."""
    if hold not in (AUTO, ZOH, LINEAR):
        raise BadInputHold(f"--input-hold {hold!r}: expected {AUTO}, {ZOH} or {LINEAR}")
    own = (frame.attrs.get("own_samples") or {}).get(input_name)
    lacking = frame.attrs.get("own_samples_dropped") or "the log does not carry them"
    if own is not None and not holds(HeldInput(*(np.asarray(a, float) for a in own)), frame["t"].to_numpy(float),
                                     frame[input_name].to_numpy(float)):
        own, lacking = None, "the column changed since the import: its rows no longer what they hold"
    steady, spread = steady_stamps(own)
    if hold == ZOH or (hold == AUTO and own is not None and input_name in HELD and steady):
        if own is not None:
            updates = HeldInput(np.asarray(own[0], float), np.asarray(own[1], float))
            where = f"its own {len(updates.times)} updates in the recording"
        else:
            updates = held_updates(frame["t"].to_numpy(float), frame[input_name].to_numpy(float))
            where = f"its rows taken as its update stamps (its own updates not used: {lacking})"
        why = "--input-hold zoh" if hold == ZOH else "auto: a set-point"
        return updates, (f"input {input_name} taken as held between its updates ({why}; {where}: zero-order hold, the "
                         f"value at t - delay the last update at or before it); --input-hold linear reads it linearly "
                         f"between rows")
    what = ("a sampled signal" if input_name not in HELD else
            f"a set-point whose own updates are not used ({lacking}): its rows quantize them" if own is None else
            f"a set-point whose own stamps come in bursts, 10-90 % of their intervals {spread} of their median: "
            f"stamped on receipt, not when it took effect") if hold == AUTO else "--input-hold linear"
    return None, (f"input {input_name} read linearly between its rows ({what}); --input-hold zoh takes it as held "
                  f"between them (for rows that are its own update stamps)")


def steady_stamps(own, band: float = 0.5) -> tuple[bool, str]:
    """(whether a set-point's own stamps keep a sender's steady rate: 10-90 % of their intervals
    within ``band`` of the median, the range they span as text); bursts are stamps of receipt."""
    if own is None or len(own[0]) < 3:
        return False, "-"
    d = np.diff(np.asarray(own[0], float))
    lo, hi = np.percentile(d, [10, 90]) / max(float(np.median(d)), 1e-12)
    return bool(lo >= 1 - band and hi <= 1 + band), f"{lo:.2g}-{hi:.2g}"


def holds(held: HeldInput, t: np.ndarray, x: np.ndarray, slack: float = SENT_WITH_ROW + 1e-4) -> bool:
    """Whether every row x(t) is the update in force at t, within ``slack`` s (the importer takes a
    value sent up to SENT_WITH_ROW after a row as the row's: measurements.runs.held; 0.1 ms more for
    the stamps' rounding)."""
    return bool(np.all((held.at(t) == x) | (held.at(t - slack) == x) | (held.at(t + slack) == x)))


def yaw_sampling(log: DrivingLog, stamps: np.ndarray, values: np.ndarray, rows: np.ndarray
                 ) -> tuple[np.ndarray | None, str]:
    """(DrivingLog.sampled, the note): a gyro whose rows interpolate its own samples at ``stamps``
    (frame.attrs["own_samples"], a recording's import; judged by measurements.own_samples.interpolates,
    the diagnosis's rule) is predicted alike, the model's yaw rate read at the stamps (linear between
    samples) and interpolated back: the weights of each sample on its neighbours; None where the
    grid is not the log's rows (an averaged or resampled clock)."""
    t, h = log.t, log.h
    if len(rows) != len(t) or np.max(np.abs(rows - t)) > 1e-6 * h or len(stamps) < 2:
        return None, "yaw rate: its own sampling not modelled (the grid is not the log's rows)"
    if not interpolates(t, log.r, stamps, values) or not np.all(log.measured):
        return None, "yaw rate: its own sampling not modelled (the rows are not its samples interpolated)"
    n = len(t)
    new_run = np.r_[True, log.run[1:] != log.run[:-1]]
    first = np.flatnonzero(new_run)[np.cumsum(new_run) - 1]                  # each sample's run: first, last index
    run_end = np.r_[np.flatnonzero(new_run)[1:] - 1, n - 1][np.cumsum(new_run) - 1]
    k, a = interpolation_weights(t, stamps)
    entries = []          # (grid index, weight): the sample's two stamps, each linear between grid samples
    for side, weight in ((k, 1.0 - a), (k + 1, a)):
        x = np.clip((stamps[side] - t[first]) / h, 0.0, None)
        j = first + np.floor(x).astype(int)
        f = x - np.floor(x)
        entries += [(j, weight * (1.0 - f)), (j + 1, weight * f)]
    offsets = [np.clip(j, first, run_end) - np.arange(n) for j, _ in entries]
    B = int(max(np.max(np.abs(o)) for o in offsets))
    if B > 8:
        return None, "yaw rate: its own sampling not modelled (its samples more than 8 rows apart)"
    W = np.zeros((n, 2 * B + 1))
    for o, (_, w) in zip(offsets, entries):
        np.add.at(W, (np.arange(n), o + B), w)
    return W, (f"yaw rate: its rows interpolate its own {len(stamps)} samples ({1 / float(np.median(np.diff(stamps))):.3g} "
               f"Hz): the model's yaw rate is read alike (at the samples, interpolated back)")


def held_updates(t: np.ndarray, x: np.ndarray, shift: float = 0.0) -> HeldInput:
    """A set-point's updates from its rows: the first row and every row whose value differs from
    the row before, each at its row (+ ``shift``)."""
    new = np.r_[True, x[1:] != x[:-1]]
    return HeldInput(t[new].astype(float) + shift, x[new].astype(float))


@dataclass
class Segments:
    """Rows of sample indices simulated side by side: ``idx`` (S, L), padded with each row's last
    index; ``scored`` marks the samples a row is judged on (after its burn-in, moving)."""

    idx: np.ndarray
    scored: np.ndarray
    held_out: np.ndarray          # (S,) bool

    def take(self, rows) -> "Segments":
        return Segments(self.idx[rows], self.scored[rows], self.held_out[rows])

    @property
    def seconds(self) -> int:
        return int(self.scored.sum())


def cut_segments(log: DrivingLog, min_speed: float, length: float = 10.0, burn_in: float = 1.0,
                 min_length: float = 1.0, hold_every: int = 3) -> Segments:
    """Stretches of driving (v >= min_speed, no gap, at least ``min_length`` s) cut into pieces of
    about ``length`` s, each simulated from ``burn_in`` s before it (less where its stretch starts
    the run: a quarter of what precedes its end); every ``hold_every``-th piece is held out."""
    h = log.h
    moving = (log.v >= min_speed) & (log.measured if log.measured is not None else True)
    pieces = []
    edges = np.flatnonzero(np.diff(np.r_[0, moving.astype(int), 0]))
    for a, b in zip(edges[::2], edges[1::2]):
        while a < b and log.run[a] != log.run[b - 1]:          # a stretch never crosses a gap
            split = a + int(np.argmax(log.run[a:b] != log.run[a]))
            pieces += _pieces(a, split, h, length, min_length)
            a = split
        pieces += _pieces(a, b, h, length, min_length)
    if not pieces:
        return Segments(np.zeros((0, 1), int), np.zeros((0, 1), bool), np.zeros(0, bool))
    run_first = {}
    for i, k in enumerate(log.run):
        run_first.setdefault(int(k), i)
    rows = []
    burn = int(round(burn_in / h))
    for a, b in pieces:
        start = max(run_first[int(log.run[a])], a - burn)
        settle = min(burn, (b - start) // 4)
        rows.append((start, max(a, start + settle), b))
    L = max(b - s for s, _, b in rows)
    idx = np.empty((len(rows), L), int)
    scored = np.zeros((len(rows), L), bool)
    for i, (s, a, b) in enumerate(rows):
        idx[i, : b - s] = np.arange(s, b)
        idx[i, b - s:] = b - 1
        scored[i, a - s: b - s] = moving[a:b]
    held = (np.arange(len(rows)) % hold_every) == hold_every - 1
    if len(rows) == 1:
        held[:] = False
    return Segments(idx, scored, held)


def _pieces(a: int, b: int, h: float, length: float, min_length: float) -> list[tuple[int, int]]:
    n = b - a
    if n * h < min_length:
        return []
    k = max(1, int(round(n * h / length)))
    bounds = np.linspace(a, b, k + 1).round().astype(int)
    return list(zip(bounds[:-1], bounds[1:]))


SMALL_ANGLE, ACKERMANN = "small angle", "Ackermann"     # how the wheel angle w enters the model: w or tan w


class YawModel:
    """The single-track model of the study driven through delay, gain, offset and lag; simulates
    every segment side by side. ``values``: the free parameters by name (others at their defaults).
    ``kernel``: ``c`` (single_track_kernel), ``python`` (the reference) or ``auto`` (C where a
    compiler is found; default single_track_kernel.DEFAULT)."""

    DEFAULTS = {"delay": 0.0, "lag": 0.0, "gyro_bias": 0.0, "steer_offset": 0.0, "steer_gain": 1.0,
                "friction": math.inf, "friction_ratio": 1.0, "shape": 1.3, "cornering_speed_slope": 0.0,
                "cornering_reference_speed": 2.0}
    # ``friction`` is the front axle's mu, ``friction_ratio`` the rear's over it (mu_r = ratio mu):
    # with one mu on both axles the steady turn delta - L / R = alpha_f - alpha_r is K h(a_y) with h
    # fixed by mu and the shape alone, so the understeer past the linear range scales with K; a
    # vehicle whose front lets go first (or its rear) has limit understeer its K does not set

    def __init__(self, model: str, params: TractorParameters, log: DrivingLog, segs: Segments,
                 max_substep: float = 0.02, min_sim_speed: float = 0.05, kernel: str | None = None,
                 geometry: str = SMALL_ANGLE) -> None:
        self.model, self.p, self.log, self.segs = model, params, log, segs
        self.geometry = geometry               # how the wheel angle enters: SMALL_ANGLE (w) or ACKERMANN (tan w)
        self.kernel = kernel or single_track_kernel.DEFAULT     # "c", "python" (the reference) or "auto"
        self.loads = axle_loads(params.m, params.l_f, params.l_r)
        self.L = params.l_f + params.l_r
        self.n_sub = max(1, int(math.ceil(log.h / max_substep)))
        # below min_sim_speed the slip equations (1/v) are replaced by that speed and the yaw rate
        # scaled by v / min_sim_speed, as in the plant: a car at rest does not turn
        self.v_sim = np.maximum(log.v, min_sim_speed)
        self.low_speed_scale = np.clip(log.v / min_sim_speed, 0.0, 1.0)

    def wheel_angle(self, values: dict) -> np.ndarray:
        """w = g u(t - tau) + delta_0 on every sample (u before its run's start: its first value);
        tan w under ACKERMANN geometry (the single-track model's steady turn r = v w / (L + K v^2)
        becomes r = v tan w / (L + K v^2), the no-slip turn of an Ackermann machine)."""
        u = self.log.delayed_input(values.get("delay", 0.0))
        return self.turning(values.get("steer_gain", 1.0) * u + values.get("steer_offset", 0.0))

    def turning(self, w: np.ndarray) -> np.ndarray:
        """The wheel angle as it turns the model: w, tan w under ACKERMANN geometry (clipped as the
        plant's: components.tractor_yaw_plant.steer_input)."""
        return steer_input(w, "tan") if self.geometry == ACKERMANN else w

    def simulate(self, values: dict, segs: Segments | None = None) -> np.ndarray:
        """Gyro reading the model predicts, (S, L) on the segments' samples."""
        return self.simulate_many([values], segs)[0]

    def simulate_many(self, sets: list[dict], segs: Segments | None = None, lateral: bool = False):
        """(R, S, L): the model under each of R parameter sets, all rows in one call (the C kernel
        steps them one after another; the Python path steps them together: a Jacobian's sets cost
        little more than one; sets that differ only in the gyro bias are simulated once);
        ``lateral``: also the lateral velocity at the centre of gravity v_y, (yaw, v_y)."""
        sets = [{**self.DEFAULTS, **v} for v in sets]
        segs = segs or self.segs
        idx = segs.idx
        S, L = idx.shape
        R = len(sets)
        distinct, which = self._distinct(sets)
        yaw, vy = self._simulate_rows(distinct, idx)
        pick = (which[:, None] * S + np.arange(S)).ravel()          # (R S,): each set's rows
        low_speed = np.tile(self.low_speed_scale[idx], (R, 1))
        out = yaw[pick] * low_speed
        out = self.log.as_measured(out, np.tile(idx, (R, 1)))     # a yaw rate derived from a heading: averaged alike
        out += np.repeat([float(v["gyro_bias"]) for v in sets], S)[:, None]
        if lateral:
            return out.reshape(R, S, L), (vy[pick] * low_speed).reshape(R, S, L)
        return out.reshape(R, S, L)

    def _distinct(self, sets: list[dict]) -> tuple[list[dict], np.ndarray]:
        """(the sets that differ in more than the gyro bias, which of them each set is); every set
        its own when the vehicle's parameters are per row (the replays' relaxation lengths)."""
        if any(np.ndim(getattr(self.p, k)) for k in ("m", "I", "l_f", "l_r", "sigma_f", "sigma_r")):
            return sets, np.arange(len(sets))
        first: dict[tuple, int] = {}
        which = [first.setdefault(tuple((k, v[k]) for k in sorted(v) if k != "gyro_bias"), len(first)) for v in sets]
        distinct = [None] * len(first)
        for v, i in zip(sets, which):
            distinct[i] = distinct[i] or v
        return distinct, np.array(which, int)

    def _simulate_rows(self, sets: list[dict], idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(yaw rate, v_y), each (R S, L), of the single-track model under each set (before the
        low-speed scaling, the measurement's averaging and the gyro bias)."""
        S = len(idx)
        w = np.concatenate([self.wheel_angle(v)[idx] for v in sets])          # (R S, L)
        rows = {key: np.repeat([float(v[key]) for v in sets], S) for key in self.DEFAULTS.keys() | {"c_f", "c_r"}}
        h = self.log.h
        lag = rows["lag"]
        a = np.where(lag > 1e-6, np.exp(-h / np.maximum(lag, 1e-6)), 0.0)
        # the lag's exact step for an input linear between samples (first-order hold):
        # d+ = a d + (1 - a) w_j + c (w_j+1 - w_j), c = 1 - (T/h)(1 - a): c -> 1 as T -> 0 (no lag,
        # d = w), c -> (1 - a)/2 for T >> h; its delay at low frequency is T, whatever h
        c = 1.0 - lag / h * (1.0 - a)
        p = self.row_parameters(sets, S)
        # a held input: each sample step's switch from w_j to w_j+1 (DrivingLog.hold_phases)
        phase = (None if self.log.held is None else
                 np.concatenate([self.log.hold_phases(float(v["delay"]))[idx] for v in sets]))
        if single_track_kernel.choose(self.kernel) == "c":
            return single_track_kernel.simulate(self.model, self.n_sub, h, w, self.v_sim[idx], self._packed(rows, a, c, p),
                                                phase)
        vv = np.tile(self.v_sim[idx], (len(sets), 1))
        if phase is not None:
            return self._simulate_python_held(w, vv, phase, rows, p)
        return self._simulate_python(w, vv, rows, a, c, p)

    def row_parameters(self, sets: list[dict], S: int) -> TractorParameters:
        """The vehicle's parameters, the front relaxation length per row (R S,) when a set gives
        one (``sigma_f``, m)."""
        if not any("sigma_f" in v for v in sets):
            return self.p
        if np.ndim(self.p.sigma_f):
            raise ValueError("a relaxation length per set and per row at once")
        return replace(self.p, sigma_f=np.repeat([float(v.get("sigma_f", self.p.sigma_f)) for v in sets], S))

    def _packed(self, rows: dict, a: np.ndarray, c: np.ndarray, p: TractorParameters) -> np.ndarray:
        """The C kernel's per-row parameters (single_track_kernel.PARAMETERS), (R S, P)."""
        Fzf, Fzr = self.loads
        columns = {"lag_decay": a, "hold_gain": c, "lag": rows["lag"], "delay": rows["delay"], "C_f": rows["c_f"] * Fzf, "C_r": rows["c_r"] * Fzr,
                   "mu": rows["friction"], "shape": rows["shape"],
                   "F_zr": Fzr * rows["friction_ratio"],           # the kernel's rear peak is mu F_zr: mu_r F_zr
                   "cornering_speed_slope": rows["cornering_speed_slope"],
                   "cornering_reference_speed": rows["cornering_reference_speed"],
                   "sigma_f": p.sigma_f, "sigma_r": p.sigma_r, "m": p.m, "I": p.I, "l_f": p.l_f, "l_r": p.l_r,
                   "F_zf": Fzf}
        n = len(a)
        return np.stack([np.broadcast_to(np.asarray(columns[k], float), (n,)) for k in single_track_kernel.PARAMETERS],
                        axis=1)

    def _stepped(self, w: np.ndarray, vv: np.ndarray, rows: dict, p: TractorParameters, step):
        """The reference paths' loop: (yaw rate, v_y) each (rows, L) from the kinematic state at the
        first sample, carried from sample j to j + 1 by ``step(j, z, d, linear, tyre, cornering)``
        -> (z, d) (d the wheel angle; linear: the rows with linear tyres; cornering: C_f, C_r,
        slope, v_ref)."""
        Fzf, Fzr = self.loads
        Cf, Cr = rows["c_f"] * Fzf, rows["c_r"] * Fzr
        mu = rows["friction"]
        saturating = np.any(np.isfinite(mu))
        tyre = {"mu": mu if saturating else np.inf, "mu_r": mu * rows["friction_ratio"] if saturating else np.inf,
                "shape": rows["shape"], "C_f": Cf, "C_r": Cr}
        cornering = (Cf, Cr, rows["cornering_speed_slope"], rows["cornering_reference_speed"])
        n_rows, L = w.shape
        z = np.zeros((n_rows, N_STATES[self.model]))
        d = w[:, 0].copy()
        r0 = vv[:, 0] * d / self.L                       # kinematic start
        z[:, 0], z[:, 1] = p.l_r * r0, r0
        out, out_vy = np.empty((n_rows, L)), np.empty((n_rows, L))
        for j in range(L):
            out[:, j], out_vy[:, j] = z[:, 1], z[:, 0]
            if j < L - 1:
                z, d = step(j, z, d, ~np.isfinite(mu), tyre, cornering)
        return out, out_vy

    def _simulate_python(self, w: np.ndarray, vv: np.ndarray, rows: dict, a: np.ndarray, c: np.ndarray,
                         p: TractorParameters):
        """The reference path: every row stepped together, (yaw rate, v_y) each (rows, L), from the
        kinematic state; rows with linear tyres by the exact first-order-hold step at the sample's
        mean speed (``exact_steps``), the others by ``n_sub`` ROS2 substeps per sample
        (components.models.tyre.rates)."""
        def step(j, z, d, linear, tyre, cornering):
            Cf, Cr, slope, v_ref = cornering
            d_next = a * d + (1.0 - a) * w[:, j] + c * (w[:, j + 1] - w[:, j])
            z_next = z.copy()
            if np.any(~linear):          # speed and wheel angle linear across the step
                v0, v1, n_sub = vv[:, j], vv[:, j + 1], self.n_sub
                z_next = self._ros2_substeps(p, z, self.log.h / n_sub, lambda k: (
                    v0 + k / n_sub * (v1 - v0), d + k / n_sub * (d_next - d)), tyre, cornering)
            if np.any(linear):
                vm = 0.5 * (vv[:, j] + vv[:, j + 1])
                scale = cornering_scale(slope, v_ref, vm)
                P, g1, g2 = exact_steps(self.model, p, vm, self.log.h, {**tyre, "C_f": Cf * scale, "C_r": Cr * scale})
                exact = np.einsum("sij,sj->si", P, z) + g1 * d[:, None] + g2 * (d_next - d)[:, None]
                z_next = np.where(linear[:, None], exact, z_next)
            return z_next, d_next
        return self._stepped(w, vv, rows, p, step)

    def _simulate_python_held(self, w: np.ndarray, vv: np.ndarray, phase: np.ndarray, rows: dict,
                              p: TractorParameters):
        """The reference path for a held input (zero-order hold): each sample step in two pieces,
        w_j for phi_j h then w_j+1 (``phase``), through the lag d' = (w - d) / T exactly (T = 0:
        d = w); linear tyres by the exact step of the model with d as a state, x = [z, d],

            x+ = expm(t A) x + t phi1(t A) B w,  A = [[J, b], [0, -1/T]],  B = [0, 1/T]

        at the sample's mean speed (T = 0: A's corner and B 0, d set to w first), the Magic Formula
        by ``n_sub`` ROS2 substeps per piece on d exact at their ends."""
        n, h = N_STATES[self.model], self.log.h
        inv_T = np.where(rows["lag"] > 1e-6, 1.0 / np.maximum(rows["lag"], 1e-6), 0.0)

        def step(j, z, d, linear, tyre, cornering):
            Cf, Cr, slope, v_ref = cornering
            vm = 0.5 * (vv[:, j] + vv[:, j + 1])
            scale = cornering_scale(slope, v_ref, vm)
            lin_tyre = {**tyre, "mu": np.inf, "mu_r": np.inf, "C_f": Cf * scale, "C_r": Cr * scale}
            for start, length, omega in ((0.0, phase[:, j] * h, w[:, j]), (phase[:, j] * h, (1.0 - phase[:, j]) * h,
                                                                              w[:, j + 1])):
                d = np.where(inv_T > 0, d, omega)
                z_next, d_next = z, omega + (d - omega) * np.exp(-length * inv_T)
                if np.any(~linear):          # speed linear across the sample step, d exact through the lag
                    z_next = self._ros2_substeps(p, z, length / self.n_sub, self._lagged_law(
                        vv[:, j], vv[:, j + 1], start, length / self.n_sub, d, omega, inv_T), tyre, cornering)
                if np.any(linear):
                    b, J = rates(self.model, p, vm, np.ones_like(vm), np.zeros((len(vm), n)), **lin_tyre)
                    A = np.zeros((len(vm), n + 1, n + 1))
                    A[:, :n, :n], A[:, :n, n], A[:, n, n] = J, b, -inv_T
                    B = np.zeros((len(vm), n + 1))
                    B[:, n] = inv_T
                    P, g1, _ = phi_steps(A, B, length)
                    x = np.einsum("sij,sj->si", P, np.c_[z, d]) + g1 * omega[:, None]
                    z_next = np.where(linear[:, None], x[:, :n], z_next)
                    d_next = np.where(linear, x[:, n], d_next)
                z, d = z_next, d_next
            return z, d
        return self._stepped(w, vv, rows, p, step)

    def _lagged_law(self, v_start, v_end, start, hs, d0, omega, inv_T):
        """The input law of a piece from ``start`` s into a sample step, substeps ``hs`` (rows,):
        k -> (speed linear across the sample step, d = w + (d0 - w) exp(-s / T) (T = 0: w)) at s = k hs."""
        h = self.log.h
        return lambda k: (v_start + (start + k * hs) / h * (v_end - v_start),
                          omega + (d0 - omega) * np.exp(-(k * hs) * inv_T))

    def _ros2_substeps(self, p, z, hs, law, tyre, cornering):
        """The state after ``n_sub`` ROS2 substeps of ``hs`` s (a number or one per row), ``law(k)``
        the (speed, wheel angle) at the k-th substep's start; the cornering scaled at each substep's
        mean speed (components.models.tyre.rates)."""
        Cf, Cr, slope, v_ref = cornering
        hz, hm = (np.reshape(hs, (-1, 1)), np.reshape(hs, (-1, 1, 1))) if np.ndim(hs) else (hs, hs)
        eye = np.eye(z.shape[1])
        for k in range(self.n_sub):
            (v0, d0), (v1, d1) = law(k), law(k + 1)
            scale = cornering_scale(slope, v_ref, 0.5 * (v0 + v1))
            tyre = {**tyre, "C_f": Cf * scale, "C_r": Cr * scale}
            f0, J = rates(self.model, p, v0, d0, z, **tyre)
            M = np.linalg.inv(eye - GAMMA_ROS2 * hm * J)
            k1 = np.einsum("sij,sj->si", M, f0)
            f1, _ = rates(self.model, p, v1, d1, z + hz * k1, **tyre)
            k2 = np.einsum("sij,sj->si", M, f1 - 2.0 * k1)
            z = z + hz * (1.5 * k1 + 0.5 * k2)
        return z


def cornering_scale(slope: np.ndarray, v_ref: np.ndarray, v: np.ndarray) -> np.ndarray:
    """max(0.2, 1 + k (v - v_ref)) where k != 0, else 1: the speed-dependent cornering's factor."""
    return np.where(slope != 0.0, np.maximum(0.2, 1.0 + slope * (v - v_ref)), 1.0)


def exact_steps(model: str, p, v: np.ndarray, h: float, tyre: dict, degree: int = 12):
    """(P, g1, g2), (rows, n, n), (rows, n), (rows, n): the exact step of the linear single-track
    model dz/dt = J z + b d at speed v over h for a wheel angle linear across it (d0 -> d1),

        z+ = P z + g1 d0 + g2 (d1 - d0),  P = expm(h J),  g1 = h phi1(h J) b,  g2 = h phi2(h J) b,

    phi1(X) = sum X^k / (k + 1)!, phi2(X) = sum X^k / (k + 2)! (linear tyres: b = f(0, 1)); by
    scaling and squaring as single_track_kernel.c: X = h J / 2^s, ||X||_1 <= 1/2, expm(X) by the
    [6/6] Pade approximant, phi2(X) b by Horner to ``degree``, phi1(X) b = b + X phi2(X) b, then s squarings of the block matrix
    [[P, g1, g2], [0, 1, c], [0, 0, 1]] (c = 2^-s at the start)."""
    n = N_STATES[model]
    b, J = rates(model, p, v, np.ones_like(v), np.zeros((len(v), n)), **{**tyre, "mu": np.inf, "mu_r": np.inf})
    return phi_steps(J, b, np.full(len(v), float(h)), degree)


def phi_steps(J: np.ndarray, b: np.ndarray, h: np.ndarray, degree: int = 12):
    """(P, g1, g2) of dz/dt = J z + b d over h (rows,) for d linear across the step (d0 -> d1):

        z+ = P z + g1 d0 + g2 (d1 - d0),  P = e^{hJ},  g1 = int_0^h e^{Js} ds b = h phi1(hJ) b,
        g2 = (1/h) int_0^h e^{Js} (h - s) ds b = h phi2(hJ) b

    (the top block row of expm([[hJ, hb, 0], [0, 0, I], [0, 0, 0]])), as exact_steps and the C twin
    identification/phi_step.h. b: (rows, n), or (rows, n, p) for p inputs, each column with its own
    arithmetic; g1 and g2 alike."""
    cols = b if b.ndim == 3 else b[:, :, None]
    norm = np.abs(h[:, None, None] * J).sum(axis=1).max(axis=1)
    s = np.where(norm > 0.5, np.ceil(np.log2(np.maximum(norm, 0.5) / 0.5)), 0.0).astype(int)
    scale = np.ldexp(h, -s)
    X = J * scale[:, None, None]
    beta = cols * scale[:, None, None]
    terms = beta / np.array([float(math.factorial(k + 2)) for k in range(degree + 1)])[:, None, None, None]
    y = terms[degree]
    for k in range(degree - 1, -1, -1):              # phi2(X) beta = sum_k X^k beta / (k + 2)!, by Horner
        y = X @ y
        y += terms[k]
    c = np.ldexp(1.0, -s)[:, None, None]
    order = np.argsort(-s, kind="stable")            # the rows still squaring at step k: a prefix
    P, c, s = pade_expm(X)[order], c[order], s[order]
    g1, g2 = (beta + X @ y)[order], (c * y[order])   # phi1(X) beta = beta + X phi2(X) beta
    for k in range(int(s.max(initial=0))):
        m = int(np.count_nonzero(s > k))
        Pm, g1m = P[:m], g1[:m]
        g2[:m] = Pm @ g2[:m] + c[:m] * g1m + g2[:m]
        g1[:m] = Pm @ g1m + g1m
        c[:m] *= 2.0
        P[:m] = Pm @ Pm
    back = np.argsort(order)
    P, g1, g2 = P[back], g1[back], g2[back]
    return (P, g1, g2) if b.ndim == 3 else (P, g1[:, :, 0], g2[:, :, 0])


PADE_6 = (1.0, 1.0 / 2, 5.0 / 44, 1.0 / 66, 1.0 / 792, 1.0 / 15840, 1.0 / 665280)


def pade_expm(X: np.ndarray) -> np.ndarray:
    """expm of each matrix of X (rows, n, n), ||X||_1 <= 1/2: the [6/6] Pade approximant
    (coefficients PADE_6; relative error below 1e-16)."""
    c = PADE_6
    eye = np.eye(X.shape[1])
    X2 = X @ X
    X4 = X2 @ X2
    X6 = X4 @ X2
    U = X @ (c[1] * eye + c[3] * X2 + c[5] * X4)
    V = c[0] * eye + c[2] * X2 + c[4] * X4 + c[6] * X6
    return np.linalg.solve(V - U, V + U)


def understeer_gradient(c_f: float, c_r: float) -> float:
    """K = (1/c_f - 1/c_r) / g_0 [rad/(m/s2)] from the cornering coefficients (stiffness / axle load)."""
    return (1.0 / c_f - 1.0 / c_r) / GRAVITY


def steady_state_gain(speed, K: float, L: float, gain: float = 1.0):
    """Steady-state yaw rate per unit steering input: g v / (L + K v^2)."""
    speed = np.asarray(speed, float)
    return gain * speed / (L + K * speed ** 2)


def _problem(model: YawModel, free: list[Parameter], fixed: dict, segs: Segments, mask: np.ndarray):
    """(values_of, fun, jac, lower, upper) of the least squares of the gyro against the model on the
    ``mask`` samples of ``segs``, in scaled parameters x = value / scale (fit's and gauss_newton_gain's)."""
    r_meas = model.log.r[segs.idx]
    lo = np.array([p.lower / p.scale for p in free])
    hi = np.array([p.upper / p.scale for p in free])

    def values_of(x):
        return {**fixed, **{p.name: float(xi) * p.scale for p, xi in zip(free, x)}}

    last: dict[str, np.ndarray] = {}

    def fun(x):
        last["x"], last["f"] = np.array(x, float), (r_meas - model.simulate(values_of(x), segs))[mask]
        return last["f"]

    def jac(x):
        """Forward differences, every perturbed set simulated in one batched pass (f(x): the last
        residuals when they were at x, as least_squares asks; rows are simulated alike alone or
        batched, so the columns are the same)."""
        f0 = last["f"] if "x" in last and np.array_equal(last["x"], x) else None
        return forward_jacobian(lambda xs: [(r_meas - s)[mask] for s in model.simulate_many(
            [values_of(xi) for xi in xs], segs)], x, lo, hi, f0=f0, floor=1.0, signed=False)

    return values_of, fun, jac, lo, hi


def _start_point(free: list[Parameter], start: dict, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    return np.clip([start[p.name] / p.scale for p in free], lo + 1e-6 * (hi - lo), hi - 1e-6 * (hi - lo))


def fit(model: YawModel, free: list[Parameter], start: dict, fixed: dict, segs: Segments,
        max_nfev: int = 40, mask: np.ndarray | None = None) -> FitResult:
    """Bounded least squares of the gyro against the model on ``segs``' scored samples (and
    ``mask``, (S, L), when given)."""
    r_meas = model.log.r[segs.idx]
    mask = segs.scored if mask is None else segs.scored & mask
    values_of, fun, jac, lo, hi = _problem(model, free, fixed, segs, mask)
    x0 = _start_point(free, start, lo, hi)
    sol = least_squares(fun, x0, jac=jac, bounds=(lo, hi), max_nfev=max_nfev, x_scale=1.0, ftol=1e-6, xtol=1e-6)
    values = values_of(sol.x)
    res = sol.fun
    residual = r_meas - model.simulate(values, segs)
    rows = [residual[i][mask[i]] for i in range(len(segs.idx))]
    n, n_eff = len(res), effective_size(rows, updates=model.log.updates_in(segs, mask))
    cov = solution_covariance(sol.jac, sol.cost, sol.x, free, n, n_eff)    # one on its bound held there
    return FitResult(values, tuple(free), cov, {"yaw": float(res @ res)}, {"yaw": n}, {"yaw": n_eff},
                     converged=bool(sol.status > 0))


def gauss_newton_gain(model: YawModel, free: list[Parameter], start: dict, fixed: dict, segs: Segments,
                      added: tuple[str, ...]) -> tuple[float, float]:
    """(RSS at ``start``, the fall of the RSS the ``added`` parameters bring to first order): with
    the residuals f and fit's Jacobian J at start, the Gauss-Newton step within the bounds,
    min over lower <= x0 + dx <= upper of |f + J dx|^2 (scipy lsq_linear), taken with every parameter
    of ``free`` less that taken with ``added`` held. At the optimum of the fit without them it is the
    score test's (Rao) gain of the parameters added, and what is left of that fit's own descent
    (stopped on its budget) is not theirs. One batched Jacobian: the cost of one step of ``fit``."""
    values_of, fun, jac, lo, hi = _problem(model, free, fixed, segs, segs.scored)
    x0 = _start_point(free, start, lo, hi)
    f = fun(x0)
    J = jac(x0)
    rss = float(f @ f)

    def fall(columns: np.ndarray) -> float:
        step = lsq_linear(J[:, columns], -f, bounds=(lo[columns] - x0[columns], hi[columns] - x0[columns]))
        return rss - 2.0 * float(step.cost)

    kept = np.array([p.name not in added for p in free])
    return rss, fall(np.ones(len(free), bool)) - fall(kept)


def fit_percent(y: np.ndarray, yhat: np.ndarray) -> float:
    """100 (1 - ||y - yhat|| / ||y - mean y||): the NRMSE fit (100 % perfect, 0 % the mean)."""
    den = float(np.linalg.norm(y - y.mean()))
    return float(100.0 * (1.0 - np.linalg.norm(y - yhat) / den)) if den > 0 else float("nan")
