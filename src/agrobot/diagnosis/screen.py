"""A cheap screen before the selection's costly fits: the candidates linearised about the model,
and the best fall in the residual sum of squares that linearisation allows, against what the
selection needs of them (dBIC < STRONG, diagnosis.selection).

For each stage s a fit would touch, r_s is the model's fit-part residual and the columns of B_s
the residual's responses to the fit's free parameters: the tangent (a forward difference) of each
parameter the fit refits beside the candidates (the stages' uncertain ones and the group's
members, at their fitted values), and for each candidate's parameter its tangent at its value in
the model (the score test of a small effect) and the secants from there to GRID points across
its searched range (a rate limit or a dead-band has no slope at its null value: a tangent there
sees nothing; the secants' span holds the larger values the parameter can take)::

    RSS_s,lin  = min_c |r_s - B_s c|^2          (each stage on its own: no joint fit does better on it)
    dBIC_lin   = sum_s n_eff,s ln(1 - SAFETY (1 - RSS_s,lin / RSS_s)) + k ln(sum_s n_eff,s)

n_eff,s the larger of the model's and the predicted residual's (estimation.effective_size, at most the
measurement's own updates on the fit part: Replay.updates), k the candidates'
parameters. A candidate whose dBIC_lin, with its fall in RSS taken SAFETY times, still cannot
reach ``STRONG`` is not fitted: it could not be supported. SAFETY covers what the nonlinear fit
finds beyond the linearisation: on the F1TENTH excerpt's 91 pair fits the fitted fall in RSS was
at most 1.34 x the linearised one.

The selection screens its pairs (Selector.pair: the costly step, every two effects of a misfit
stage); each effect alone is always fitted (the first step's findings are reported, and a later
step's near rivals need their dBIC). The screen is not applied to an effect shown on a stage only
through another part of the model (Effect.tested_on: it is scored where it is not fitted).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from agrobot.estimation import effective_size

from .candidates import refit_free
from .effect import Effect, Parameter

GRID = 3              # secant points across a candidate parameter's searched range
SAFETY = 2.0          # the linearised fall in RSS is taken this many times before it rules a candidate out
STEP = 1e-3           # forward-difference step of a refitted parameter, in its typical scale


@dataclass
class Screened:
    """The screen's number for one candidate (or pair): its linearised dBIC and whether it is fitted."""

    ids: tuple[str, ...]
    delta_bic: float
    fitted: bool
    falls: dict[str, float]           # each stage's linearised fall in RSS, 1 - RSS_s,lin / RSS_s
    sizes: dict[str, float]           # each stage's n_eff,s

    def text(self) -> str:
        return f"{' + '.join(self.ids)} (linearised dBIC {self.delta_bic:.1f})"


def grid(p: Parameter, at: float) -> list[float]:
    """GRID values across ``p``'s searched range (geometric where the range spans a decade of
    positive values: a rate limit), but ``at`` itself."""
    if p.lower > 0 and p.upper / p.lower > 10:
        points = np.geomspace(p.lower, p.upper, GRID)
    else:
        points = np.linspace(p.lower, p.upper, GRID)
    return [float(x) for x in points if not math.isclose(x, at, rel_tol=1e-9, abs_tol=1e-12)]


def tangent_step(p: Parameter, at: float) -> float:
    """A forward step of ``p`` from ``at``, toward the inside of its range."""
    h = STEP * p.scale * max(1.0, abs(at) / p.scale)
    return -h if at + h > p.upper else h


class Screen:
    """The linearised candidates about one model (``values``) on a replay; the columns of each
    parameter are computed once per model and stage."""

    def __init__(self, replay, sigma: dict[str, float], strong: float) -> None:
        self.replay, self.sigma, self.strong = replay, sigma, strong
        self._key: tuple | None = None
        self._columns: dict[tuple[str, str, str], np.ndarray] = {}
        self._residual: dict[str, np.ndarray] = {}
        self.rounds: dict[tuple, dict] = {}          # the pairs screened, per model and pool, in order

    def _at(self, values: dict[str, float]) -> None:
        key = tuple(sorted(values.items()))
        if key != self._key:
            self._key, self._columns, self._residual = key, {}, {}
            self.values = dict(values)

    def residual(self, stage: str) -> np.ndarray:
        """The model's normalised fit-part residual on ``stage``."""
        if stage not in self._residual:
            self._residual[stage] = self.replay.residuals(stage, self.values, "fit") / self.sigma[stage]
        return self._residual[stage]

    def columns(self, stage: str, p: Parameter, kind: str) -> np.ndarray:
        """The residual's responses on ``stage`` to ``p``: its tangent (kind "tangent") or its
        secants across its range ("secants"), one column each."""
        key = (stage, p.name, kind)
        if key not in self._columns:
            at = self.values[p.name]
            points = [at + tangent_step(p, at)] if kind == "tangent" else grid(p, at)
            sets = [{**self.values, p.name: x} for x in points]
            moved = self.replay.residuals_many(stage, sets, "fit")
            r0 = self.residual(stage)
            self._columns[key] = np.column_stack([r0 - r / self.sigma[stage] for r in moved]) if moved \
                else np.zeros((len(r0), 0))
        return self._columns[key]

    def judge(self, values: dict[str, float], refitted: list[Parameter], candidates: list[Effect],
              stages: tuple[str, ...]) -> Screened:
        """The screen's number for fitting ``candidates`` (their parameters free, with ``refitted``)
        on ``stages`` from the model ``values``, and whether it lets them be fitted."""
        self._at(values)
        k = sum(len(e.parameters) for e in candidates)
        falls, sizes = [], []
        for s in stages:
            r0 = self.residual(s)
            cols = [self.columns(s, p, "tangent") for p in refitted]
            cols += [self.columns(s, p, kind) for e in candidates for p in e.parameters for kind in ("tangent", "secants")]
            B = np.column_stack(cols)
            norm = np.linalg.norm(B, axis=0)
            B = B[:, norm > 0] / norm[norm > 0]
            left = r0 - B @ np.linalg.lstsq(B, r0, rcond=None)[0] if B.shape[1] else r0
            rss0 = float(r0 @ r0)
            falls.append(1.0 - float(left @ left) / rss0 if rss0 > 0 else 0.0)
            updates = self.replay.updates(s)
            sizes.append(max(effective_size(left, updates), effective_size(r0, updates)))
        dbic = k * math.log(max(sum(sizes), 2.0))
        for fall, n_eff in zip(falls, sizes):
            dbic += n_eff * math.log(max(1.0 - SAFETY * fall, 1e-300))
        return Screened(tuple(e.id for e in candidates), dbic, dbic < self.strong, dict(zip(stages, falls)),
                        dict(zip(stages, sizes)))

    def pair(self, values: dict[str, float], related: list[Effect], a: Effect, b: Effect, stages: tuple[str, ...],
             pool: list[Effect]) -> bool:
        """Whether the pair (a, b) is fitted (with the group's members ``related`` and the stages'
        uncertain parameters refitted, as selection._refit does), its number noted for the trace
        under the round of ``pool`` from this model. An effect only tested on one of the stages is
        always fitted (it is scored where it is not fitted)."""
        members = related + [a, b]
        if any(set(e.tested_on) & set(stages) for e in members):
            return True
        refitted = refit_free(self.replay, stages, related, joining=[a, b])
        screened = self.judge(values, refitted, [a, b], stages)
        key = (tuple(sorted(values.items())), tuple(e.id for e in pool))
        entry = self.rounds.setdefault(key, {"members": tuple(e.id for e in related), "pairs": {}})
        entry["pairs"][screened.ids] = screened
        return screened.fitted

    def lines(self) -> list[str]:
        """The screen's decisions, one line per round of pairs, for the selection's trace."""
        out = []
        for entry in self.rounds.values():
            pairs = sorted(entry["pairs"].values(), key=lambda x: x.delta_bic)
            skipped = [x.text() for x in pairs if not x.fitted]
            fitted = [x.text() for x in pairs if x.fitted]
            model = f"the model with {', '.join(entry['members'])}" if entry["members"] else "the model"
            out.append(f"screen: pairs against {model}: {len(skipped)} of {len(pairs)} not fitted, their fall in RSS "
                       f"linearised and taken x{SAFETY:g} still leaving dBIC above {self.strong:g} (--no-screen fits "
                       f"them): {'; '.join(skipped) or 'none'}; fitted: {'; '.join(fitted) or 'none'}")
        return out
