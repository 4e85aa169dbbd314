"""The delay at which a study's simulated guidance loop loses stability: the check of the
margins (analysis.margins) in the time domain.

Simulated check: the study run twice with the steering command delayed by d, the second time with
the tractor started OFFSET to the side (the same seed: the same noise); the loop is stable when the
two runs' cross-track errors (the tracker's error, reference - CG, across the reference's
direction) have come together: their difference (RMS) below a quarter of the offset where both
runs are on a straight in the second half
of the run (its later half; the last quarter of the run when that is under 5 s). An unstable loop
keeps them apart (its oscillation grows until a saturation, the steering's or the tracker's tanh,
bounds it), a stable one pulls both onto the reference; the difference of the two runs removes the
course's own excitation. Across, on the straights, because that is where the margins are computed,
and because on a route followed by arc length the two tractors may settle a little apart along it
(nothing pulls them back along the path; the route point also steps by its 0.1 m spacing): on a
straight that changes nothing across it, in a turn it shifts when each slows down. A fast instability (near the yaw-rate loop's
phase crossover) moves the CG little: it shows as the steering command sitting at the yaw-rate
controller's angle or rate bound on more than a tenth of its samples (a stable run touches the
rate bound at the junctions of the path only, under 3 %).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.engine import Simulation
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study

from .loop_anatomy import Anatomy

OFFSET = 0.3                  # m: the second run's tractor starts this far to the side
CONVERGED = 0.25              # stable: RMS difference of the two runs' cross-track errors at the end < CONVERGED x OFFSET
SATURATED = 0.10              # unstable: the steering command at its angle or rate bound on more of its samples

def simulate(study: Study, duration: float):
    """The study's signals over its first ``duration`` seconds (in memory)."""
    study = study.with_values({"study.stop_time": min(study.study.stop_time, study.study.start_time + duration)})
    return Simulation(build_system(resolve(study))).run().to_frame()


@dataclass
class SimulatedRun:
    delay: float
    separation: float             # RMS difference of the two runs' cross-track errors at the end (straights) [m]
    saturated: float              # share of the steering command's samples at its angle or rate bound
    wall_time: float

    @property
    def stable(self) -> bool:
        return self.separation < CONVERGED * OFFSET and self.saturated <= SATURATED

    def describe(self) -> str:
        return (f"{'stable' if self.stable else 'LOST STABILITY'} (cross-track errors of the runs started {OFFSET:g} m "
                f"apart end {self.separation:.3f} m apart; steering command at a bound {100 * self.saturated:.1f} % "
                f"of the time; {self.wall_time:.1f} s)")


def saturated_share(frame, study: Study, an: Anatomy, settle: float = 15.0) -> float:
    """Share of the steering command's samples after ``settle`` s at its angle bound or moved by
    its rate bound (98 %)."""
    if not an.command_signal or an.command_signal not in frame:
        return 0.0
    t = frame["t"].to_numpy()
    k = (t - study.study.start_time) / an.command_step
    own = np.abs(k - np.round(k)) < 1e-6
    t, u = t[own], frame[an.command_signal].to_numpy()[own]
    at_bound = (np.abs(u[1:]) >= 0.98 * an.steer_limit) | \
        (np.abs(np.diff(u)) >= 0.98 * an.steer_rate_limit * an.command_step)
    window = t[1:] > t[0] + min(settle, 0.5 * (t[-1] - t[0]))
    return float(np.mean(at_bound[window])) if window.any() else 0.0


def cross_track_error(frame, an: Anatomy) -> np.ndarray:
    """The tracker's error (reference - CG) across the reference's direction, left positive."""
    ex, ey = frame[f"{an.tracker}.error_x"].to_numpy(), frame[f"{an.tracker}.error_y"].to_numpy()
    vx, vy = frame[f"{an.reference}.xdot_ref"].to_numpy(), frame[f"{an.reference}.ydot_ref"].to_numpy()
    speed = np.hypot(vx, vy)
    return np.where(speed > 1e-6, (-vy * ex + vx * ey) / np.where(speed > 1e-6, speed, 1.0), np.hypot(ex, ey))


def simulated_run(study: Study, an: Anatomy, delay: float, duration: float, values: dict | None = None) -> SimulatedRun:
    """The study (with ``values`` set) run twice with the steering command delayed by ``delay`` [s]
    in all, the second time with the tractor started OFFSET to the side (module docstring)."""
    start = time.perf_counter()
    delayed = study.with_values({**(values or {}), an.delay_key: delay})
    a = simulate(delayed, duration)
    b = simulate(delayed.with_values({an.offset_key: an.own_offset + OFFSET}), duration)
    n = min(len(a), len(b))
    t = a["t"].to_numpy()[:n]
    gap = np.abs(cross_track_error(a, an)[:n] - cross_track_error(b, an)[:n])
    g = f"{an.reference}.yaw_rate_ref"
    straight = (np.abs(a[g].to_numpy()[:n]) < 1e-3) & (np.abs(b[g].to_numpy()[:n]) < 1e-3)
    second_half = t > t[0] + 0.5 * (t[-1] - t[0])
    on = np.flatnonzero(straight & second_half)
    if len(on) * (t[1] - t[0]) >= 5.0:
        late = np.zeros(n, bool)
        late[on[len(on) // 2:]] = True                 # the later half of the straights of the second half
    else:
        late = t >= t[0] + 0.75 * (t[-1] - t[0])
    return SimulatedRun(delay, float(np.sqrt(np.mean(gap[late] ** 2))),
                        max(saturated_share(a, delayed, an), saturated_share(b, delayed, an)), time.perf_counter() - start)


def simulated_delay_limit(study: Study, an: Anatomy, predicted: float, duration: float,
                          progress: Callable[[str], None] | None = None,
                          max_runs: int = 10) -> tuple[float, float, list[SimulatedRun]]:
    """(largest total steering delay found stable, smallest found unstable) by bisection, from a
    bracket of +-15 % of the predicted margin around the predicted limit (widened when the
    simulation disagrees) down to 2 % of the margin (at least 0.01 s); nan / inf when the bracket
    could not be closed within ``max_runs`` pairs of runs."""
    runs: list[SimulatedRun] = []
    own = an.own_delay
    margin = max(predicted - own, 0.05) if np.isfinite(predicted) else 1.0
    tolerance = max(0.01, 0.02 * margin)

    def stable(d: float) -> bool:
        r = simulated_run(study, an, d, duration)
        runs.append(r)
        if progress:
            progress(f"  run {len(runs)}: steering command delay {d:.3f} s ... {r.describe()}")
        return r.stable

    lo, hi = own + 0.85 * margin, own + 1.15 * margin
    while not stable(lo):
        hi = lo
        if lo <= own + 1e-9 or len(runs) >= max_runs:
            return math.nan, hi, runs
        lo = own + 0.7 * (lo - own) if lo - own > 0.02 else own
    while stable(hi):
        lo, hi = hi, own + 1.3 * (hi - own)
        if len(runs) >= max_runs:
            return lo, math.inf, runs
    while hi - lo > tolerance and len(runs) < max_runs:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return lo, hi, runs


