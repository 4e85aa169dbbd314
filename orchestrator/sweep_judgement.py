"""Each point of a sweep judged on its own, and the points that fail named with what they share.

Bounds judged per point: the study analysis's and the study's (orchestrator.key_figures), and
the oscillation bound. Oscillation: a loop that hunts (a limit cycle of an actuator) may track
its reference within every error bound while its actuator works ten times as hard; its error
bounds cannot see it. The measure is a metric of the point (an actuator's rate RMS) over that of
the nominal run (the study with its own values, no swept value set), bounded:

    r = metric_point / metric_nominal <= ratio

The analysis that computes the metric names it and its bound, with the reason for the number:
``OSCILLATION = (metric, ratio)`` in the sweep analysis module (``sweep.analysis``), else in the
study's analysis module (``study.analysis``); None or absent: no oscillation bound.

The points outside a bound are grouped by the bounds they fail; each group is described by what
its points share (``shared``): a choice all of them took that not every point took, a numeric
range narrower than the swept one, each kept only when chance would not explain it (random draws
all inside it less often than 1 in 100; on a grid, 75 % of its points failing), in groups of
``SHARED_MIN_POINTS`` or more; and how many of the points in that region fail (the description's
precision).
"""
from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np
import pandas as pd

from .key_figures import Bound, _number, bounds, hook
from .registry import import_study_module
from .runner import _analysis
from .study import Study

SHARED_MIN_POINTS = 3
CHOICES_UP_TO = 6            # a swept parameter with at most this many distinct values is a choice
CHANCE = 0.01                # a condition random draws would all meet by chance less often than this is shared
PRECISION = 0.75             # on a grid: a condition is shared when this share of its points fail
EDGE = 0.02                  # a failing range this close to an end of the swept span is open at that end


def oscillation(study: Study) -> tuple[str, float] | None:
    """(metric, largest ratio to the nominal) judged for ``study``'s sweep, None for none: the
    sweep analysis's ``OSCILLATION``, else the study analysis's."""
    names = [study.sweep.analysis if study.sweep is not None else None, study.study.analysis]
    for name in names:
        if name:
            module = import_study_module(name)
            if hasattr(module, "OSCILLATION"):
                return module.OSCILLATION
    return None


def nominal_from_table(table: pd.DataFrame, study: Study) -> dict[str, float]:
    """The nominal run's oscillation metric as a table of points holds it (metric / ratio; a table
    saved without its nominal run), empty when it does not."""
    chosen = oscillation(study)
    if chosen is None or chosen[0] not in table or ratio_column(chosen[0]) not in table:
        return {}
    ratio = table[ratio_column(chosen[0])].astype(float)
    values = (table[chosen[0]].astype(float) / ratio)[np.isfinite(ratio) & (ratio > 0)]
    return {chosen[0]: float(values.median())} if len(values) else {}


def ratio_column(metric: str) -> str:
    return f"{metric}_vs_nominal"


def with_oscillation(table: pd.DataFrame, study: Study, nominal: Mapping[str, Any] | None) -> pd.DataFrame:
    """``table`` with the column ``METRIC_vs_nominal`` (the point's value over the nominal run's)
    when the points and the nominal computed the metric."""
    chosen = oscillation(study)
    reference = _reference(nominal, chosen[0]) if chosen is not None else None
    if reference is None or table.empty or chosen[0] not in table:
        return table
    table = table.copy()
    table[ratio_column(chosen[0])] = table[chosen[0]].astype(float) / reference
    return table


def _reference(nominal: Mapping[str, Any] | None, metric: str) -> float | None:
    value = (nominal or {}).get(metric)
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value > 0
    return float(value) if ok else None


def sweep_bounds(study: Study, nominal: Mapping[str, Any] | None) -> dict[str, Bound]:
    """The bounds each point is judged by: the key figures' (the study analysis's and the study's)
    and the oscillation bound (when the nominal run computed its metric)."""
    judged = {k: b for k, b in bounds(_analysis(study), study.study.bounds).items() if b is not None}
    chosen = oscillation(study)
    if chosen is not None and _reference(nominal, chosen[0]) is not None:
        judged[ratio_column(chosen[0])] = Bound("<=", float(chosen[1]), "sweep: hunting", f"{chosen[1]:g}")
    return judged


def too_short(study: Study, nominal: Mapping[str, Any] | None) -> dict[str, float]:
    """{bounded figure: the stop time (s) it needs} for the bounds the ``nominal`` run is too short
    to judge: the study analysis's ``stop_time_needed(values, study) -> {figure: s}``. The points run
    as long: those like it cannot judge them either."""
    if not nominal:
        return {}
    analysis = _analysis(study)
    judged = sweep_bounds(study, nominal)
    return {k: t for k, t in hook(analysis, "stop_time_needed", nominal, study).items() if k in judged}


def length_warning(study: Study, nominal: Mapping[str, Any] | None, points: int) -> str | None:
    """The line a sweep prints before its first point when its nominal run is too short for a bound
    (``too_short``): the study file, ``study.stop_time``, the bounds and the stop time needed."""
    short = too_short(study, nominal)
    if not short:
        return None
    need, why = max(short.values()), hook(_analysis(study), "reasons", nominal, study)
    stop, origin = study.study.stop_time, study.origin("study.stop_time")
    given = f" ({origin.split(' (')[0]})" if origin.startswith("--set") else ""
    reason = next((why[k] for k in short if k in why), "")
    many = len(short) > 1
    return (f"warning: {study.where}: study.stop_time = {stop:g} s{given} is too short for the bound"
            f"{'s' if many else ''} on {', '.join(short)} ({reason}): the nominal run cannot judge "
            f"{'them' if many else 'it'}, nor can those of the {points} points that run like it (the sweep's "
            f"table counts them as not judged). To judge {'them' if many else 'it'}, run at least {need:g} s: "
            f"--set study.stop_time={need:g}")


def point_row(record: Mapping[str, Any], study: Study, nominal: Mapping[str, Any] | None) -> dict[str, Any]:
    """A stored point's record as one row of the table (its status, metrics and oscillation ratio)."""
    row = {"status": record.get("status"), **(record.get("metrics") or {})}
    chosen = oscillation(study)
    reference = _reference(nominal, chosen[0]) if chosen is not None else None
    if reference is not None and chosen[0] in row:
        row[ratio_column(chosen[0])] = float(row[chosen[0]]) / reference
    return row


def failed_bounds(row: Mapping[str, Any], judged: Mapping[str, Bound]) -> list[str]:
    """The bounds a completed point fails (a figure it lacks, or nan, is not judged here: the
    table of key figures says why it is missing)."""
    out = []
    for key, bound in judged.items():
        value = row.get(key)
        number = isinstance(value, (int, float, np.number)) and not isinstance(value, bool)
        if number and math.isfinite(float(value)) and not bound.holds(float(value)):
            out.append(key)
    return out


def severity(row: Mapping[str, Any], judged: Mapping[str, Bound]) -> float:
    """How far a point is from its bounds, the worst of value / bound (bound / value for a lower
    bound); above 1 outside. A point that did not complete, or a figure that is nan: infinite."""
    if row.get("status") != "completed":
        return math.inf
    worst = 0.0
    for key, bound in judged.items():
        value = row.get(key)
        if not isinstance(value, (int, float, np.number)) or isinstance(value, bool):
            continue
        value = float(value)
        if not math.isfinite(value):
            return math.inf
        if bound.value == 0 or value == 0:
            continue
        worst = max(worst, value / bound.value if bound.op.startswith("<") else bound.value / value)
    return worst


def _condition(name: str, values: pd.Series, inside: pd.Series) -> tuple[str, pd.Series] | None:
    """The narrowest condition on parameter ``name`` that every failing point (``inside``)
    meets: (text, mask over all points), or None when every value meets it."""
    everywhere, failing = values.dropna(), values[inside].dropna()
    if failing.empty:
        return None
    numeric = pd.api.types.is_numeric_dtype(everywhere) and not pd.api.types.is_bool_dtype(everywhere)
    if not numeric or everywhere.nunique() <= CHOICES_UP_TO:
        chosen = sorted(set(failing.astype(str)))
        if len(chosen) == everywhere.astype(str).nunique():
            return None
        text = f"{name} = {chosen[0]}" if len(chosen) == 1 else f"{name} in {{{', '.join(chosen)}}}"
        return text, values.astype(str).isin(chosen)
    lo, hi, all_lo, all_hi = failing.min(), failing.max(), everywhere.min(), everywhere.max()
    if all_hi <= all_lo or (lo <= all_lo and hi >= all_hi):
        return None
    swept = f"(swept {_number(all_lo)}-{_number(all_hi)})"
    edge = EDGE * (all_hi - all_lo)
    if lo <= all_lo + edge and hi >= all_hi - edge:
        return None
    if hi >= all_hi - edge:
        return f"{name} >= {_number(lo)} {swept}", values >= lo
    if lo <= all_lo + edge:
        return f"{name} <= {_number(hi)} {swept}", values <= hi
    return f"{name} {_number(lo)}-{_number(hi)} {swept}", values.between(lo, hi)


def by_chance(n: int, share: float, choice: bool) -> float:
    """The chance that ``n`` points drawn at random all meet a condition met by ``share`` of all
    points: share^n for a choice; for a range found from the points themselves, the chance
    that n uniform draws span at most that share, n q^(n-1) - (n-1) q^n."""
    if choice:
        return share ** n
    return n * share ** (n - 1) - (n - 1) * share ** n


def shared(table: pd.DataFrame, failing: pd.Series, parameters: list[str], drawn: bool) -> str:
    """What the failing points share, and how many points of that region fail: "plant.model =
    b, source.rate >= 1.72 (swept 1-2.5): 23 of the 27 points there fail". A condition is
    kept when it is not chance: for random draws (``drawn``, a Monte Carlo) when ``by_chance`` is
    below ``CHANCE``; for values placed on a grid when at least ``PRECISION`` of its points fail."""
    n = int(failing.sum())
    if n < SHARED_MIN_POINTS:
        return ""
    region = pd.Series(True, index=table.index)
    texts = []
    for name in parameters:
        if name not in table:
            continue
        found = _condition(name, table[name], failing)
        if found is None:
            continue
        text, mask = found
        share = float(mask.mean())
        choice = " = " in text or " in {" in text
        kept = by_chance(n, share, choice) < CHANCE if drawn else (mask & failing).sum() >= PRECISION * mask.sum()
        if kept:
            texts.append(text)
            region &= mask
    if not texts:
        return "nothing in the swept parameters that chance would not explain"
    return f"{', '.join(texts)}: {int((region & failing).sum())} of the {int(region.sum())} points there fail"


def failing_groups(table: pd.DataFrame, judged: Mapping[str, Bound]) -> list[tuple[tuple[str, ...], list[str], pd.Series]]:
    """The completed points outside a bound, grouped by the bounds they fail, largest group first:
    [(bounds, points, mask over the table), ...]."""
    if table.empty or "status" not in table:
        return []
    keys = pd.Series([tuple(failed_bounds(row, judged)) if row.get("status") == "completed" else ()
                      for row in table.to_dict("records")], index=table.index)
    groups = []
    for key in sorted({k for k in keys if k}, key=lambda k: -int((keys == k).sum())):
        mask = keys == key
        groups.append((key, list(table.loc[mask, "point"].astype(str)), mask))
    return groups


def judgement_lines(study: Study, table: pd.DataFrame, judged: Mapping[str, Bound],
                    nominal: Mapping[str, Any] | None) -> list[str]:
    """The summary's lines on the points outside a bound: each group named, its points listed (up
    to 12), and what its points share."""
    lines = []
    chosen = oscillation(study)
    if chosen is not None and nominal and ratio_column(chosen[0]) in table:
        lines.append(f"oscillation: {chosen[0]} of each point over the nominal run's ({_number(nominal[chosen[0]])}, "
                     f"the study's own values), bound <= {chosen[1]:g} (a loop that hunts drives its actuator several "
                     f"times as hard as one that tracks)")
        done = table[table["status"] == "completed"][chosen[0]].astype(float)
        if len(done) and float(nominal[chosen[0]]) > chosen[1] * float(done.median()):
            lines.append(f"  warning: the nominal run's {chosen[0]} is {float(nominal[chosen[0]]) / float(done.median()):.1f} x "
                         f"the points' median: it may hunt, and a point that hunts as it does passes")
    groups = failing_groups(table, judged)
    if not groups:
        if judged and len(table):
            lines.append(f"every completed point within all {len(judged)} bounds, each judged on its own")
        return lines
    total = sum(len(points) for _, points, _ in groups)
    lines.append(f"points outside a bound: {total} of {len(table)}")
    params = list(study.sweep.parameters) if study.sweep is not None else []
    for names, points, mask in groups:
        shown = ", ".join(points[:12]) + (", ..." if len(points) > 12 else "")
        lines.append(f"  {len(points):>4} x {' and '.join(f'{n} {judged[n]}' for n in names)} not met  ({shown})")
        common = shared(table, mask, params, study.sweep is not None and study.sweep.mode == "monte_carlo")
        if common:
            lines.append(f"         shared: {common}")
    return lines
