"""Gain, phase and delay margins of a study's guidance loop, from its own components
(analysis.loop_models), and the delay at which its simulation loses stability.

The loop is linearised on a straight at each operating point the reference declares (the figure-8:
its speed; a field route: the work and turn speeds), on the yaw plant's side slope when it has one
(analysis.loop_models: the pull turning with the heading, the tilted IMU, the INS with its learnt
crab), and opened at three places:

- the steering command (the whole loop: yaw-rate and path loops closed): its delay margin is the
  extra actuator delay the loop tolerates, the number the simulation checks;
- the steering command with the path loop held open (the yaw-rate loop alone);
- the yaw-rate command between tracker and yaw-rate controller (the path loop, the yaw-rate loop
  closed inside): the margins of the tracker's gains.

Convention: L = -G with G the return of the opened loop (z = G w), closed by w = z, so the
closed loop is stable when L's Nyquist curve leaves -1 where the Nyquist criterion says. Phase
margin = 180 deg + arg L at a gain crossover |L| = 1; delay margin = the smallest (phase margin +
2 pi k) / crossover over the crossovers; gain margin = 1 / |L| where L crosses the negative real
axis inside the unit circle (a reduction where it crosses outside). Besides the frequency response,
the delay at which the closed-loop poles leave the unit circle is found directly (the steering's
command delay raised in whole steps): a second method for the delay limit.

A time-based reference (the figure-8) leaves the tracker an along-track error that the speed loop
sets (its steady speed excess v_d - v): it is read from a short run of the study and enters the
trackers' linearisations (it raises v_d, and so the heading gain).

Imported where used: agrobot.components.kinematic_tracker (start-up: 38 ms with the two trackers analysis.tune
defers, on every command: ``--help`` loads this module through analysis.tune).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.optimize import brentq

from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study

from agrobot.components.models.loop_blocks import NoLinearModel, OperatingPoint
from .loop_models import OpenLoop, network_of, study_ground
from .loop_anatomy import Anatomy, anatomy
from .margins_simulation import simulate

TRIM_TIME = 40.0              # s of the study run to read the speed loop's steady excess
STABLE_RADIUS = 1.0 + 1e-9


@dataclass
class Margins:
    gain: float                   # gain margin (factor > 1); inf when L never crosses the real axis in (-1, 0)
    gain_reduction: float | None  # factor < 1 below which the loop is unstable (conditionally stable), or None
    phase_deg: float              # smallest phase margin over the gain crossovers; inf without one
    crossover: float              # the gain crossover [rad/s] that sets the delay margin (nan without one)
    delay: float                  # delay margin [s] (inf without a crossover)
    phase_crossover: float        # where the gain margin is read [rad/s] (nan without one)

    @property
    def gain_db(self) -> float:
        if self.gain <= 0.0:
            return -math.inf
        return 20.0 * math.log10(self.gain) if np.isfinite(self.gain) else math.inf


def _refine(f: Callable[[float], float], a: float, b: float) -> float:
    return brentq(f, a, b, xtol=1e-10, rtol=1e-10)


def margins_of(loop: OpenLoop, w_min: float = 1e-3, points: int = 3000) -> Margins:
    """Margins of L = -G from its frequency response on ``points`` frequencies up to the period's
    Nyquist frequency, each crossing refined by root finding."""
    w_max = 0.999 * math.pi / loop.dt
    w = np.logspace(math.log10(w_min), math.log10(w_max), points)
    L = -loop.response(w)

    def at(x: float) -> complex:
        return complex(-loop.response(np.array([x]))[0])

    mag = np.abs(L)
    best_pm, best_delay, wc = math.inf, math.inf, math.nan
    for i in np.flatnonzero(np.sign(mag[:-1] - 1.0) != np.sign(mag[1:] - 1.0)):
        x = _refine(lambda v: abs(at(v)) - 1.0, w[i], w[i + 1])
        lag = (np.angle(at(x)) + math.pi) % (2 * math.pi)          # 180 deg + arg L, in [0, 2 pi)
        pm = math.degrees(lag if lag <= math.pi else lag - 2 * math.pi)
        best_pm = min(best_pm, pm)
        if lag / x < best_delay:
            best_delay, wc = lag / x, x
    gain, reduction, wp = math.inf, None, math.nan
    crossings = []
    for i in np.flatnonzero(np.sign(L.imag[:-1]) != np.sign(L.imag[1:])):
        if L.real[i] >= 0 and L.real[i + 1] >= 0:
            continue
        x = _refine(lambda v: at(v).imag, w[i], w[i + 1])
        crossings.append((x, at(x).real))
    # L is real at w = 0 and at the Nyquist frequency: a loop that sits on the negative real axis
    # there (a sign-reversed static gain, a lag of 180 deg at pi/dt) crosses it without a sign change
    # (the lowest frequency of the grid stands for z = 1, a pole of the integrators)
    ends = [(0.0, L[0])]
    try:
        ends.append((math.pi / loop.dt, at(math.pi / loop.dt)))
    except np.linalg.LinAlgError:                    # a pole at z = -1: no finite crossing there
        pass
    crossings += [(x, v.real) for x, v in ends if np.isfinite(v) and abs(v.imag) <= 1e-2 * abs(v) and -1.0 < v.real < 0]
    for x, re in crossings:
        if re >= 0:
            continue
        if re > -1.0 and 1.0 / -re < gain:
            gain, wp = 1.0 / -re, x
        elif re < -1.0:
            reduction = max(reduction or 0.0, 1.0 / -re)
    return Margins(gain, reduction, best_pm, wc, best_delay, wp)


# --- analysis -------------------------------------------------------------------------------

@dataclass
class PointResult:
    op: OperatingPoint
    loops: dict[str, Margins]
    open_loops: dict[str, OpenLoop]
    stable: bool                              # the closed loop at the study's values
    delay_limit: float                        # total steering command delay at which the poles leave the unit circle [s]
    speed_excess: float | None = None         # v_d - v read from the trim run (time-based reference)


@dataclass
class Analysis:
    study: Study
    anatomy: Anatomy
    points: list[PointResult]
    notes: list[str] = field(default_factory=list)


LOOPS = {"whole loop": "steering command", "yaw-rate loop": "steering command, path held", "path loop": "yaw-rate command"}


def open_loops(study: Study, an: Anatomy, op: OperatingPoint) -> dict[str, OpenLoop]:
    net = network_of(study, op)
    return {"whole loop": net.opened_at([an.steering_break]),
            "yaw-rate loop": net.opened_at([an.steering_break], zeroed=[an.path_break]),
            "path loop": net.opened_at([an.path_break])}


def stable(study: Study, an: Anatomy, op: OperatingPoint, delay: float | None = None) -> bool:
    """The closed loop's poles inside the unit circle, with the steering command delayed by
    ``delay`` in all (None: the study's own)."""
    if delay is not None:
        study = study.with_values({an.delay_key: delay})
    return network_of(study, op).opened_at([an.steering_break]).spectral_radius() < STABLE_RADIUS


def pole_delay_limit(study: Study, an: Anatomy, op: OperatingPoint, guess: float) -> float:
    """The smallest steering command delay (whole steering steps) at which the closed loop has a pole
    outside the unit circle; inf when none up to 10 s."""
    h = an.delay_step
    lo = int(round(an.own_delay / h))
    hi = max(lo + 1, int(math.ceil(guess / h)) + 1)
    while stable(study, an, op, hi * h):
        lo, hi = hi, 2 * hi
        if hi * h > 10.0:
            return math.inf
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if stable(study, an, op, mid * h) else (lo, mid)
    return hi * h


def speed_excess(study: Study, an: Anatomy, duration: float = TRIM_TIME) -> float:
    """v_d - v on the reference after its start: the median over the last quarter of a short run
    (the speed loop's steady excess, which sets a time-based tracker's along-track error)."""
    frame = simulate(study, duration)
    t = frame["t"].to_numpy()
    v_d = frame[f"{an.tracker}.speed_desired"].to_numpy()
    v_r = frame[f"{an.reference}.speed_ref"].to_numpy() if f"{an.reference}.speed_ref" in frame else None
    if v_r is None:
        raise NoLinearModel(f"{study.where}: the reference {an.reference!r} records no speed_ref")
    window = (t >= 0.75 * t[-1]) & (v_r > 0.99 * np.max(v_r))
    return float(np.median(v_d[window] - v_r[window])) if window.any() else 0.0


def analyse(study: Study, speed_excess_value: float | None = None, progress: Callable[[str], None] | None = None) -> Analysis:
    """Margins at every operating point of the study's reference."""
    from agrobot.components.kinematic_tracker import trim_along_track_error

    an = anatomy(study)
    notes = []
    if study.sweep is not None:
        notes.append(f"this study sweeps {', '.join(study.sweep.parameters)} ({study.sweep.mode}): the margins are at "
                     f"its own values; a point's with --set NAME=VALUE")
    points = []
    model = resolve(study)
    system_reference = model.component_class(an.reference)(an.reference, model.parameters(an.reference))
    tracker_p = model.parameters(an.tracker)
    for label, spec in system_reference.operating_points().items():
        excess = None
        e = spec["along_track_error"]
        if e is None:
            if "k_s" not in tracker_p or "k_c" not in tracker_p:
                raise NoLinearModel(f"{study.where}: the margins: the reference {an.reference!r} is time based and the "
                                    f"tracker {an.tracker!r} has no speed law v_d = v_r + k_s tanh(k_c e) to place its "
                                    f"along-track error")
            if speed_excess_value is None:
                if progress:
                    progress(f"reading the speed loop's steady excess from a {TRIM_TIME:.0f} s run ...")
                speed_excess_value = speed_excess(study, an)
            excess = speed_excess_value
            e = trim_along_track_error(tracker_p, excess)
            notes.append(f"{label}: time-based reference: the speed loop leaves v_d - v = {excess:+.3f} m/s, "
                         f"an along-track error of {e:.3f} m (tracker's speed law)")
        if spec.get("turn_radius"):
            notes.append(f"{label}: linearised on a straight; its curves of {spec['turn_radius']:g} m radius are not "
                         f"(--simulate checks the course)")
        ground = study_ground(study, float(spec["speed"]))
        if model.parameters(an.offset_key.split(".")[0]).get("terrain_file"):
            notes.append(f"{label}: the yaw plant's ground is a height grid: linearised on level ground (a plane, "
                         f"slope_angle, is linearised on its slope)")
        if not ground.level:
            notes.append(f"{label}: on the yaw plant's side slope: roll {math.degrees(ground.roll):.2f} deg, pitch "
                         f"{math.degrees(ground.pitch):.2f} deg, pull across the heading {ground.pull:+.3f} m/s2 "
                         f"({ground.pull_per_heading:+.3f} m/s2/rad with the heading), IMU f_y {ground.specific_force:+.3f} "
                         f"m/s2, the crab {100 * ground.crab:+.2f} cm/s learnt by the INS (k = "
                         f"{ground.slip_compliance(float(spec['speed'])):.2e} s2/m)")
        op = OperatingPoint(float(spec["speed"]), float(e), label, ground)
        loops = open_loops(study, an, op)
        margins = {name: margins_of(loop) for name, loop in loops.items()}
        ok = loops["whole loop"].spectral_radius() < STABLE_RADIUS
        whole = margins["whole loop"]
        guess = an.own_delay + (whole.delay if np.isfinite(whole.delay) else 1.0)
        limit = pole_delay_limit(study, an, op, guess) if ok else an.own_delay
        points.append(PointResult(op, margins, loops, ok, limit, excess))
    return Analysis(study, an, points, notes)


# --- report --------------------------------------------------------------------------------

def _fmt(x: float, fmt: str, unit: str = "") -> str:
    return f"{x:{fmt}}{unit}" if np.isfinite(x) else "inf" if x == math.inf else "none"


def table(analysis: Analysis) -> str:
    an = analysis.anatomy
    lines = []
    for r in analysis.points:
        lines.append(f"\nat {r.op.speed:.2f} m/s ({r.op.label}; along-track error {r.op.along_track_error:.3f} m)"
                     + ("" if r.stable else "  -- THE CLOSED LOOP IS UNSTABLE at the study's values"))
        lines.append(f"  {'loop':<15}{'opened at':<30}{'gain margin':>18}{'phase margin':>14}{'crossover':>13}{'delay margin':>14}")
        for name, m in r.loops.items():
            gm = f"{m.gain:.2f} ({m.gain_db:.1f} dB)" if np.isfinite(m.gain) else "inf"
            if m.gain_reduction is not None:
                gm += f" / {m.gain_reduction:.2f}"
            lines.append(f"  {name:<15}{LOOPS[name]:<30}{gm:>18}{_fmt(m.phase_deg, '.1f', ' deg'):>14}"
                         f"{_fmt(m.crossover, '.2f', ' rad/s'):>13}{_fmt(m.delay, '.3f', ' s'):>14}")
        lines.append(f"  closed-loop poles leave the unit circle at a steering command delay of "
                     f"{_fmt(r.delay_limit, '.2f', ' s')} (the study's {an.own_delay:.2f} s + "
                     f"{_fmt(r.delay_limit - an.own_delay, '.2f', ' s')})")
    return "\n".join(lines)


def report(analysis: Analysis) -> str:
    an, study = analysis.anatomy, analysis.study
    head = [f"margins of {study.where}: linearised on a straight (analysis.loop_models); the tracker "
            f"{an.tracker!r} ({study.components[an.tracker].type}), the steering command into "
            f"{an.steering_break[0]}.{an.steering_break[1]}, its delay {an.delay_key}"]
    head += [f"  {n}" for n in analysis.notes]
    foot = ["", "", "gain margin: factor (dB) on the loop gain at the opening ('/ x': also unstable below a factor x);",
            "delay margin: extra delay at the opening the loop tolerates."]
    return "\n".join(head) + table(analysis) + "\n".join(foot)


def as_dict(analysis: Analysis) -> dict:
    """The analysis as JSON-ready values (inf and nan as null)."""
    def num(x):
        return float(x) if x is not None and np.isfinite(x) else None

    an = analysis.anatomy
    return {"study": str(analysis.study.where), "tracker": an.tracker, "steering_command": ".".join(an.steering_break),
            "delay_parameter": an.delay_key, "own_delay_s": an.own_delay, "notes": analysis.notes,
            "operating_points": [{
                "label": r.op.label, "speed_m_s": r.op.speed, "along_track_error_m": r.op.along_track_error,
                "speed_excess_m_s": r.speed_excess, "closed_loop_stable": r.stable,
                "delay_limit_s": num(r.delay_limit),
                "loops": {name: {"opened_at": LOOPS[name], "gain_margin": num(m.gain), "gain_margin_db": num(m.gain_db),
                                 "gain_reduction": m.gain_reduction, "phase_margin_deg": num(m.phase_deg),
                                 "crossover_rad_s": num(m.crossover), "delay_margin_s": num(m.delay),
                                 "phase_crossover_rad_s": num(m.phase_crossover)}
                          for name, m in r.loops.items()}} for r in analysis.points]}
