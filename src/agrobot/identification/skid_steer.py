"""The yaw dynamics of a skid-steered (or differential-drive) vehicle: the gyro against a turn-rate input.

A skid-steered vehicle has no steering angle: it turns by the difference of its sides' wheel (or
track) speeds. Its input is a turn rate ``w``: the wheel odometry's yaw rate (v_R - v_L) / B
(column ``odom_yaw_rate``, B the track the odometry divides by), else a commanded turn rate such
as cmd_vel.angular.z (column ``turn_rate_cmd``). Model::

    T dy/dt + y = K(w_d) w_d,     w_d = w(t - tau),     r_gyro = y + b
    K(w) = K                      (K (1 - s |w|) where the turn-rate dependence wins, below)

K is the gyro's yaw rate per unit of input turn rate. Against a geometric track B it is B / B_eff:
the wheels of a skid-steered vehicle slip sideways in a turn, so the instantaneous centres of
rotation of its sides lie outside the wheels (Mandow et al., "Experimental kinematics for wheeled
skid-steer mobile robots", IROS 2007: the ICR expansion factor chi = B_eff / B, K = 1 / chi) and the
vehicle turns less than its wheel speeds ask: K of about 0.5-0.95 on grass and soil, smaller at
tighter turns and higher speeds (Wang et al., Sensors 15 (2015) 9681: the ICR coefficient as a
function of path curvature and speed, Pioneer P3-AT). A differential-drive robot on castors turns
as its wheels ask, K about 1. A K above PLAUSIBLE_GAIN is not skid steering: the odometry divides
by an effective track already (ROS diff_drive_controller's wheel_separation_multiplier: 1.875 in
the Clearpath Husky's husky_control/config/control.yaml, where K = 1 / 1.875 = 0.53 against the
geometric track reads as 1 against the odometry), a wheel-speed scale, or a gyro scale. A K below
PLAUSIBLE_GAIN[0] = 0.3 (an ICR expansion chi above 3.3, beyond the 1.5-2.5 measured on tracks and
skid-steered wheels on soil and concrete) is not slip either: an input in deg/s reads K / 57.3, an
input that is not this vehicle's turn rate, or the gyro's wrong axis.

tau is the input's delay to the yaw: positive for a command (the drives' response); for the wheel
odometry it is the odometry's own lateness against the gyro with its sign reversed (a rolling mean
of wheel speeds stamped late gives tau < 0). T is a first-order lag (the drives' and the
vehicle's inertia; stepped exactly for an input linear between samples, as identification.driving
steps the steering lag). b is the gyro bias (none for a yaw rate from a heading).

Fitted by bounded least squares on segments of the log, every third one held out, with the
project's estimation engine (identification.driving.fit, estimation.FitResult: intervals
from the Jacobian inflated by n / n_eff, never more than the yaw measurement's own updates); a
value on a bound is widened to its physical limit once (estimation.Parameter.widened) and, still
there, not concluded. The turn-rate dependence s is kept when it wins on BIC by more than
BIC_MARGIN and takes GAIN_MARGIN off the held-out RMS.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.signal import lfilter

from agrobot.estimation import (AT_BOUND, FitResult, Parameter, interval)
from agrobot.measurements import LogError
from agrobot.measurements.direction import rank_correlation
from agrobot.measurements.log import DEGREE_SUSPECT, robust_peak

from .driving import DrivingLog, NotEnoughDriving, Segments, cut_segments, even_grid, fit_percent
from .driving import fit as driving_fit
from .vehicle import Vehicle

TURN_INPUTS = {"odom_yaw_rate": "wheel odometry", "turn_rate_cmd": "command"}   # in order of preference
INPUT_TEXT = {"wheel odometry": "the wheel odometry's yaw rate (v_R - v_L) / B",
              "command": "the commanded turn rate"}
SKID_DRIVES = ("skid", "differential")
EQUATION = "r(t) = y(t) + b,  T dy/dt + y = K w(t - tau)"
EQUATION_SLOPE = "r(t) = y(t) + b,  T dy/dt + y = K (1 - s |w_d|) w_d,  w_d = w(t - tau)"
PLAUSIBLE_GAIN = (0.3, 1.05)             # K against a geometric track (module docstring)
PLAUSIBLE_DELAY = {"command": (0.0, 0.6), "wheel odometry": (-0.6, 0.3)}      # s
PLAUSIBLE_LAG = {"tractor": 2.0, "truck": 2.0}                                  # s; other classes 1.0
MIN_SECONDS = 20.0
INPUT_SILENCE = 0.5                      # s: the longest the input may go without an update
MIN_TURNING = 0.02                       # rad/s: std of the input turn rate
SEGMENT, BURN_IN = 6.0, 2.0              # s
BIC_MARGIN, GAIN_MARGIN = 10.0, 0.02
DEG = math.pi / 180.0


def applies(frame, vehicle: Vehicle) -> bool:
    """True for a vehicle declared skid-steered or differential (vehicle.drive), or a log without a
    steering angle that holds a turn-rate input (TURN_INPUTS)."""
    if vehicle.drive in SKID_DRIVES:
        return True
    return "delta" not in frame and "delta_cmd" not in frame and any(c in frame for c in TURN_INPUTS)


def why_not_diagnosed(frame, vehicle: Vehicle) -> str | None:
    """Why ``diagnose`` cannot decide on a skid-steered vehicle's log (None: it is not one)."""
    if not applies(frame, vehicle):
        return None
    how = (f"vehicle.drive = {vehicle.drive!r}" if vehicle.drive in SKID_DRIVES else
           f"the log has a turn-rate input ({', '.join(c for c in TURN_INPUTS if c in frame)}) and no steering angle")
    return (f"cannot decide: skid-steered vehicle ({how}); the diagnosis catalogue models Ackermann steering (a "
            f"steering angle through a single-track model): `identify` fits this vehicle's yaw dynamics (K, delay, "
            f"lag, gyro bias against its turn rate)")


def turn_input(frame, where: str) -> tuple[str, list[str]]:
    """(the turn-rate column, notes): the first of TURN_INPUTS the log has (the others passed over,
    said); a LogError naming the columns looked for and the remedy when it has none."""
    have = [c for c in TURN_INPUTS if c in frame]
    if not have:
        second = (" (its yaw_rate_2 is a second yaw-rate source: if it is the wheel odometry's, map that "
                  "field as odom_yaw_rate)" if "yaw_rate_2" in frame else "")
        raise LogError(f"{where}: a skid-steered vehicle's yaw is identified against a turn-rate input, and the log "
                       f"has none: no {' or '.join(TURN_INPUTS)} [rad/s]{second}; map the wheel odometry's yaw rate "
                       f"with --signal 'odom_yaw_rate=/odom.twist.twist.angular.z' or a commanded turn rate with "
                       f"--signal 'turn_rate_cmd=/cmd_vel.angular.z' (a table: a column of that name in rad/s); "
                       f"the log has {', '.join(map(str, frame.columns))}")
    notes = [f"input: {have[0]}, {INPUT_TEXT[TURN_INPUTS[have[0]]]}"]
    bound, unit = DEGREE_SUSPECT[have[0]]
    if (peak := robust_peak(frame[have[0]].to_numpy(float))) > bound:
        notes.append(f"warning: {have[0]} reaches {peak:.3g} (99.5 % of its values within), more than {bound:g} {unit}: "
                     f"it looks like deg/s (declare its unit in its --signal: '{have[0]}=TOPIC[deg/s]')")
    if len(have) > 1:
        notes.append(f"passed over: {', '.join(have[1:])} (the measured wheel odometry is preferred to a command; "
                     f"leave {have[0]} out of the log, or its --signal, to fit the command)")
    if "yaw_rate" not in frame:
        raise LogError(f"{where}: the skid-steer model fits a gyro yaw_rate [rad/s] and the log has none (a yaw rate "
                       f"from a heading or a course is not fitted against a turn rate yet); map the IMU's vertical "
                       f"axis with --signal 'yaw_rate=/imu/data.angular_velocity.z'")
    return have[0], notes


def parameters(vehicle: Vehicle, kind: str, slope: bool = False) -> list[Parameter]:
    """K, tau, T, b (and s): bounds wider than a plausible vehicle's, so that an implausible value is
    fitted and named, not stopped on a bound."""
    lo, hi = (-1.0, 1.0) if kind == "wheel odometry" else (0.0, 1.0)
    bias = vehicle.gyro_bias_bound or 3.0 * DEG
    out = [Parameter("yaw_gain", "1", 0.2, 0.05, 2.5, limit=(0.01, 5.0),
                     meaning="K: gyro yaw rate per unit input turn rate (B / B_eff against a geometric track)"),
           Parameter("delay", "s", 0.1, lo, hi, limit=(-2.0 if lo < 0 else 0.0, 2.5),
                     meaning="tau: delay from the input to the yaw (negative: the input is stamped late)"),
           Parameter("lag", "s", 0.1, 0.0, 2.0, limit=(0.0, 5.0), meaning="T: first-order lag of the yaw"),
           Parameter("gyro_bias", "rad/s", 0.01, -bias, bias, limit=vehicle.physical_limits()["yaw_rate_bias"],
                     meaning="b: gyro bias")]
    if slope:
        out.append(Parameter("gain_slope", "s/rad", 0.2, -2.0, 2.0,
                             meaning="s: K falls by s per rad/s of |w| (a turn-rate dependence)"))
    return out


def simulate(log: DrivingLog, values: dict, segs: Segments) -> np.ndarray:
    """The gyro reading the model predicts, (S, L) on the segments' samples, each row from the
    steady state of its first input."""
    w = log.delayed_input(values["delay"])[segs.idx]
    x = values["yaw_gain"] * (1.0 - values.get("gain_slope", 0.0) * np.abs(w)) * w
    T, h = values["lag"], log.h
    if T > 1e-6:
        a = math.exp(-h / T)
        c = 1.0 - T / h * (1.0 - a)            # first-order hold: the lag's exact step, as driving.YawModel
        y, _ = lfilter([c, 1.0 - a - c], [1.0, -a], x, axis=1, zi=x[:, :1] * (1.0 - c))
    else:
        y = x
    return log.as_measured(y) + values.get("gyro_bias", 0.0)


class SkidModel:
    """The skid-steer model as identification.driving.fit reads a model: its log and ``simulate``."""

    def __init__(self, log: DrivingLog):
        self.log = log

    def simulate(self, values: dict, segs: Segments) -> np.ndarray:
        return simulate(self.log, values, segs)

    def simulate_many(self, sets: list[dict], segs: Segments) -> list[np.ndarray]:
        return [simulate(self.log, values, segs) for values in sets]


def fit(log: DrivingLog, segs: Segments, free: list[Parameter], start: dict, fixed: dict | None = None) -> FitResult:
    """Bounded least squares of the gyro against ``simulate`` on the segments' scored samples
    (identification.driving.fit)."""
    return driving_fit(SkidModel(log), free, start, fixed or {}, segs, max_nfev=60)


def delay_start(log: DrivingLog, lo: float, hi: float) -> tuple[float, float]:
    """(tau, K): the lag of the least residual of the regression of r on w(t - tau) over a grid of
    tau in [lo, hi] (a start for the fit), and its slope."""
    best = (math.inf, 0.0, 1.0)
    for tau in np.arange(lo, hi + 1e-9, max(log.h, 0.02)):
        w = log.delayed_input(float(tau))
        A = np.c_[w, np.ones_like(w)]
        coef, *_ = np.linalg.lstsq(A, log.r, rcond=None)
        rss = float(np.sum((log.r - A @ coef) ** 2))
        if rss < best[0]:
            best = (rss, float(tau), float(coef[0]))
    return best[1], best[2]


def widened_fit(log: DrivingLog, segs: Segments, free: list[Parameter], start: dict, fixed: dict) -> FitResult:
    """The fit, refitted once with every parameter that ended on a bound short of its physical
    limit widened to that limit (estimation.Parameter.widened)."""
    result = fit(log, segs, free, start, fixed)
    wide = [p.widened(result.values[p.name]) for p in free]
    if not any(wide):
        return result
    free = [w or p for w, p in zip(wide, free)]
    return fit(log, segs, free, result.values, fixed)


def held_out(log: DrivingLog, result: FitResult, test: Segments) -> dict:
    """RMS [rad/s] and fit [%] of the model on the held-out segments."""
    y = log.r[test.idx][test.scored]
    yhat = simulate(log, result.values, test)[test.scored]
    return {"rmse": float(np.sqrt(np.mean((y - yhat) ** 2))), "fit_percent": fit_percent(y, yhat),
            "samples": int(y.size)}


def quantity(result: FitResult, p: Parameter) -> dict:
    """A fitted parameter's value, std and 95 % interval; on a bound: no interval, not concluded."""
    value, sd = result.values[p.name], result.std(p.name)
    side = result.at_bound(p)
    d = {"value": float(value), "std": float(sd), "interval": [float(x) for x in interval(value, sd)],
         "unit": p.unit, "bounds": [p.lower, p.upper], "meaning": p.meaning,
         "identifiable": side is None and math.isfinite(sd)}
    if side:
        tol = AT_BOUND * (p.upper - p.lower)
        unit = "" if p.unit == "1" else " " + p.unit
        d["note"] = (f"not concluded: ended on its {side} bound {p.lower if side == 'lower' else p.upper:g}{unit} "
                     f"(within {tol:.3g} of it, {100 * AT_BOUND:g} % of its range {p.lower:g}..{p.upper:g})"
                     + (" (no lag resolved: the yaw follows the input within a sample)" if p.name == "lag" else ""))
    elif not math.isfinite(sd):
        d["note"] = "not identifiable from this log: the residuals do not depend on it"
    return d


def _input_on_its_updates(frame, where: str, name: str, notes: list[str]):
    """The rows where the input is known: a blank (not finite) input cell between two of its updates
    is interpolated (a channel updated slower than the log's rows); rows before its first update,
    after its last, or in a silence longer than INPUT_SILENCE (the yaw's lag and delay are tenths of
    a second) are left out. A LogError naming the column when fewer than MIN_SECONDS of rows are left."""
    u = frame[name].to_numpy(float)
    t = frame["t"].to_numpy(float)
    known = np.isfinite(u)
    if known.all():
        return frame
    tk = t[known]
    keep = np.zeros(len(t), bool)
    if len(tk) >= 2:
        after = np.clip(np.searchsorted(tk, t, side="left"), 1, len(tk) - 1)
        keep = (t >= tk[0]) & (t <= tk[-1]) & (tk[after] - tk[after - 1] <= INPUT_SILENCE)
    if keep.sum() < 2 or t[keep][-1] - t[keep][0] < MIN_SECONDS:
        raise LogError(f"{where}: the turn-rate input {name} has {int(known.sum())} finite cells of {len(u)} rows: "
                       f"too few to identify against (needs {MIN_SECONDS:g} s of it updated at least every {INPUT_SILENCE:g} s); "
                       f"map a turn-rate channel that is recorded with the gyro")
    notes.append(f"{name}: {int((~known).sum())} blank cells of {len(u)} rows (a channel updated slower than the "
                 f"rows): interpolated between its updates; {int((~keep).sum())} rows outside them left out")
    return frame.loc[keep].assign(**{name: np.interp(t[keep], tk, u[known])})


def _log_of(frame, where: str, name: str, notes: list[str]) -> tuple[DrivingLog, Segments]:
    """The input and the gyro on an even clock, cut into segments (every sample: a skid-steered
    vehicle turns standing, and standing still it shows the bias); refused when the gyro turns
    against the input, or the log holds too little turning."""
    log = even_grid(_input_on_its_updates(frame, where, name, notes).assign(v=1.0), name, max_rate=25.0)
    notes += log.notes
    # of the ranks: a few bursts of a glitching gyro (runs of rows at its range's end) do not outweigh the rest
    rho = rank_correlation(log.r, log.u) if np.std(log.r) > 0 and np.std(log.u) > 0 else 0.0
    if rho < -0.3:
        raise LogError(f"{where}: the gyro yaw_rate turns against {name} (rank correlation {rho:.2f}): one of them is counted "
                       f"clockwise; both must be counter-clockwise positive (REP 103): negate one in its --signal "
                       f"(-1*/imu/data.angular_velocity.z)")
    turning = float(np.std(log.u))
    if turning < MIN_TURNING:
        raise NotEnoughDriving(f"{where}: the input {name} hardly turns (std {turning:.3g} rad/s); identification "
                               f"needs {MIN_TURNING} rad/s or more: drive turns both ways")
    segs = cut_segments(log, 0.5, SEGMENT, BURN_IN)
    seconds = segs.seconds * log.h
    if seconds < MIN_SECONDS or segs.held_out.sum() < 1 or (~segs.held_out).sum() < 2:
        raise NotEnoughDriving(f"{where}: {seconds:.1f} s of log without a clock gap in {len(segs.idx)} segment(s); "
                               f"the skid-steer identification needs {MIN_SECONDS:g} s in 3 segments (two to fit, one "
                               f"held out): record {max(MIN_SECONDS - seconds, 3 * SEGMENT - seconds, 0):.0f} s more")
    return log, segs


def _fits(log: DrivingLog, segs: Segments, vehicle: Vehicle, kind: str) -> dict:
    """The base model from the best of two lags at the regression's delay, widened where it ends on
    a bound; the model with the turn-rate dependence from it; which is kept and why."""
    fit_segs, test = segs.take(~segs.held_out), segs.take(segs.held_out)
    free = parameters(vehicle, kind)
    tau0, k0 = delay_start(log, free[1].lower, free[1].upper)
    starts = [{"yaw_gain": min(max(k0, 0.1), 2.4), "delay": tau0, "lag": lag, "gyro_bias": 0.0} for lag in (0.05, 0.5)]
    base = min((widened_fit(log, fit_segs, free, s, {}) for s in starts), key=lambda r: r.rss_total)
    free_s = list(base.free) + parameters(vehicle, kind, slope=True)[4:]
    ext = fit(log, fit_segs, free_s, {**base.values, "gain_slope": 0.0})
    out_base, out_ext = held_out(log, base, test), held_out(log, ext, test)
    dbic = ext.bic - base.bic
    slope = quantity(ext, free_s[-1])
    gain = 1.0 - out_ext["rmse"] / out_base["rmse"] if out_base["rmse"] > 0 else 0.0
    reasons = [why for bad, why in (
        (not dbic < -BIC_MARGIN, f"dBIC {dbic:.1f} (needs below -{BIC_MARGIN:g})"),
        (not gain >= GAIN_MARGIN, f"it changes the held-out RMS by {-100 * gain:+.1f} % (needs -{100 * GAIN_MARGIN:g} % "
                                  f"or better)"),
        (not slope["identifiable"], slope.get("note", "s not identifiable")),
        (slope["interval"][0] <= 0 <= slope["interval"][1], "the 95 % interval of s holds 0")) if bad]
    kept = not reasons
    dependence = {"model": "K (1 - s |w|)", "kept": kept, "why_not": reasons, "delta_bic": dbic,
                  "held_out_gain": gain, "gain_slope": slope}
    return {"final": ext if kept else base, "held_out": out_ext if kept else out_base, "dependence": dependence,
            "fit_segs": fit_segs, "test": test}


def plausibility(params: dict, kind: str, vehicle: Vehicle) -> dict:
    """Each value against what a skid-steered vehicle of its class can have: K in PLAUSIBLE_GAIN,
    tau in PLAUSIBLE_DELAY[kind], T up to PLAUSIBLE_LAG (1 s unless the class says), |b| within the
    class's gyro bias; a value on a bound is not concluded (listed apart), and named implausible too
    when it lies outside that range (the fit went as far from it as it could)."""
    lag_hi = PLAUSIBLE_LAG.get(vehicle.kind or "", 1.0)
    bias_hi = vehicle.gyro_bias_bound or 3.0 * DEG
    ranges = {"yaw_gain": PLAUSIBLE_GAIN, "delay": PLAUSIBLE_DELAY[kind], "lag": (0.0, lag_hi),
              "gyro_bias": (-bias_hi, bias_hi)}
    why = {"yaw_gain": "the gyro turns more than the input asks: the odometry divides by an effective track already "
                       "(a wheel_separation_multiplier: K against the geometric track is K / multiplier), a wheel-speed "
                       "or gyro scale, or the input is not this vehicle's turn rate",
           "yaw_gain_low": "the gyro turns far less than the input asks, more than any skid steering slips: the input "
                           "in deg/s? (K x 57.3 = {deg:.3g}; declare its unit in its --signal: '{column}=TOPIC[deg/s]'), or the "
                           "input is not this vehicle's turn rate",
           "delay": f"not a {kind}'s delay to the yaw: a clock offset between the input's and the gyro's channels",
           "lag": "slower than a vehicle of this class turns: the input is not what drives the yaw",
           "gyro_bias": "beyond a gyro of this class: a gyro under a slope or the wrong axis"}
    findings, column = [], next(c for c, k in TURN_INPUTS.items() if k == kind)
    for name, (lo, hi) in ranges.items():
        q = params.get(name)
        if q and math.isfinite(q["value"]) and not lo <= q["value"] <= hi:
            unit = "" if q["unit"] == "1" else " " + q["unit"]
            reason = why["yaw_gain_low" if name == "yaw_gain" and q["value"] < lo else name]
            findings.append(f"{name} = {q['value']:.4g}{unit}{'' if q['identifiable'] else ' (on its bound)'} outside "
                            f"[{lo:.4g}, {hi:.4g}]{unit}: {reason.format(deg=q['value'] / DEG, column=column)}")
    return {"plausible": not findings, "findings": findings,
            "ranges": {k: [float(a), float(b)] for k, (a, b) in ranges.items()},
            "not_concluded": [f"{k}: {q['note']}" for k, q in params.items() if q.get("note")]}


def identify_skid_steer(frame, where: str, study=None, progress=None) -> dict:
    """The report (JSON-able) of the skid-steer model fitted to a log; raises LogError or
    NotEnoughDriving naming what the log lacks."""
    say = progress or (lambda text: None)
    vehicle = Vehicle.of(study)
    name, notes = turn_input(frame, where)
    kind = TURN_INPUTS[name]
    notes.insert(0, f"vehicle.drive = {vehicle.drive!r} declared: the skid-steer model" if vehicle.drive in SKID_DRIVES
                 else "no steering angle (delta, delta_cmd) in the log and a turn-rate input: the skid-steer model "
                      "(declare vehicle.drive = 'skid' or 'differential' in the study's [vehicle] table to say so)")
    notes.append("yaw measured by: gyro yaw_rate")
    log, segs = _log_of(frame, where, name, notes)
    say(f"skid-steer model: {len(segs.idx)} segments, {segs.seconds * log.h:.0f} s ({segs.held_out.sum()} held out)")
    fits = _fits(log, segs, vehicle, kind)
    final = fits["final"]
    params = {p.name: quantity(final, p) for p in final.free}
    turning = np.abs(log.u)[np.abs(log.u) > MIN_TURNING]
    return {"method": "output error, skid-steer yaw model against a turn-rate input, segments held out",
            "source": where, "model": "skid steer", "final_model": "skid_steer", "input": name, "input_kind": kind,
            "equation": EQUATION_SLOPE if fits["dependence"]["kept"] else EQUATION,
            "samples_per_second": 1 / log.h, "seconds_driven": segs.seconds * log.h,
            "segments": {"fit": int(len(fits["fit_segs"].idx)), "held_out": int(len(fits["test"].idx)),
                         "length_s": SEGMENT, "burn_in_s": BURN_IN},
            "vehicle": {"class": vehicle.kind, "drive": vehicle.drive},
            "parameters": params, "delay": params["delay"],
            "held_out_fit": {"value": fits["held_out"]["fit_percent"], "rmse": fits["held_out"]["rmse"], "unit": "%",
                             "rmse_unit": "rad/s", "samples": fits["held_out"]["samples"], "per_segment": []},
            "fit": {"n": final.n_total, "n_eff": final.n_eff_total, "bic": final.bic},
            "turn_rate_dependence": fits["dependence"],
            "turn_rate_range": {"p50": float(np.percentile(turning, 50)) if turning.size else 0.0,
                                "p95": float(np.percentile(turning, 95)) if turning.size else 0.0, "unit": "rad/s"},
            "plausibility": plausibility(params, kind, vehicle),
            "not_identifiable": [f"{k}: {q['note']}" for k, q in params.items() if q.get("note")],
            "notes": notes, "yaw_measurement": {"kind": "gyro", "text": "yaw measured by: gyro yaw_rate"},
            "_plot": None}


def summary_lines(report: dict) -> list[str]:
    """The skid-steer model's lines of ``identify``'s summary."""
    def q(d: dict, f: str = "{:.4g}") -> str:
        unit = "" if d["unit"] == "1" else " " + d["unit"]
        if not d["identifiable"]:
            return f.format(d["value"] + 0.0 if abs(d["value"]) > 1e-12 else 0.0) + unit + " (not concluded)"
        return f.format(d["value"]) + " [" + ", ".join(f.format(x) for x in d["interval"]) + "]" + unit

    p, hf, dep, pl = report["parameters"], report["held_out_fit"], report["turn_rate_dependence"], report["plausibility"]
    lines = [f"model: {report['equation']}",
             f"input w: {report['input']} ({INPUT_TEXT[report['input_kind']]}); measured r: gyro yaw_rate",
             f"K (yaw rate per input turn rate, B / B_eff): {q(p['yaw_gain'])}",
             f"delay tau: {q(p['delay'])}", f"lag T: {q(p['lag'])}",
             f"gyro bias b: {q(p['gyro_bias'])} ({math.degrees(p['gyro_bias']['value']):.3g} deg/s)"]
    if dep["kept"]:
        lines.append(f"turn-rate dependence kept: s {q(p['gain_slope'])}; dBIC {dep['delta_bic']:.0f}, held-out RMS "
                     f"-{100 * dep['held_out_gain']:.0f} %")
    else:
        lines.append(f"turn-rate dependence K (1 - s |w|) not kept (dBIC {dep['delta_bic']:.1f}): "
                     + "; ".join(dep["why_not"]))
    lines.append(f"held-out fit: {hf['value']:.1f} %, RMSE {hf['rmse']:.4g} rad/s over {hf['samples']} samples")
    lines.append("plausible for a skid-steered vehicle: " + ("yes" if pl["plausible"] else "NO: " + "; ".join(pl["findings"])))
    return lines + [f"  {x}" for x in pl["not_concluded"]]
