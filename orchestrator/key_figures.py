"""The key figures a command prints at its end, judged against bounds.

An analysis module declares its figures, and the bounds it knows, in ``METRICS``: figure ->
(unit, statement). A statement that begins with a comparison and a number (``"< 0.40"``,
``">= 0.99"``, ``"<= 0.05 (RTK class)"``; a bare number means ``==``) is a bound that the figure
passes or fails; other text (``"steady-state error seen"``) is shown as a note; None is neither.
``BOUNDS_SOURCE`` names where its bounds come from (``"paper"``; default ``"analysis"``). A study
adds or replaces bounds in ``[study] bounds = {figure = "< 0.30"}`` (source ``"study"``).

Every ``nan`` and every FAIL of a run's table says why on its line. An analysis module may define
``reasons(values, study) -> {figure: why}`` (a figure it could not compute: "no straight after the
13 s settling: run at least 40 s") and ``unjudged(values, study) -> {figure: why}`` (a bound that
does not fit what was run: "bounds for the whole field; this run plans 2 swaths"; the figure is
shown, not judged). A FAIL the analysis gives no reason for says by how much it missed its bound.

``run_table`` is the table of a run, ``sweep_table`` that of a sweep (P50, P95 and max over the
completed points, and the share within each bound), ``realtime_lines`` the pacing of a real-time
run and whether it kept real time.
"""
from __future__ import annotations

import math
import operator
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np
import pandas as pd

from .errors import did_you_mean
from .study_files import StudyError
from .study_schema import BOUND

_OPS = {"<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge, "==": operator.eq,
        "=": operator.eq}


@dataclass(frozen=True)
class Bound:
    op: str
    value: float
    source: str
    number: str = ""            # the value as written ("0.40")

    def holds(self, x: float) -> bool:
        return bool(_OPS[self.op](x, self.value)) if math.isfinite(x) else False

    def __str__(self) -> str:
        return f"{'==' if self.op == '=' else self.op} {self.number or f'{self.value:g}'}"


def parse_bound(statement: str | None, source: str) -> Bound | None:
    """The bound a statement begins with (see the module docstring), None when it is not one."""
    if not isinstance(statement, str):
        return None
    m = BOUND.match(statement)
    if m is None:
        return None
    return Bound(m.group(1) or "==", float(m.group(2)), source, m.group(2))


def declared(analysis) -> dict[str, tuple[str | None, str | None]]:
    """figure -> (unit, statement) from the analysis module's ``METRICS`` (empty without one)."""
    table = getattr(analysis, "METRICS", None) or {}
    return {k: (v[0], v[1]) if isinstance(v, tuple) else (v, None) for k, v in table.items()}


def known_figures(analysis) -> set[str]:
    """Every figure an analysis says it computes (``METRICS`` and ``METRIC_UNITS``)."""
    return set(declared(analysis)) | set(getattr(analysis, "METRIC_UNITS", None) or {})


def bounds(analysis, study_bounds: Mapping[str, str] | None = None) -> dict[str, Bound]:
    """The analysis's bounds, with the study's added over them."""
    source = getattr(analysis, "BOUNDS_SOURCE", "analysis")
    out = {k: b for k, (_, text) in declared(analysis).items() if (b := parse_bound(text, source)) is not None}
    for key, text in (study_bounds or {}).items():
        out[key] = parse_bound(text, "study")
    return out


def check_study_bounds(analysis, study_bounds: Mapping[str, str], origin) -> None:
    """Refuse, before anything runs, a bound on a figure the analysis does not compute
    (``origin(field)`` says where the bound was given: Study.origin)."""
    known = known_figures(analysis) | {"sim_time_s", "wall_time_s", "events"}
    if analysis is None or not known_figures(analysis):
        return
    for key in study_bounds:
        if key not in known:
            raise StudyError(f"{origin(f'study.bounds.{key}')}: the analysis {getattr(analysis, '__name__', '')!r} "
                             f"computes no figure {key!r}{did_you_mean(key, sorted(known))}"
                             + f" Its figures: {', '.join(sorted(declared(analysis)) or sorted(known))}")


def _number(x: Any) -> str:
    if isinstance(x, bool) or not isinstance(x, (int, float, np.number)):
        return str(x)
    x = float(x)
    if not math.isfinite(x):
        return str(x)
    if x == int(x) and abs(x) < 1e9:
        return f"{int(x)}"
    return f"{x:.4g}" if abs(x) >= 1e-3 or x == 0 else f"{x:.3e}"


def _figures(values: Mapping[str, Any], analysis, judged: Mapping[str, Bound]) -> list[tuple[str, str | None, str | None]]:
    """(figure, unit, note) in the order to show: the analysis's declared figures, then the
    judged ones it did not declare; for a study without an analysis, every number."""
    table = declared(analysis)
    units = dict(getattr(analysis, "METRIC_UNITS", None) or {})
    rows = [(k, unit, text) for k, (unit, text) in table.items() if k in values]
    rows += [(k, units.get(k), None) for k in judged if k not in table]
    if not table:
        rows += [(k, units.get(k), None) for k, v in values.items() if k not in judged
                 and isinstance(v, (int, float)) and not isinstance(v, bool)]
    return rows


def hook(analysis, name: str, values: Mapping[str, Any], study) -> dict[str, str]:
    """An analysis's ``reasons`` or ``unjudged`` for this run (empty without one or a study)."""
    hook = getattr(analysis, name, None)
    return dict(hook(values, study)) if hook is not None and study is not None else {}


def _missed(value: float, bound: Bound, unit: str | None) -> str:
    """How far a finite value lies on the wrong side of its bound."""
    gap = abs(value - bound.value)
    side = "above" if value > bound.value else "below" if value < bound.value else "at"
    unit = "" if unit in (None, "", "1") else unit
    return f"{_number(gap)} {unit} {side} the bound".replace("  ", " ") if side != "at" else "at the bound"


def run_table(values: Mapping[str, Any], analysis, judged: Mapping[str, Bound], study=None) -> tuple[str, list[str]]:
    """(the table, the failed bounds as lines) of one run; every nan and FAIL with its reason (the
    analysis's ``reasons`` and ``unjudged`` for ``study``, see the module docstring)."""
    rows = _figures(values, analysis, judged)
    why, unjudged = hook(analysis, "reasons", values, study), hook(analysis, "unjudged", values, study)
    width = max([len(k) for k, _, _ in rows] + [10])
    lines = [f"{'figure':<{width}}  {'value':>11}  {'unit':<6} {'bound':<22} check", "-" * (width + 50)]
    failed, skipped = [], 0
    for key, unit, note in rows:
        value = values.get(key, math.nan)
        number = isinstance(value, (int, float, np.number)) and not isinstance(value, bool)
        finite = number and math.isfinite(float(value))
        bound = judged.get(key)
        reason = "" if finite or not number else why.get(key) or (
            "not computed by the analysis" if key not in values else "not computed (the analysis says no more)")
        if bound is not None and key in unjudged:
            text, check, reason = f"{bound} ({bound.source})", "not judged", unjudged[key]
            skipped += 1
        elif bound is not None:
            ok = number and bound.holds(float(value))
            text, check = f"{bound} ({bound.source})", "pass" if ok else "FAIL"
            if not ok:
                # a number on the wrong side: how far; a nan or missing figure: why the analysis has none
                reason = _missed(float(value), bound, unit) if finite else reason
                failed.append(f"{key} = {_number(value)} {unit or ''} (bound {bound}, {bound.source}): {reason}"
                              .replace("  ", " "))
        else:
            text, check = (note or ""), ""
        line = f"{key:<{width}}  {_number(value):>11}  {unit or '':<6} {text:<22} {check}".rstrip()
        lines.append(f"{line}{' ' * max(1, width + 48 - len(line))} {reason}" if reason else line)
    if judged:
        present = [k for k in judged if k in values and k not in unjudged]
        lines.append((f"bounds: {len(present) - len(failed)} of {len(present)} met" if failed else
                      f"bounds: all {len(present)} met") + (f" ({skipped} not judged: see their lines)" if skipped else ""))
    return "\n".join(lines), failed


def sweep_table(table, analysis, judged: Mapping[str, Bound], skip: set[str] = frozenset(),
                short: Mapping[str, float] | None = None) -> str:
    """P50, P95 and max of each key figure over the completed points; the share of all points
    within each bound (a failed point counts as outside). ``skip``: the swept parameters; ``short``:
    {figure: stop time needed} of the bounds the nominal run was too short to judge: a point without
    that figure is counted as not judged, neither within nor outside."""
    done = table[table["status"] == "completed"] if "status" in table else table
    numeric = {c: 0.0 for c in done.columns if c not in skip and pd.api.types.is_numeric_dtype(done[c])}
    rows = [(k, unit) for k, unit, _ in _figures(numeric, analysis, judged)
            if k in numeric and k not in ("sim_time_s", "wall_time_s", "events", "point", "seed")]
    if not rows:
        return ""
    width = max([len(k) for k, _ in rows] + [10])
    lines = [f"{'figure':<{width}}  {'unit':<6}{'P50':>11}{'P95':>11}{'max':>11}  {'bound':<22} within",
             "-" * (width + 72)]
    for key, unit in rows:
        x = done[key].to_numpy(dtype=float)
        x = x[np.isfinite(x)]
        stats = [np.percentile(x, 50), np.percentile(x, 95), x.max()] if len(x) else [math.nan] * 3
        bound = judged.get(key)
        within = ""
        if bound is not None and len(table):
            inside = sum(bound.holds(float(v)) for v in done[key])
            within = f"{inside} of {len(table)} ({100 * inside / len(table):.0f}%)"
            unjudged = int(done[key].isna().sum()) if key in (short or {}) else 0
            if unjudged:             # too short to have the figure: not judged, not counted either way
                n = len(table) - unjudged
                within = (f"{inside} of {n} judged{f' ({100 * inside / n:.0f}%)' if n else ''}; {unjudged} "
                          f"not judged: run at least {short[key]:g} s")
        lines.append(f"{key:<{width}}  {unit or '':<6}" + "".join(f"{_number(v):>11}" for v in stats)
                     + f"  {(f'{bound} ({bound.source})' if bound else ''):<22} {within}".rstrip())
    return "\n".join(lines)


def realtime_lines(stats: Mapping[str, Any] | None) -> tuple[list[str], str | None]:
    """(summary lines, a warning or None) of a real-time run's pacing statistics."""
    if not stats or not stats.get("steps"):
        return [], None
    n, misses = stats["steps"], stats.get("deadline_misses", 0)
    jit, busy = stats.get("jitter_ms", {}), stats.get("compute_ms", {})
    fmt = lambda d: "/".join(_number(d.get(q, math.nan)) for q in ("p50", "p99", "max"))  # noqa: E731
    lines = [f"real time: {n} steps of {_number(stats['step_ms'])} ms; {misses} started more than "
             f"{_number(stats['tolerance_ms'])} ms after their deadline ({100 * misses / n:.1f}%)",
             f"  lateness p50/p99/max {fmt(jit)} ms; compute per step p50/p99/max {fmt(busy)} ms"]
    warning = None
    if misses:
        warning = (f"real time was not kept: {misses} of {n} steps ({100 * misses / n:.0f}%) missed their "
                   f"deadline (worst {_number(jit.get('max', math.nan))} ms late); the controller's timing "
                   f"differs from the hardware's")
    return lines, warning
