"""Tracker gains from the study's plant (its yaw model, possibly an identified one) that meet
margin targets, checked in simulation (``tune STUDY``).

Design rule (loop shaping by search): among the tracker's gains on a grid refined by a pattern
search (each tracker's own parameters, ``tunable``), keep those whose whole loop (opened at the steering command, analysis.margins)
has at every operating point of the reference a delay margin, a phase margin and a gain margin at
least the targets; take the one with the highest gain crossover (the bandwidth that keeps the
tracking error small), and among those within 5 % of it the smallest along-track error (a
time-based reference's along-track error atanh(dv / k_s) / k_c is half the Euclidean error
on the figure-8), which must stay within a budget (Targets.along_track). When no gains meet the
targets the yaw-rate controller's move weight R is raised (a calmer inner loop: its own gain
margin can be the limit) and the search repeated; the rest of the study stays as it is.

The proposal is written as a small study that ``extends`` the original (Study.extension_toml),
then simulated: its metrics against the paper's bounds and the steering command delay at which it
loses stability against the predicted one.

Imported where used: agrobot.components.kinematic_tracker (start-up: 38 ms with the two trackers next, on every
command: ``--help`` loads this module for the defaults of tune's options), agrobot.components.pure_pursuit (start-up:
the same), agrobot.components.stanley (start-up: the same), agrobot.analysis.figure8 (start-up: 29 ms, the same way).
"""
from __future__ import annotations

import itertools
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from agrobot.orchestrator.errors import InputError
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.study import Study

from agrobot.components.models.loop_blocks import NoLinearModel, OperatingPoint
from .loop_models import block_of, network_of
from .margins import Analysis, Margins, analyse, anatomy, margins_of
from .margins_simulation import simulated_delay_limit


@dataclass(frozen=True)
class Targets:
    delay: float = 0.25         # s of extra steering delay the loop must tolerate
    phase_deg: float = 45.0
    gain_db: float = 6.0
    along_track: float = 0.20   # m: a time-based reference's along-track error (half the paper's straight bound)


@dataclass(frozen=True)
class Range:
    parameter: str
    low: float
    high: float
    points: int


def tunable(cls, params: dict) -> list[Range]:
    """The gains ``tune`` searches for a tracker class (log-spaced grids)."""
    from agrobot.components.kinematic_tracker import KinematicTracker
    from agrobot.components.pure_pursuit import PurePursuit
    from agrobot.components.stanley import Stanley

    if issubclass(cls, KinematicTracker):
        return [Range("lookahead", float(params["l_r"]), 12.0, 16), Range("k_c", 0.3, 8.0, 12)]
    if issubclass(cls, PurePursuit):
        return [Range("lookahead_min", 0.5, 8.0, 14), Range("lookahead_time", 0.2, 4.0, 12)]
    if issubclass(cls, Stanley):
        return [Range("k", 0.05, 10.0, 24)]
    raise NoLinearModel(f"tune: no gains to search for a tracker of class {cls.__name__}")


@dataclass
class Design:
    values: dict[str, float]
    margins: list[Margins]            # whole loop, per operating point
    along_track: float                # the largest trim along-track error over the operating points [m]
    feasible: bool
    slack: float                      # smallest relative excess over the targets (< 0: misses one)

    @property
    def bandwidth(self) -> float:
        return min(m.crossover for m in self.margins) if all(np.isfinite(m.crossover) for m in self.margins) else 0.0


def _slack(m: Margins, t: Targets) -> float:
    values = [(m.delay - t.delay) / t.delay if t.delay > 0 else (0.0 if m.delay > 0 else -1.0),
              (m.phase_deg - t.phase_deg) / max(t.phase_deg, 1.0),
              (m.gain_db - t.gain_db) / max(t.gain_db, 1.0)]
    return min(v if np.isfinite(v) else 1.0 for v in values)


def _rounded(x: float) -> float:
    """Three significant digits: the values a person writes in a study file."""
    return float(f"{x:.3g}")


class Search:
    """The study's network per operating point, its tracker block swapped for each candidate."""

    def __init__(self, study: Study, points: list[OperatingPoint], speed_excess_value: float | None):
        self.study, self.an = study, anatomy(study, "tune")
        model = resolve(study)
        self.cls = model.component_class(self.an.tracker)
        self.params = model.parameters(self.an.tracker)
        self.step = study.components[self.an.tracker].step or study.study.base_step
        self.excess = speed_excess_value
        self.points = points
        self.networks = [network_of(study, op, "tune") for op in points]

    def evaluate(self, values: dict[str, float], targets: Targets, w_min: float = 1e-2) -> Design:
        from agrobot.components.kinematic_tracker import trim_along_track_error

        params = {**self.params, **values}
        tracker = self.cls(self.an.tracker, params)
        margins, along = [], 0.0
        for op, net in zip(self.points, self.networks):
            if self.excess is not None and op.along_track_error != 0.0:
                op = OperatingPoint(op.speed, trim_along_track_error(params, self.excess), op.label)
            along = max(along, abs(op.along_track_error))
            node = net.blocks[self.an.tracker]
            net.blocks[self.an.tracker] = block_of(tracker, self.step, node.ratio, op)
            try:
                loop = net.opened_at([self.an.steering_break])
                ok = loop.spectral_radius() < 1.0
                margins.append(margins_of(loop, w_min, 800) if ok else Margins(0.0, None, -math.inf, math.nan, 0.0, math.nan))
            finally:
                net.blocks[self.an.tracker] = node
        slack = min([_slack(m, targets) for m in margins] + [(targets.along_track - along) / targets.along_track])
        return Design(values, margins, along, slack >= 0.0, slack)


def search(study: Study, targets: Targets, points: list[OperatingPoint], speed_excess_value: float | None,
           progress: Callable[[str], None] | None = None, grid: float = 1.0) -> tuple[Design, list[Design]]:
    """The best design (module docstring) and every design evaluated: a log-spaced grid (``grid``
    scales its number of points), then a pattern search around its best (feasible: the highest
    bandwidth; none feasible yet: the largest slack), halving the step three times."""
    s = Search(study, points, speed_excess_value)
    ranges = tunable(s.cls, s.params)
    grids = [np.geomspace(r.low, r.high, max(3, int(round(r.points * grid)))) for r in ranges]
    designs: dict[tuple, Design] = {}

    def evaluate(logs) -> Design:
        values = {r.parameter: _rounded(float(np.clip(math.exp(v), r.low, r.high))) for r, v in zip(ranges, logs)}
        key = tuple(values.values())
        if key not in designs:
            designs[key] = s.evaluate(values, targets)
        return designs[key]

    def rank(d: Design) -> tuple:
        return (1, d.bandwidth) if d.feasible else (0, d.slack)

    total = int(np.prod([len(g) for g in grids]))
    for i, combo in enumerate(itertools.product(*grids)):
        evaluate([math.log(v) for v in combo])
        if progress and (i + 1) % 40 == 0:
            progress(f"  {i + 1} of {total} candidate gains evaluated")
    best = max(designs.values(), key=rank)
    at = [math.log(v) for v in best.values.values()]
    steps = [math.log(g[1] / g[0]) / 2 for g in grids]
    for _ in range(3):
        moved = True
        while moved:
            moved = False
            for i in range(len(at)):
                for sign in (-1, 1):
                    trial = list(at)
                    trial[i] += sign * steps[i]
                    d = evaluate(trial)
                    if rank(d) > rank(best):
                        best, at, moved = d, trial, True
        steps = [x / 2 for x in steps]
    feasible = [d for d in designs.values() if d.feasible]
    if not feasible:
        return best, list(designs.values())
    top = max(d.bandwidth for d in feasible)
    near = [d for d in feasible if d.bandwidth >= 0.95 * top]
    return max(near, key=lambda d: (-d.along_track, d.bandwidth)), list(designs.values())


@dataclass
class Proposal:
    study: Study                   # the tuned study
    values: dict[str, object]      # the values set (keys as in Study.with_values)
    before: Analysis
    after: Analysis
    targets: Targets
    text: str                      # the extension study file


def identified_values(study: Study, path, model: str) -> dict[str, object]:
    """The plant and the yaw-rate controller's model set to a fitted transfer function of an
    ``identify`` result (identification.json: models.NAME.num/den)."""
    path = Path(path)
    try:
        report = json.loads(path.read_text())
    except FileNotFoundError:
        raise InputError(f"--identified {path}: not found") from None
    except (OSError, ValueError) as exc:
        raise InputError(f"--identified {path}: not an identification.json ({exc})") from None
    models = report.get("models") if isinstance(report, dict) else None
    if not isinstance(models, dict) or model not in models or "num" not in models[model] or "den" not in models[model]:
        known = ", ".join(sorted(models)) if isinstance(models, dict) else "none"
        raise InputError(f"--identified {path}: no model {model!r} with num and den (models: {known})")
    resolved = resolve(study)
    plant = resolved.one(role="yaw_plant", purpose="tune --identified")
    controller = resolved.one(role="yaw_rate_controller", purpose="tune --identified")
    num, den = [float(x) for x in models[model]["num"]], [float(x) for x in models[model]["den"]]
    return {f"{plant}.model": "transfer_function", f"{plant}.tf_num": num, f"{plant}.tf_den": den,
            f"{controller}.num": num, f"{controller}.den": den}


MOVE_WEIGHT_FACTORS = (1.0, 2.0, 4.0, 8.0, 16.0)


def propose(study: Study, targets: Targets, progress: Callable[[str], None] | None = None,
            identified: dict[str, object] | None = None, grid: float = 1.0) -> Proposal:
    """Search the tracker's gains with the study's yaw-rate controller; when none meets the targets
    (the inner loop's own gain margin can be the limit), again with its move weight R raised
    (MOVE_WEIGHT_FACTORS: a calmer inner loop). Round, re-analyse; an InputError when no design
    meets the targets."""
    say = progress or (lambda line: None)
    base = study.with_values(identified) if identified else study
    before = analyse(base, progress=say)
    excess = next((r.speed_excess for r in before.points if r.speed_excess is not None), None)
    points = [r.op for r in before.points]
    an = before.anatomy
    model = resolve(base)
    controller = model.one(role="yaw_rate_controller", purpose="tune")
    R0 = float(model.parameters(controller)["R"])
    ranges = tunable(model.component_class(an.tracker), model.parameters(an.tracker))
    closest = None
    for factor in MOVE_WEIGHT_FACTORS:
        trial = base if factor == 1.0 else base.with_values({f"{controller}.R": _rounded(R0 * factor)})
        say(f"searching {' x '.join(f'{max(3, int(round(r.points * grid)))} {r.parameter}' for r in ranges)} gains of {an.tracker} "
            f"({base.components[an.tracker].type}), {controller}.R = {_rounded(R0 * factor):g}, for delay margin >= "
            f"{targets.delay:g} s, phase margin >= {targets.phase_deg:g} deg, gain margin >= {targets.gain_db:g} dB at "
            f"{', '.join(f'{p.speed:g} m/s' for p in points)} ...")
        best, _ = search(trial, targets, points, excess, say, grid)
        if closest is None or best.slack > closest[0].slack:
            closest = (best, factor)
        if best.feasible:
            break
    best, factor = closest
    if not best.feasible:
        m = min(best.margins, key=lambda x: x.delay)
        raise InputError(f"{study.where}: tune: no gains of {an.tracker} ({base.components[an.tracker].type}) on the "
                         f"searched grid (with {controller}.R up to {MOVE_WEIGHT_FACTORS[-1]:g} x {R0:g}) meet the targets; "
                         f"the closest ({_describe(best.values)}, R = {_rounded(R0 * factor):g}) reaches a delay margin "
                         f"of {m.delay:.3f} s, phase margin {m.phase_deg:.1f} deg, gain margin {m.gain_db:.1f} dB: lower "
                         f"--delay-margin / --phase-margin / --gain-margin, or reduce the steering delay")
    values: dict[str, object] = dict(identified or {})
    values.update({f"{an.tracker}.{k}": v for k, v in best.values.items()})
    if factor != 1.0:
        values[f"{controller}.R"] = _rounded(R0 * factor)
    tuned = study.with_values(values)
    after = analyse(tuned, speed_excess_value=excess, progress=say)
    comment = _comment(study, after, targets)
    return Proposal(tuned, values, before, after, targets, study.extension_toml(values, comment))


def _describe(values: dict[str, float]) -> str:
    return ", ".join(f"{k} = {v:g}" for k, v in values.items())


def _comment(study: Study, after: Analysis, targets: Targets) -> str:
    lines = [f"Tracker gains proposed by `tune` for {study.where} (targets: delay margin >= {targets.delay:g} s, "
             f"phase margin >= {targets.phase_deg:g} deg, gain margin >= {targets.gain_db:g} dB at the steering command).",
             "Predicted whole-loop margins:"]
    for r in after.points:
        m = r.loops["whole loop"]
        lines.append(f"  {r.op.speed:g} m/s ({r.op.label}): delay margin {m.delay:.3f} s, phase margin {m.phase_deg:.1f} deg, "
                     f"gain margin {m.gain_db:.1f} dB, crossover {m.crossover:.2f} rad/s")
    lines.append("Check: python -m agrobot margins THIS_FILE --simulate")
    return "\n".join(lines)


def _value(v) -> str:
    return f"{v:.4g}" if isinstance(v, (int, float)) else ("[...]" if isinstance(v, list) else str(v))


def comparison(p: Proposal) -> str:
    """Before and after: the gains set and the whole loop's margins at each operating point."""
    t = p.targets
    rows = [f"{'':<34}{'study':>12}{'proposed':>12}   target"]
    before = resolve(p.before.study)
    for key, value in p.values.items():
        name, param = key.split(".", 1)
        rows.append(f"{key:<34}{_value(before.parameters(name).get(param)):>12}{_value(value):>12}")
    for b, a in zip(p.before.points, p.after.points):
        mb, ma = b.loops["whole loop"], a.loops["whole loop"]
        rows.append(f"whole loop at {a.op.speed:g} m/s ({a.op.label}):")
        for label, x, y, goal in (("  delay margin [s]", mb.delay, ma.delay, f">= {t.delay:g}"),
                                  ("  phase margin [deg]", mb.phase_deg, ma.phase_deg, f">= {t.phase_deg:g}"),
                                  ("  gain margin [dB]", mb.gain_db, ma.gain_db, f">= {t.gain_db:g}"),
                                  ("  crossover [rad/s]", mb.crossover, ma.crossover, "(bandwidth)"),
                                  ("  delay limit (poles) [s]", b.delay_limit, a.delay_limit, "")):
            rows.append(f"{label:<34}{x:>12.3f}{y:>12.3f}   {goal}")
        if b.speed_excess is not None:
            rows.append(f"{'  along-track error [m]':<34}{b.op.along_track_error:>12.3f}{a.op.along_track_error:>12.3f}"
                        f"   <= {t.along_track:g}")
    return "\n".join(rows)


def simulated_check(p: Proposal, duration: float, progress: Callable[[str], None] | None = None) -> list[str]:
    """The proposal simulated: its metrics (the paper's bounds where the study's analysis gives the
    figure-8's) and the steering command delay at which it loses stability, against the prediction."""
    from .figure8 import PAPER_BOUNDS

    say = progress or (lambda line: None)
    study = p.study
    stop = min(study.study.stop_time, study.study.start_time + duration)
    say(f"\nsimulating the proposal ({stop - study.study.start_time:.0f} s) ...")
    metrics = run_study(study.with_values({"study.stop_time": stop}), None, plots=False).metrics
    lines = ["", f"{'simulated with the proposed gains':<40}{'value':>10}   bound"]
    bounded = [k for k in PAPER_BOUNDS if k in metrics]
    for key in bounded:
        ok = metrics[key] < PAPER_BOUNDS[key]
        lines.append(f"  {key:<38}{metrics[key]:>10.3f}   < {PAPER_BOUNDS[key]:.2f} m  {'PASS' if ok else 'FAIL'}")
    if not bounded:
        lines += [f"  {k:<38}{v:>10.4g}" for k, v in metrics.items()
                  if isinstance(v, float) and ("xte" in k or "euclid" in k)]
    an = p.after.anatomy
    predicted = p.after.points[0].delay_limit          # the reference's first operating point: where a run spends its time
    say(f"\nbisecting the steering command delay at which the proposal loses stability (predicted {predicted:.3f} s) ...")
    lo, hi, runs = simulated_delay_limit(study, an, predicted, duration, progress=say)
    lines += ["", f"{'steering command delay at which it loses stability':<52}{'predicted':>10}{'simulated':>20}",
              f"  {'(own ' + format(an.own_delay, '.3f') + ' s + delay margin)':<50}{predicted:>10.3f}"
              f"{f'{lo:.3f} .. {hi:.3f}':>20}"]
    return lines
