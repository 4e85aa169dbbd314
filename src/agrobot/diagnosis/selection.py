"""Several effects at once: forward selection with a joint refit, and backward
elimination, so that effects that mimic each other are separated by evidence, not by the order
in which they were tried.

The model is the baseline plus a set S of catalogue effects. Stages couple through the
effects that touch several of them (the gyro bias: yaw and position), and, where the track sees
the yaw model's side-slip (a car at highway speed: Replay.side_slip_block), through the yaw
model's values, so each trial refits the *group* of a candidate: the effects of S that share a
stage with it (transitively), their parameters, the candidate's and the stages' uncertain
parameters, scored on the group's stages.

- forward: every effect not in S is refitted jointly with its group; the supported one with the
  lowest dBIC (candidates.py: dBIC < -10, held-out gain >= min_gain, no signal worse by 5%,
  material, nothing the log shows against it: Effect.contradicts) joins S;
- backward: every other member f of S is tested by refitting its group without it; f stays only
  if the model with f is still supported against the model without it (same rules);
- a tie: when another supported candidate of the same stage came within ``TIE`` of the best's dBIC
  and is no longer supported once the best has joined, the two explain the same misfit and the
  data cannot tell which: the pair is reported as inconclusive with the experiment that would
  separate them; of two tied explanations the one with fewer parameters joins when the other is not
  supported on top of it (Selector.simplest: a side slope on a log driven along one heading is a
  steering offset's constant pull, its fall line not pinned);
- pairs: when no single candidate is supported but a stage is still above its noise floor
  (unexplained.is_misfit), pairs of effects of that stage are fitted together (a dead-band with a
  rate limit fits badly alone); a supported pair joins S;
- stop when nothing more is supported (at most ``max_effects`` steps);
- absorbed: an effect of a stage that is still misfit at the end leaves S only when the stage's
  data-driven extension, fitted without it, beats it by ``min_gain`` on the held-out part and the
  effect adds less than ``min_gain`` on top of that extension: a named effect that explains a
  residual about as well as a free map stays (Selector.absorbed).

An effect that shows on a stage only through another part of the model (Effect.tested_on: a
steering map on the steering stage, whose actuator rate is a wheel rate read through the map) is
fitted on the stages it acts on and scored on all of them; its held-out gain is the best of its
stages' (a gain error is one parameter for the turns and for the rate a second effect would name).
Such a stage is evidence for it (in dBIC and gain) only where the model without it leaves that stage
misfit and the effect's held-out RMS falls there (evidence_stages): on a steering stage the
baseline explains to its noise, a map bending the rate limit is no evidence, and an asymmetry must
not outweigh an offset the straight driving shows.

A steering gain or ratio curve read through a wheel-angle reading whose noise passes material power
into the yaw stage (a car's 0.05 deg on a quarter of a degree) is judged as on a noise-free reading
(Selector.through_noise, diagnosis.reading_noise): fitted by corrected least squares, its held-out
gain of the yaw rate's RMS net of the noise's passage, and reported so.

A steering map that lowers the yaw gain in hard turns, on a log driven into the tyres, is told from tyre
saturation only with the saturation fitted beside it (Selector.map_or_saturation); a ratio curve on a log
whose hard turns are collinear in delta and a_y (one speed, diagnosis.curve_or_saturation) is tied with it
whatever the fits say, the turns' correlation given.

Each effect of the final model is reported by its drop-one comparison: the final model against
the final model refitted without it (held-out RMS per stage with and without it).
"""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field, replace

import numpy as np

from agrobot.components.models.tyre import SHAPE_BOUNDS
from agrobot.components.models.yaw_dynamics import GRAVITY
from agrobot.orchestrator.work_progress import Work

from agrobot.estimation import REPORTED_AT_BOUND

from .baseline import replay_lateral
from .candidates import (STAGES, FitResult, Replay, _fit, class_held, class_held_note, fit_baseline, frees_scales,
                         merged, refit_free)
from .noise_floor import stage_floors
from .reading_noise import INPUT_NOISE_SHARE, held_out_gain, noise_free_fit, passage_power, reading_level
from .screen import Screen
from .simplification import healthy_levels
from .unexplained import extension, is_misfit
from .catalogue import CATALOGUE, SIGNALS
from .curve_or_saturation import COLLINEAR, Collinearity, turn_collinearity
from .effect import Effect, Parameter
from .effects.steering_offset import SPEED_KEY, WHEELBASE_KEY
from .effects.steering_ratio_curve import DELTA_KEY
from .effects.tyre_saturation import LATERAL_KEY, friction_text
from .vehicle_limits import StudyLimits
from .verdict import audit_findings

SCALES = ("gyro_scale", "speed_scale")   # a yaw gain alone: on a command-only log, the command's gain
TIE = 10.0             # dBIC difference below which two rival explanations are not told apart
STRONG = -10.0         # dBIC below which the evidence is strong
ATTENUATED = ("steering_gain", "steering_ratio_curve")    # read through the wheel angle's noise: corrected least squares


@dataclass
class Finding:
    """One effect judged against the same model without it."""

    effect: Effect
    fit: FitResult                          # the model with the effect (its group refitted)
    delta_bic: float
    gain_by_signal: dict[str, float]
    rmse_before: dict[str, float]     # held-out, without the effect
    rmse_after: dict[str, float]      # held-out, with it
    material: bool
    supported: bool
    reasons: list[str]
    stages: tuple[str, ...] = ()
    without: FitResult | None = None        # the model refitted without the effect (drop-one only)
    evidence: tuple[str, ...] = ()             # the stages counted for it (evidence_stages)

    @property
    def gain(self) -> float:
        return self.gain_by_signal[shown_signal(self.effect, self.evidence or self.stages, self.gain_by_signal)]


def main_stage(effect: Effect, scored) -> str:
    """The effect's first stage among those scored (a partial log may lack its first)."""
    return next(s for s in effect.stages if s in scored)


def shown_signal(effect: Effect, scored, gains: dict[str, float]) -> str:
    """The signal whose held-out gain judges the effect: its main stage's, or, for an effect also
    tested on stages it shows on only through the model (Effect.tested_on), the best of its scored
    stages'."""
    if not effect.tested_on:
        return SIGNALS[main_stage(effect, scored)][0]
    return max((SIGNALS[s][0] for s in effect.stages if s in scored), key=lambda k: gains[k])


def evidence_stages(effect: Effect, stages, gains: dict[str, float], without: FitResult,
                    floors: dict | None) -> tuple[str, ...]:
    """The stages that are evidence for ``effect``: all it acts on, and a stage it is only tested on
    (Effect.tested_on: a steering map on the actuator's rate, read through the map) only where the
    model without it leaves that stage misfit (above its noise floor, unexplained.is_misfit) and
    the effect's held-out RMS falls there. A stage already explained to its noise has nothing left
    for the effect to explain; a fall in its fitted RSS there is the map bending the rate limit
    (r / M'), not the map itself, and would outweigh the turns that tell a map from an offset."""
    def counts(s: str) -> bool:
        if s not in effect.tested_on:
            return True
        misfit = floors is None or is_misfit(s, without.rmse_test[s], floors)
        return misfit and gains[SIGNALS[s][0]] > 0.0
    counted = tuple(s for s in stages if counts(s))
    return counted or tuple(stages)


def _judge(effect: Effect, with_: FitResult, without: FitResult, stages, baseline_values, min_gain,
           floors: dict | None = None, unexplainable: dict[str, float] | None = None) -> Finding:
    """dBIC = sum_s n_eff,s ln(RSS_with / RSS_without) + k ln(sum n_eff); support as in candidates.py.
    ``floors``: the stages' noise floors (noise_floor.py); given, a signal whose held-out RMS rises
    counts against the effect only where it is then misfit (unexplained.is_misfit): a track left
    within its noise is no evidence against a gain that fixes the turns. ``unexplainable``: a mean
    square per stage that no model explains (the wheel-angle reading's noise passed through the yaw
    model, reading_noise.passage_power); the held-out gains are of the RMS net of it, and of the
    measurement's own noise where ``floors`` carry it (noise_floor.HeldOutNoise: a derived yaw rate's)."""
    names = {s: SIGNALS[s][0] for s in stages}
    before = {names[s]: without.rmse_test[s] for s in stages}
    after = {names[s]: with_.rmse_test[s] for s in stages}
    noise = (floors or {}).get("_held_out", {})        # the measurement's own noise (noise_floor.HeldOutNoise)
    gains = {names[s]: held_out_gain(before[names[s]], after[names[s]], (unexplainable or {}).get(s, 0.0), noise.get(s))
             for s in stages}
    counted = evidence_stages(effect, stages, gains, without, floors)
    dbic = stages_bic(with_, without, counted, len(effect.parameters))
    material = bool(effect.material(with_.values, baseline_values))
    reasons = []
    if dbic >= STRONG:
        reasons.append(f"dBIC {dbic:.1f} is not below {STRONG:.0f}")
    main = shown_signal(effect, counted, gains)
    if gains[main] < min_gain:
        reasons.append(f"held-out {main} RMS falls by {100 * gains[main]:.1f}% < {100 * min_gain:.0f}%")
    worse = [names[s] for s in stages if gains[names[s]] < -0.05
             and (floors is None or is_misfit(s, with_.rmse_test[s], floors))]
    if worse:
        reasons.append(f"held-out RMS rises for {worse}")
    if not material:
        reasons.append(f"fitted value below the materiality threshold ({effect.threshold})")
    reasons += effect.contradicts(with_.values, baseline_values)
    return Finding(effect, with_, dbic, gains, before, after, material, not reasons, reasons, tuple(stages),
                   evidence=counted)


def stages_bic(with_: FitResult, without: FitResult, stages, k: int) -> float:
    """dBIC of ``with_`` (k parameters more) against ``without`` on ``stages``:
    sum_s n_eff,s ln(RSS_s,with / RSS_s,without) + k ln(sum_s n_eff,s)."""
    n = sum(with_.n_eff[s] for s in stages)
    return sum(with_.n_eff[s] * math.log(max(with_.rss[s], 1e-300) / max(without.rss[s], 1e-300))
               for s in stages) + k * math.log(max(n, 2.0))


def turns_bic(model: FitResult, finding: Finding) -> float:
    """A finding's dBIC (stages_bic, as _judge's) on the stages its effect acts on, those it is only
    tested on left out (Effect.tested_on: a steering map on the actuator's stage)."""
    acts = [s for s in finding.evidence if s not in finding.effect.tested_on]
    return stages_bic(finding.fit, model, acts, len(finding.effect.parameters))


def held_out_text(finding: Finding) -> str:
    """A finding's held-out gains, one per signal, in %."""
    return ", ".join(f"{k} {100 * g:.1f}%" for k, g in finding.gain_by_signal.items())


def by_turns(model: FitResult, best: Finding, supported: list[Finding]) -> Finding:
    """Of supported steering-map effects (tested on the actuator's stage), the one the turns favour by
    more than TIE over ``best`` (the lowest dBIC), or by less with a larger held-out gain on every
    signal (the held-out part agreeing), else ``best``. The actuator's stage sees a map only
    through its rate read through it, r / M'(reading): a gain k there is the rate limit scaled by
    1 / k, a soft design figure (plausibility.RATE_MARGIN), whatever the map's shape; the yaw rate
    v tan(M(reading)) / L shows the shape itself (k reading, or reading (1 + c reading^2))."""
    if not best.effect.tested_on:
        return best

    def favoured(f: Finding) -> bool:
        lead = turns_bic(model, best) - turns_bic(model, f)
        shared = set(f.gain_by_signal) & set(best.gain_by_signal)
        return lead > TIE or (lead > 0 and bool(shared) and all(f.gain_by_signal[k] > best.gain_by_signal[k]
                                                                for k in shared))
    rivals = [f for f in supported if f is not best and set(f.effect.tested_on) & set(best.effect.tested_on)
              and favoured(f)]
    return min(rivals, key=lambda f: turns_bic(model, f)) if rivals else best


def group(stages: set[str], members: list[Effect], available=STAGES,
          block: tuple[str, ...] = ()) -> tuple[tuple[str, ...], list[Effect]]:
    """The stages and the members coupled to ``stages`` through shared stages (transitively),
    among the ``available`` stages (a partial log judges fewer); ``block``: stages that couple
    whole (Replay.side_slip_block: the track reads the yaw model's side-slip)."""
    stages = set(stages) & set(available)
    stages, related = set(stages), []
    changed = True
    while changed:
        changed = False
        if stages & set(block) and not set(block) <= stages:
            stages |= set(block)
            changed = True
        for f in members:
            if f not in related and stages & set(f.stages):
                related.append(f)
                stages |= set(f.stages)
                changed = True
    return tuple(s for s in STAGES if s in stages and s in available), related


def fitted_stages(effects: list[Effect], stages) -> tuple[str, ...]:
    """``stages`` but those the effects are only tested on (Effect.tested_on; none of them acting
    there directly), where they are scored, not fitted."""
    tested = {s for e in effects for s in e.tested_on} - {s for e in effects for s in e.stages if s not in e.tested_on}
    return tuple(s for s in stages if s not in tested) or tuple(stages)


def _refit(replay: Replay, values: dict, effects: list[Effect], stages, sigma, starts) -> FitResult:
    """The effects' and the stages' uncertain parameters fitted on ``stages``, but for the stages the
    effects are only tested on (Effect.tested_on; none of them acting there directly): those are
    scored, not fitted (a steering map's gain fixed by the turns, not by the actuator's rate it
    also explains); cornering scales the class does not have held unless an effect acts on the
    tyres (candidates.class_held)."""
    fit_on = fitted_stages(effects, stages)
    fit = _fit(replay, values, refit_free(replay, fit_on, effects), fit_on, starts, sigma)
    if fit_on == tuple(stages):
        return fit
    scored = _fit(replay, fit.values, [], tuple(stages), [{}], sigma)
    return replace(scored, free=fit.free, cov=fit.cov)


@dataclass
class Selection:
    base: FitResult
    sigma: dict[str, float]
    model: FitResult
    effects: list[Finding]                       # drop-one judgement of each effect of the final model
    first_step: list[Finding]                    # every catalogue effect against the baseline
    final: FitResult                                   # the final model scored on every stage
    floors: dict                                 # each stage's noise floor under it (noise_floor.py)
    inconclusive: list[dict] = field(default_factory=list)
    trace: list[str] = field(default_factory=list)


BEND_SHARE = 0.5       # a tyre's force leaves its linear one (by a few %) past about half its peak


def drives_into_tyres(replay: Replay) -> bool:
    """The log's lateral acceleration |v r| (99th percentile while moving) reaches BEND_SHARE of the
    grip the study's tyres hold (friction x g, vehicle_limits.StudyLimits): only there can tyre
    saturation bend the yaw gain as a steering map does."""
    seen, friction = replay_lateral(replay), StudyLimits.of(replay.baseline).friction
    if seen is None or not friction:
        return True
    return seen[1] >= BEND_SHARE * friction * GRAVITY


class Selector:
    def __init__(self, replay: Replay, min_gain: float = 0.05, max_effects: int = 4, seed: int = 0,
                 saturation: dict | None = None, progress=None, screen: bool = True) -> None:
        self.replay, self.min_gain, self.max_effects, self.seed = replay, min_gain, max_effects, seed
        self.screening = screen                 # the linearised screen before the pair fits (diagnosis.screen)
        self.screen: Screen | None = None
        self.progress = progress                # the tool's progress lines (orchestrator.work_progress)
        self.saturation = saturation            # identify's tyre saturation on this log (friction, shape), if kept
        self.gate_note = ""                     # why identify's kept saturation was left to the gate
        moving = replay.speed > replay.min_speed
        a_y = np.abs(np.nan_to_num(replay.speed * replay.gyro))[moving] if "yaw" in replay.stages else np.zeros(0)
        # the baseline's values, and what a materiality rule reads of the log itself
        delta = np.abs(np.nan_to_num(replay.delta))[moving] if "yaw" in replay.stages else np.zeros(0)
        speed = np.nan_to_num(replay.speed)[moving]
        self.base_values = {**replay.baseline.values, LATERAL_KEY: float(np.percentile(a_y, 99)) if len(a_y) else 0.0,
                            DELTA_KEY: float(np.percentile(delta, 99)) if len(delta) else 0.0,
                            SPEED_KEY: float(np.percentile(speed, 95)) if len(speed) else 0.0,
                            WHEELBASE_KEY: replay.baseline.tractor.l_f + replay.baseline.tractor.l_r}
        # the effects this log can judge: one of the stages they act on replayed (not only one they are
        # tested on: a steering map without the turns is a rate limit), the columns they read there
        self.catalogue = [e for e in (restaged(x.for_log(self.base_values), replay) for x in CATALOGUE)
                          if (set(e.stages) - set(e.tested_on)) & set(replay.stages)
                          and all(c in replay.frame for c in e.needs) and e.applies(replay)]
        if getattr(replay, "command_only", False) and not {"position", "speed"} & set(replay.stages):
            # judged on the yaw rate alone, a sensor's scale is the command's unknown gain: not told apart
            self.catalogue = [e for e in self.catalogue if e.id not in SCALES]
        self._cache: dict[tuple, Finding] = {}
        self._first: dict[str, dict[str, float]] = {}
        self._evaluated: tuple | None = None
        self.widened: list[str] = []
        self.floors: dict | None = None
        self._reading_noise: float | None = None     # the wheel-angle reading's noise level (reading_noise)
        self.noisy_reading = False                   # a gain read through it was corrected (through_noise)
        self.least_squares: dict[str, list] = {}     # its least-squares values and deviations, by effect
        self.work = Work(None, "", 0)

    def add(self, model: FitResult, members: list[Effect], effect: Effect) -> Finding:
        """The model with ``effect`` joined to its group, judged against ``model``."""
        stages, related = group(set(effect.stages), members, self.replay.stages, self.replay.side_slip_block)
        # reused only from the same model: a group's stages read the rest of it (the track reads the yaw
        # model's side-slip, so a lever arm fitted before the tyres were refitted takes up their error)
        key = (effect.id, tuple(sorted(f.id for f in related)), tuple(sorted(model.values.items())))
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        self.work.step()
        if effect.id in self._first:
            starts = [self._first[effect.id]]
        else:
            starts = [{p.name: x for p, x in zip(effect.parameters, start)} for start in effect.starts]
        fit = _refit(self.replay, model.values, related + [effect], stages, self.sigma, starts)
        wider = widened(effect, fit.values)
        if wider is not None:           # no verdict on a prior's edge: refit on the range widened to the limit
            self.catalogue = [wider if e is effect else e for e in self.catalogue]
            self.widened.append(f"{effect.id}: " + ", ".join(
                f"{p.name} ended on {fit.values[p.name]:.4g} {p.unit}, searched again in [{w.lower:.4g}, {w.upper:.4g}]"
                for p, w in zip(effect.parameters, wider.parameters) if (p.lower, p.upper) != (w.lower, w.upper)))
            effect = wider
            fit = _refit(self.replay, model.values, related + [effect], stages, self.sigma,
                         [{p.name: fit.values[p.name] for p in effect.parameters}])
        fit, unexplainable = self.through_noise(effect, fit, related, stages)
        finding = _judge(effect, fit, model, stages, self.base_values, self.min_gain, self.floors, unexplainable)
        self._cache[key] = finding
        if effect.id not in self._first:
            self._first[effect.id] = {p.name: fit.values[p.name] for p in effect.parameters}
        return finding

    def drop(self, model: FitResult, members: list[Effect], effect: Effect) -> Finding:
        """``model`` judged against itself refitted without ``effect`` (a member)."""
        others = [f for f in members if f is not effect]
        stages, related = group(set(effect.stages), others, self.replay.stages, self.replay.side_slip_block)
        reset = {p.name: self.base_values[p.name] for p in effect.parameters}
        if frees_scales(effect):        # the cornering scales it freed, held again without it (class_held)
            reset.update(class_held(self.replay, related))
        without = _refit(self.replay, {**model.values, **reset}, related, stages, self.sigma, [{}])
        unexplainable = {"yaw": passage_power(self.replay, model.values, self.reading_noise)} \
            if effect.id in ATTENUATED and self.noisy_reading else None
        finding = _judge(effect, model, without, stages, self.base_values, self.min_gain, self.floors, unexplainable)
        finding.without = merged(model, without, reset)      # the model to fall back to
        return finding

    def run(self) -> Selection:
        """The selection, its candidate fits counted on the progress lines."""
        with Work(self.progress, "fitting the candidate effects", len(self.catalogue), "fits") as self.work:
            return self._select()

    def _select(self) -> Selection:
        base, self.sigma = fit_baseline(self.replay)
        self.screen = Screen(self.replay, self.sigma, STRONG) if self.screening else None
        self.floors = self.evaluate(base)[1]         # the noise floors a rising signal is judged against
        trace_gate = self.saturation_gate(base)
        notes = [x for x in (self.replay.side_slip_note(), trace_gate, self.audit_start(), class_held_note(self.replay)) if x]
        model, members, trace, inconclusive = base, [], notes, []
        first = [self.add(base, [], e) for e in self.catalogue]
        first.sort(key=lambda f: (not f.supported, f.delta_bic))
        removed: set[str] = set()
        for _ in range(self.max_effects):
            if members:
                self.work.more(len(self.catalogue) - len(members))
            trials = first if not members else [self.add(model, members, e) for e in self.catalogue if e not in members]
            # the recording before the vehicle: a supported recording effect (a position reference
            # with its clock) joins before the vehicle effects it can imitate
            supported = sorted((f for f in trials if f.supported and f.effect.id not in removed),
                               key=lambda f: (not getattr(f.effect, "recording", False), f.delta_bic))
            if not supported:
                pair = self.pair(model, members, removed)
                if pair is None:
                    break
                a, b, fit, dbic = pair
                members = members + [a, b]
                model = merged(model, fit)
                trace.append(f"+ {a.id} and {b.id} together (neither alone is supported; dBIC {dbic:.1f})")
                model, members = self.still_supported(model, members, members[:-2], removed, trace)
                continue
            best = supported[0]
            turns = by_turns(model, best, supported)
            if turns is not best:
                trace.append(f"= {turns.effect.id} before {best.effect.id}: the turns tell them apart (dBIC there "
                             f"{turns_bic(model, turns):.1f} against {turns_bic(model, best):.1f}, held-out gains "
                             f"{held_out_text(turns)} against {held_out_text(best)}); "
                             f"{best.effect.id} leads only on the stages it is tested on")
                best = turns
            rivals = [f for f in supported if f is not best and f.delta_bic - best.delta_bic < TIE
                      and set(f.effect.stages) & set(best.effect.stages)]
            simpler = self.simplest(model, members, best, rivals)
            if simpler is not best:
                trace.append(f"= {simpler.effect.id} before {best.effect.id}: tied (dBIC {simpler.delta_bic:.1f} "
                             f"against {best.delta_bic:.1f}), and {best.effect.id}'s further parameters add nothing "
                             f"on top of it")
                best = simpler
                rivals = [f for f in supported if f is not best and abs(f.delta_bic - best.delta_bic) < TIE
                          and set(f.effect.stages) & set(best.effect.stages)]
            # a rival that is not supported itself (dBIC not strong, or immaterial) but within TIE of
            # the best and with evidence for it: the log cannot tell the two apart
            near = [f for f in trials if f not in supported and f.effect is not best.effect and f.delta_bic < 0
                    and 0.0 <= f.delta_bic - best.delta_bic < TIE and set(f.effect.stages) & set(best.effect.stages)
                    and f.effect.id not in removed]
            for rival in near:
                inconclusive.append(_tie(best, rival, "it is not supported on its own (" + "; ".join(rival.reasons)
                                         + ") but its evidence is within the margin of the chosen one's"))
            members = members + [best.effect]
            model = merged(model, best.fit)
            trace.append(f"+ {best.effect.id} (dBIC {best.delta_bic:.1f})")
            for rival in rivals:
                again = self.add(model, members, rival.effect)
                if not again.supported:
                    inconclusive.append(_tie(best, rival, "both are supported alone, and with the chosen one in the "
                                                          "model the other adds nothing"))
            model, members = self.still_supported(model, members, members[:-1], removed, trace)
        model, members = self.absorbed(model, members, trace)
        inconclusive += self.map_or_saturation(model, members, first)
        seen, ties = set(), []
        for t in inconclusive:                       # one entry per pair, the chosen effect still in the model
            key = tuple(t["effects"])
            if key not in seen and t["effects"][0] in {m.id for m in members}:
                seen.add(key)
                ties.append(t)
        inconclusive = ties
        effects = [self.drop(model, members, f) for f in members]
        effects.sort(key=lambda f: f.delta_bic)
        final, floors = self.evaluate(model)
        effects = [self.read_through_noise(f, members, trace) for f in effects]
        trace += [f"widened {w}" for w in self.widened]
        trace += self.screen.lines() if self.screen else ["screen: off (--no-screen): every pair of a misfit stage fitted"]
        return Selection(base, self.sigma, model, effects, first, final, floors, inconclusive, trace)

    def map_or_saturation(self, model: FitResult, members: list[Effect], first: list[Finding]) -> list[dict]:
        """The steering maps of the model, where one lowers the yaw gain in the log's tight turns (a
        ratio curve c < 0, a gain k < 1), against tyre saturation, where the log drives into it (tried, with
        evidence of its own: dBIC < 0): both bend the yaw gain down in hard turns, the map's with
        delta, the saturation's with a_y. The map is told apart only where it stays supported with the
        saturation fitted beside it and the tyre's shape off its bound (on it the tyre curve cannot
        follow the bend, and the map may hold the rest of it); otherwise a tie, "cannot decide", both
        named, however far apart their dBIC. Saturation never raises the gain: a map that does is kept.
        A ratio curve on a log whose hard turns are collinear in delta and a_y (one speed:
        curve_or_saturation.turn_collinearity) is tied whatever the fits say, saturation tried with
        evidence or not: there a bend with delta is a bend with a_y."""
        by_id = {f.effect.id: f for f in first}
        sat = by_id.get("tyre_saturation")
        if sat is None or not drives_into_tyres(self.replay):
            return []
        maps = [m for m in members if m.id in ATTENUATED and m.id in by_id]
        if not any(self.lowers(m.id, model.values) for m in maps):
            return []
        turns = turn_collinearity(self.replay)
        collinear = turns is not None and turns.collinear and self.lowers("steering_ratio_curve", model.values) \
            and any(m.id == "steering_ratio_curve" for m in maps)
        if sat.delta_bic >= 0:       # no evidence of its own: only the collinear curve is tied with it
            if not collinear:
                return []
            maps = [m for m in maps if m.id == "steering_ratio_curve"]
        tyre = next((m for m in members if m.id == "tyre_saturation"), None)
        if tyre is None:             # the saturation fitted beside the maps
            tyre, joint = sat.effect, merged(model, self.add(model, members, sat.effect).fit)
            members = members + [tyre]
        else:
            joint = model
        shape = next(p for p in tyre.parameters if p.name == "tyre_shape")
        edge = shape.at_bound(joint.values["tyre_shape"], REPORTED_AT_BOUND)
        ties = []
        for effect in maps:          # a gain above 1 beside a falling curve: the small turns' part of the same bend
            kept = self.drop(joint, members, effect)
            one_curve = collinear and effect.id == "steering_ratio_curve"
            if kept.supported and not edge and not one_curve:
                continue
            ties.append({**_tie(by_id[effect.id], sat, ""), "undecided": True,
                         "why": "both lower the yaw gain in the hard turns (the map with delta, the saturation with "
                                "a_y) and this log does not tell them apart: "
                                + bend_reason(kept, edge, turns if effect.id == "steering_ratio_curve" else None)})
        return ties

    @staticmethod
    def lowers(effect_id: str, v: dict[str, float]) -> bool:
        """The map turns the wheels less than the reading in tight turns (c < 0), or everywhere (k < 1)."""
        return v["steering_ratio_curvature"] < 0 if effect_id == "steering_ratio_curve" else v["steering_gain"] < 1.0

    def through_noise(self, effect: Effect, fit: FitResult, related: list[Effect], stages,
                      trace: list[str] | None = None) -> tuple[FitResult, dict[str, float] | None]:
        """(``fit``, None), or for a gain or a ratio curve read through the wheel-angle reading (ATTENUATED) whose noise
        passes material power into the yaw stage (diagnosis.reading_noise: errors in variables
        attenuate it) the fit refitted by corrected least squares and scored on ``stages``, with the
        held-out mean square of the noise's passage (what no model explains); said in ``trace``."""
        replay = self.replay
        if effect.id not in ATTENUATED or getattr(replay, "command_only", False) \
                or replay.__dict__.get("collecting") is not None:      # no reading; a fit only noted
            return fit, None
        fit_on = fitted_stages(related + [effect], stages)
        out = noise_free_fit(replay, fit.values, refit_free(replay, fit_on, related + [effect]), fit_on, self.sigma,
                             self.reading_noise)
        if out is None:
            return fit, None
        part, share, how = out
        self.noisy_reading = True
        scored = _fit(replay, part.values, [], tuple(stages), [{}], self.sigma)
        corrected = fit.merged(replace(scored, free=part.free, cov=part.cov))
        if trace is None:       # a candidate's fit: its least-squares values kept for the final model's line
            self.least_squares[effect.id] = [(p.name, fit.values[p.name], fit.std(p.name)) for p in effect.parameters]
        else:
            trace.append(f"{effect.id}: the wheel-angle reading's noise ({math.degrees(self.reading_noise):.2g} deg) "
                         f"passed through the yaw model is {100 * share:.0f} % of the yaw stage's residual power "
                         f"(>= {100 * INPUT_NOISE_SHARE:.0f} %): it attenuates a map read through it (errors in "
                         f"variables), judged and reported by {how}: " + ", ".join(
                             f"{name} {corrected.values[name]:.4g} +- {corrected.std(name):.2g} (least squares "
                             f"{value:.4g} +- {sd:.2g})" for name, value, sd in self.least_squares.get(effect.id, [])))
        return corrected, {"yaw": passage_power(replay, corrected.values, self.reading_noise)}

    def read_through_noise(self, finding: Finding, members: list[Effect], trace: list[str]) -> Finding:
        """The final model's ``finding`` with its gain corrected as ``through_noise`` (a later refit of
        its group with another effect reads it by least squares again)."""
        others = [f for f in members if f is not finding.effect]
        stages, related = group(set(finding.effect.stages), others, self.replay.stages, self.replay.side_slip_block)
        fit, _ = self.through_noise(finding.effect, finding.fit, related, stages, trace)
        return finding if fit is finding.fit else replace(finding, fit=fit)

    @property
    def reading_noise(self) -> float:
        """sigma_n of the wheel-angle reading (reading_noise.reading_level, under the baseline's floors)."""
        if self._reading_noise is None:
            self._reading_noise = reading_level(self.replay, (self.floors or {}).get("_sensors"))
        return self._reading_noise

    def simplest(self, model: FitResult, members: list[Effect], best: Finding, rivals: list[Finding]) -> Finding:
        """Of two tied explanations (dBIC within TIE), the one with fewer parameters, when the other is not
        supported on top of it: its further parameters are what the log does not pin (a side slope's fall line
        on a log driven along one heading is a steering offset's constant pull, told apart only by the
        heading changing). A recording effect chosen first (the position's point and clock) stays."""
        if getattr(best.effect, "recording", False):
            return best
        for rival in sorted(rivals, key=lambda f: f.delta_bic):
            if len(rival.effect.parameters) >= len(best.effect.parameters):
                continue
            on_top = self.add(merged(model, rival.fit), members + [rival.effect], best.effect)
            if not on_top.supported:
                return rival
        return best

    def still_supported(self, model: FitResult, members: list[Effect], earlier: list[Effect], removed: set[str],
                        trace: list[str]) -> tuple[FitResult, list[Effect]]:
        """(model, members) less each of the ``earlier`` members that the model with the ones added
        since no longer supports (its drop-one test, with the others)."""
        for f in list(earlier):
            check = self.drop(model, members, f)
            if not check.supported:
                members = [m for m in members if m is not f]
                model = check.without
                removed.add(f.id)
                trace.append(f"- {f.id} (with the others: dBIC {check.delta_bic:.1f}; {'; '.join(check.reasons)})")
        return model, members

    def audit_start(self) -> str | None:
        """The import audit's unresolved finding that the yaw rate answers the steering before it
        (response_leads_input) is a candidate like any effect: steering_clock starts from its lead."""
        lead = next((f for f in audit_findings(self.replay.frame.attrs)
                     if f["kind"] == "response_leads_input" and not f["resolved"]), None)
        effect = next((e for e in self.catalogue if e.id == "steering_clock"), None)
        if lead is None or effect is None or not isinstance(lead.get("value"), (int, float)):
            return None
        (p,) = effect.parameters
        start = min(max(float(lead["value"]), p.lower), p.upper - 1e-6 * (p.upper - p.lower))
        self._first["steering_clock"] = {"steering_clock": start}
        return (f"steering_clock started at {start:.3f} s: the import audit finds the yaw rate answering the steering "
                f"{lead['value']:.3f} s before it (response_leads_input, unresolved)")

    def saturation_gate(self, base: FitResult) -> str | None:
        """Tyre saturation is tried only where the linear model's misfit grows with |a_y|: in the
        top tenth of |a_y| the baseline's yaw residual, signed by the turn, falls below zero (the
        vehicle turns less than the linear tyre lets it) by more than 3 standard errors and 5 % of
        the predicted yaw rate there (with the split "blocks", below the middle band's level).
        Otherwise it is left out (and the trace says why). Tyre saturation identify keeps on the
        evidence of all its held-out segments is tried whatever this says (identify_keeps)."""
        effect = next((e for e in self.catalogue if e.id == "tyre_saturation"), None)
        if effect is None:
            return None
        kept = self.identify_keeps()
        if kept is not None:
            return kept
        replay = self.replay
        keep = replay.scored("yaw")
        predicted = replay.predicted("yaw", base.values)[keep]
        res = replay.gyro[keep] - predicted
        a_y = np.abs(replay.speed[keep] * replay.gyro[keep])
        top = a_y >= np.percentile(a_y, 90)
        signed = (res * np.sign(predicted))[top]
        n_eff = max(2.0, len(signed) * base.n_eff.get("yaw", len(res)) / max(base.n.get("yaw", len(res)), 1))
        mean, se = float(signed.mean()), float(signed.std() / math.sqrt(n_eff))
        shortfall = -mean / max(float(np.mean(np.abs(predicted[top]))), 1e-9)
        than = ""
        if replay.split == "blocks":
            # the baseline was fitted over the hard driving too: its linear compromise leaves no mean
            # shortfall at the top but an excess in the middle; the shortfall is taken against the
            # middle band (20-80 % of |a_y|) instead
            mid = (a_y >= np.percentile(a_y, 20)) & (a_y <= np.percentile(a_y, 80))
            level = float(np.mean((res * np.sign(predicted))[mid])) / max(float(np.mean(np.abs(predicted[mid]))), 1e-9)
            mean -= level * float(np.mean(np.abs(predicted[top])))
            shortfall += level
            than = f" against the middle band of |a_y| (where it is {100 * level:+.0f} % of the predicted yaw rate)"
        text = (f"where |a_y| > {np.percentile(a_y, 90):.3g} m/s2 the baseline's yaw residual signed by the turn "
                f"is {mean:+.3g} rad/s{than} (t = {mean / se if se > 0 else 0.0:.1f}, {100 * shortfall:.0f} % of the "
                f"predicted yaw rate)")
        if self.gate_note:
            text += f" ({self.gate_note})"
        if se > 0 and mean / se < -3.0 and shortfall > 0.05:
            return f"tyre_saturation tried: {text}"
        self.catalogue = [e for e in self.catalogue if e is not effect]
        return f"tyre_saturation not tried: {text}; saturation needs the vehicle to turn less than the linear model there"

    def identify_keeps(self) -> str | None:
        """One vehicle model: tyre saturation that identify keeps on this log is a candidate here,
        started from identify's tyre (an "at least" friction from its bound), when it wins there on
        the evidence of all identify's held-out segments (held-out gain >= ``min_gain``); kept on its
        hardest third alone (the rest no better or worse), it is left to the gate (None)."""
        if not self.saturation:
            return None
        gain = self.saturation.get("held_out_gain", 0.0)
        said = f"friction {friction_text(self.saturation)}, held-out gain {100 * gain:.1f} %"
        if gain < self.min_gain:
            self.gate_note = (f"identify keeps tyre_saturation ({said} < {100 * self.min_gain:.0f} % over all its "
                              f"held-out segments: it wins only in the hardest turns), so this log's own gate decides")
            return None
        self._first["tyre_saturation"] = {"tyre_friction": self.saturation["friction"],
                                          "tyre_shape": min(max(self.saturation["shape"], SHAPE_BOUNDS[0]),
                                                             SHAPE_BOUNDS[1])}
        return f"tyre_saturation tried: identify keeps it on this log ({said})"

    def evaluate(self, model: FitResult) -> tuple[FitResult, dict]:
        """``model`` scored on every stage, and the stages' noise floors under it (memoised on the
        values: the end of the selection and the report ask for the same model)."""
        key = tuple(sorted(model.values.items()))
        if self._evaluated is None or self._evaluated[0] != key:
            final = _fit(self.replay, model.values, [], self.replay.stages, [{}], self.sigma)
            floors = stage_floors(self.replay, model.values, seed=self.seed)
            floors["_healthy"] = healthy_levels(self.replay, model.values, floors, seed=self.seed)
            self._evaluated = (key, final, floors)
        return self._evaluated[1], self._evaluated[2]

    def misfit_stages(self, model: FitResult) -> list[str]:
        final, floors = self.evaluate(model)
        return [s for s in self.replay.stages if is_misfit(s, final.rmse_test[s], floors)]

    def pair(self, model: FitResult, members: list[Effect], removed: set[str]):
        """Two effects of one misfit stage that only explain it together (a dead-band with a rate
        limit: each alone fits badly). (a, b, fit, dBIC) of the best supported pair, or None."""
        misfit = self.misfit_stages(model)
        # (a nonlinear effect is not paired: its replay is costly and a pair is for two small
        # steering nonlinearities that only fit together)
        pool = [e for e in self.catalogue if e not in members and e.id not in removed and set(e.stages) & set(misfit)
                and e.id != "tyre_saturation"]
        best = None
        for i, a in enumerate(pool):
            for b in pool[i + 1:]:
                if not set(a.stages) & set(b.stages):
                    continue
                stages, related = group(set(a.stages) | set(b.stages), members, self.replay.stages,
                                        self.replay.side_slip_block)
                if self.screen and not self.screen.pair(model.values, related, a, b, stages, pool):
                    continue
                starts = [{**self._first.get(a.id, {}), **self._first.get(b.id, {})}]
                fit = _refit(self.replay, model.values, related + [a, b], stages, self.sigma, starts)
                ja = _judge(a, fit, model, stages, self.base_values, self.min_gain)
                jb = _judge(b, fit, model, stages, self.base_values, self.min_gain)
                dbic = ja.delta_bic + len(b.parameters) * math.log(max(sum(fit.n_eff[s] for s in stages), 2.0))
                ok = dbic < STRONG and ja.material and jb.material and max(ja.gain, jb.gain) >= self.min_gain \
                    and not any(g < -0.05 for g in ja.gain_by_signal.values())
                if ok and (best is None or dbic < best[3]):
                    best = (a, b, fit, dbic)
        return best

    def absorbed(self, model: FitResult, members: list[Effect], trace: list[str]) -> tuple[FitResult, list[Effect]]:
        """Parsimony that favours a named effect. An effect in a stage that
        stays misfit may only have soaked up part of a misfit it does not explain; it is tested
        against the stage's data-driven extension E (kind and signal chosen with the effect), on
        the held-out part:

        - named: the model with the effect, no extension;
        - data-driven: the model refitted without the effect, plus E;
        - on top: the effect's gain when E is fitted on both sides.

        The effect leaves only when the data-driven model beats the named one by ``min_gain``
        *and* the effect adds less than ``min_gain`` on top of E: a named effect that explains the
        residual about as well as a free map stays (it is what a user can act on)."""
        misfit = set(self.misfit_stages(model))
        for f in list(members):
            if not misfit & set(f.stages):
                continue
            check = self.drop(model, members, f)
            on_top, versus = {}, {}
            for stage in check.stages:
                if stage in misfit:
                    best = extension(self.replay, stage, model.values)
                    with_ = best["rms_after"]
                    free = extension(self.replay, stage, check.without.values, like=best)["rms_after"]
                    named = model.rmse_test[stage]
                else:
                    with_ = named = model.rmse_test[stage]
                    free = check.without.rmse_test[stage]
                on_top[stage] = 1.0 - with_ / free if free > 0 else 0.0
                versus[stage] = 1.0 - free / named if named > 0 else 0.0
            text = ", ".join(f"{100 * on_top[s]:.1f}% on top, the free map {100 * versus[s]:+.1f}% against it ({s})"
                             for s in on_top)
            if max(on_top.values()) < self.min_gain and max(versus.values()) >= self.min_gain:
                members = [m for m in members if m is not f]
                model = check.without
                trace.append(f"- {f.id}: the data-driven extension without it does better on the held-out part and "
                             f"it adds nothing on top ({text}; < {100 * self.min_gain:.0f}%)")
            else:
                trace.append(f"= {f.id} stays: {text}")
        return model, members


def bend_reason(kept: Finding, edge: str | None, turns: Collinearity | None) -> str:
    """Why a map lowering the yaw gain is not told from tyre saturation: the turns collinear in delta and
    a_y (``turns``, curve_or_saturation), the tyre's shape on its ``edge``, or the map not supported beside
    the saturation (``kept``: its drop-one test); a curve's reason states the turns' correlation."""
    if turns is not None and turns.collinear:
        return (f"its hard turns are collinear in delta and a_y ({turns.text()}; >= {COLLINEAR:g}): a bend with "
                f"delta is then a bend with a_y, and no fit tells a ratio curve from a tyre curve; turns at one "
                f"angle driven at two or more speeds would")
    why = (f"with the saturation fitted beside it its shape ends on its {edge} bound (the tyre curve cannot "
           f"follow the bend; the map may hold the rest of it)" if edge else
           "with the saturation fitted beside it the map is not supported (" + "; ".join(kept.reasons) + ")")
    if turns is not None:
        why += (f"; its turns are not collinear ({turns.text()} < {COLLINEAR:g}): the tie is the joint fit's (the "
                f"tyre curve's form fitted against the map's), not the driving's")
    return why


def restaged(effect: Effect, replay: Replay) -> Effect:
    """The effect as this log and this vehicle judge it: on a log with only the steering command,
    a steering effect is judged in the yaw stage (the replayed steering drives the yaw model); its
    parameters are searched within what the study's [vehicle] allows (vehicle_bounds)."""
    if getattr(replay, "command_only", False) and "steering" in effect.stages:
        effect = copy.copy(effect)
        effect.stages = tuple(dict.fromkeys("yaw" if s == "steering" else s for s in effect.stages))
    bounds = vehicle_bounds(replay.baseline.vehicle)
    limits = replay.baseline.vehicle.physical_limits()
    if any(p.name in bounds for p in effect.parameters):
        effect = copy.copy(effect)
        effect.parameters = tuple(_bounded(p, bounds[p.name], limits.get(p.name)) if p.name in bounds else p
                                  for p in effect.parameters)
    return effect


def _bounded(p: Parameter, prior: tuple[float, float], limit: tuple[float, float] | None) -> Parameter:
    """``p`` searched first within the vehicle's ``prior`` range, widened at most to ``limit`` (the
    class's physical limit; else the effect's own)."""
    lo, hi = limit or p.limit or (p.lower, p.upper)
    return replace(p, lower=prior[0], upper=prior[1], limit=(min(lo, prior[0]), max(hi, prior[1])))


def widened(effect: Effect, values: dict[str, float]) -> Effect | None:
    """The effect with the range of each parameter that ended on a prior bound widened to its
    physical limit (Parameter.widened), or None when none can widen."""
    params, moved = [], False
    for p in effect.parameters:
        w = p.widened(values[p.name])
        moved |= w is not None
        params.append(w or p)
    if not moved:
        return None
    effect = copy.copy(effect)
    effect.parameters = tuple(params)
    return effect


def vehicle_bounds(vehicle) -> dict[str, tuple[float, float]]:
    """Search ranges from the vehicle's class and outline (none when the study does not say):
    a gyro bias a gyro of its class can have, a slope its roads or fields can have (as the lateral
    pull g sin(phi)), an antenna inside its outline."""
    out = {}
    if vehicle.gyro_bias_bound:
        out["yaw_rate_bias"] = (-vehicle.gyro_bias_bound, vehicle.gyro_bias_bound)
    if vehicle.slope_bound:
        pull = GRAVITY * math.sin(vehicle.slope_bound)
        out["slope_east"] = out["slope_north"] = (-pull, pull)
    if vehicle.kind:
        out["tyre_friction"] = vehicle.friction_range
    arm = vehicle.lever_arm_bounds()
    if arm:
        out["antenna_forward"], out["antenna_left"] = arm
    return out


def _tie(best: Finding, rival: Finding, why: str) -> dict:
    margin = rival.delta_bic - best.delta_bic
    fewer = "; the one with fewer parameters chosen" if margin < 0 else ""
    return {"effects": [best.effect.id, rival.effect.id],
            "delta_bic": [best.delta_bic, rival.delta_bic],
            "margin": margin,
            "why": f"{rival.effect.id} is within {abs(margin):.1f} of {best.effect.id}'s dBIC (a tie below {TIE:g}): "
                   f"{why}{fewer}",
            "chosen": best.effect.id,
            "experiment": f"to tell {best.effect.id} from {rival.effect.id}: {best.effect.experiment}; "
                          f"{rival.effect.experiment}"}


def select(replay: Replay, min_gain: float = 0.05, seed: int = 0, saturation: dict | None = None,
           progress=None) -> Selection:
    """``seed``: the study's, for the Monte Carlo of the position noise floor; ``saturation``:
    identify's tyre saturation on the same log (then a candidate whatever the gate says); ``progress``:
    the tool's progress callable (the candidate fits counted, orchestrator.work_progress)."""
    return Selector(replay, min_gain, seed=seed, saturation=saturation, progress=progress).run()
