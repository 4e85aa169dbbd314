"""Which stretches of a log are judged. A declared mode or engagement channel selects them
(``--where 'mode == auto'``: COLUMN OP VALUE with OP one of == != < <= > >=, joined by ``and`` /
``or``, ``and`` binding first); without one, the stretches where the command does not explain the
steering are found and left out (``--keep-unexplained`` keeps them): a machine driven by hand or
by remote while its path follower's command runs on.

The steering's relation to its command: delta(t) = a delta_cmd(t - d) + b, fitted by least
squares on the rows that fit it (a trimmed fit: the rows whose residual is within 3 times the
median, twice), d the delay of 0-1 s that fits best. A stretch is not explained where the RMS of
the residual over UNEXPLAINED_WINDOW exceeds UNEXPLAINED_RATIO times its median over the log and
UNEXPLAINED_FLOOR, and UNRELATED times the larger standard deviation of delta or of its fit there
(two unrelated signals: a saturated or rate-limited steering still follows its command), for
UNEXPLAINED_MIN seconds or more (blips under half a window dropped first; shorter agreements
inside such a stretch belong to it). Both selections are printed (times, count,
share of the log) and kept in ``frame.attrs["selection"]``.

A ``--where`` that does not fit the log (its syntax, a column the log lacks, a comparison the
column's values cannot take) is a WhereError: a usage error, after which a command writes nothing;
one that selects nothing is the log's content (a diagnosis says it cannot decide, and why).
"""
from __future__ import annotations

import re
import sys
from dataclasses import dataclass

import numpy as np
import pandas as pd

from .log import LogError

OPERATORS = ("==", "!=", "<=", ">=", "<", ">")
MODE_NAMES = ("mode", "control_mode", "drive_mode", "driving_mode", "state", "autonomy", "engaged", "engagement",
              "auto_mode", "operation_mode")
MODE_VALUES = 12        # a mode channel takes at most this many values
UNEXPLAINED_WINDOW = 2.0        # s: the residual's RMS is taken over this window
UNEXPLAINED_RATIO = 4.0         # x the log's median RMS of the residual
UNEXPLAINED_FLOOR = 0.01        # rad (0.57 deg): a smaller residual is explained
UNEXPLAINED_MIN = 3.0           # s: a shorter stretch is not named
UNRELATED = 0.8                 # the residual's RMS against the larger motion of delta or of its fit
_TERM = re.compile(r"^\s*([A-Za-z_][\w.]*)\s*(==|!=|<=|>=|<|>|=)\s*(?:'([^']*)'|\"([^\"]*)\"|([^\s'\"]+))\s*$")


class WhereError(LogError):
    """A ``--where`` that does not fit the log: the command's usage, not the log's content."""


@dataclass(frozen=True)
class Condition:
    """COLUMN OP VALUE: VALUE a number or a word (a text column's value)."""

    column: str
    op: str
    value: float | str


def is_mode_name(name) -> bool:
    """A mode or engagement channel by its name (MODE_NAMES, any letter case; a TABLE.COLUMN's
    column)."""
    return str(name).split(".")[-1].lower() in MODE_NAMES


def mode_codes(t: np.ndarray, values) -> tuple[np.ndarray, np.ndarray, list | None] | None:
    """(times, codes, labels) of a mode channel on the rows that say a value (a blank cell says
    nothing: the mode in force holds, a channel written at a lower rate or only when it changes):
    text as codes 0, 1, ... into ``labels`` (their order of first appearance), numbers as they are
    (labels None); None when it takes more than MODE_VALUES values (not a mode)."""
    col = pd.Series(values)
    number = pd.to_numeric(col, errors="coerce")
    text = col.astype(str).str.strip()
    said = col.notna().to_numpy() & (text != "").to_numpy() & (text.str.lower() != "nan").to_numpy()
    if not said.any():
        return None
    t = np.asarray(t, float)[said]
    if number[said].notna().all():
        x = number[said].to_numpy(float)
        return (t, x, None) if len(np.unique(x)) <= MODE_VALUES else None
    labels = list(dict.fromkeys(text[said]))
    if len(labels) > MODE_VALUES:
        return None
    return t, text[said].map({v: float(i) for i, v in enumerate(labels)}).to_numpy(float), labels


def decoded(codes: np.ndarray, labels: list) -> np.ndarray:
    """A mode channel's codes (NaN: not said yet) as its text values (None where not said)."""
    out = np.full(len(codes), None, dtype=object)
    ok = np.isfinite(codes)
    out[ok] = np.asarray(labels, dtype=object)[codes[ok].astype(int)]
    return out


def parse_where(text: str) -> list[list[Condition]]:
    """``--where``: the conditions as alternatives (``or``) of conjunctions (``and``); a LogError
    says what is wrong and what was expected."""
    usage = (f"--where {text!r}: expected COLUMN OP VALUE (OP one of {' '.join(OPERATORS)}), joined by 'and' or "
             f"'or', e.g. --where 'mode == auto' or --where 'engaged == 1 and v > 0.5'")
    alternatives = []
    for part in re.split(r"\s+or\s+", text.strip()):
        terms = []
        for piece in re.split(r"\s+and\s+", part):
            m = _TERM.match(piece)
            if not m:
                raise WhereError(usage)
            word = next(g for g in m.groups()[2:] if g is not None)
            quoted = m.group(3) is not None or m.group(4) is not None
            try:
                value: float | str = word if quoted else float(word)
            except ValueError:
                value = word
            terms.append(Condition(m.group(1), "==" if m.group(2) == "=" else m.group(2), value))
        alternatives.append(terms)
    if not alternatives or not all(alternatives):
        raise WhereError(usage)
    return alternatives


def _held_values(col: pd.Series) -> str:
    """What a channel holds: its values with their counts (a few), or its range."""
    counts = col.value_counts(dropna=False)
    if len(counts) <= 12:
        return ", ".join(f"{_show(v)} ({n} rows)" for v, n in counts.items())
    x = pd.to_numeric(col, errors="coerce")
    return f"{len(counts)} values from {x.min():.4g} to {x.max():.4g}" if x.notna().any() else \
        f"{len(counts)} values, e.g. {', '.join(map(_show, counts.index[:8]))}"


def _show(v) -> str:
    return f"{v:g}" if isinstance(v, (int, float, np.number)) and not isinstance(v, bool) else repr(str(v))


def _condition(frame: pd.DataFrame, c: Condition, source) -> np.ndarray:
    if c.column not in frame:
        raise WhereError(f"{source}: --where: no column {c.column!r}; the log has {', '.join(map(str, frame.columns))} "
                       f"(a raw recording's channel is mapped with --signal {c.column}=...)")
    col = frame[c.column]
    numeric = pd.api.types.is_numeric_dtype(col)
    if numeric and isinstance(c.value, str):
        raise WhereError(f"{source}: --where {c.column} {c.op} {c.value}: column {c.column!r} holds numbers "
                       f"({_held_values(col)}); compare it with a number")
    x = col.to_numpy(float) if numeric else col.astype(str).str.strip().to_numpy()
    v = c.value if numeric else str(c.value if isinstance(c.value, str) else _show(c.value))
    if not numeric and c.op not in ("==", "!="):
        raise WhereError(f"{source}: --where {c.column} {c.op} {c.value}: column {c.column!r} holds text "
                       f"({_held_values(col)}); compare it with == or !=")
    return {"==": lambda: x == v, "!=": lambda: x != v, "<": lambda: x < v, "<=": lambda: x <= v,
            ">": lambda: x > v, ">=": lambda: x >= v}[c.op]()


def index_runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(first, one past the last) row of each True stretch of ``mask``."""
    edges = np.diff(np.concatenate([[0], np.asarray(mask).astype(int), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


def stretches(mask: np.ndarray, t: np.ndarray) -> list[tuple[float, float]]:
    """(start, end) times of the True stretches of ``mask`` on the log's clock."""
    return [(float(t[a]), float(t[b - 1])) for a, b in index_runs(mask)]


def _described(what: str, mask: np.ndarray, t: np.ndarray) -> str:
    step = float(np.median(np.diff(t))) if len(t) > 1 else 0.0
    found = stretches(mask, t)
    return (f"{what}: {len(found)} stretch(es), {mask.sum() * step:.1f} s of {len(t) * step:.1f} s "
            f"({100 * mask.mean():.0f} % of the log): " + ", ".join(f"{a:.2f}-{b:.2f} s" for a, b in found[:12])
            + (" ..." if len(found) > 12 else ""))


def where_mask(frame: pd.DataFrame, text: str, source) -> tuple[np.ndarray, str]:
    """(rows selected by ``--where text``, the line that says which); a LogError naming the file,
    the channel and the values it holds when nothing is selected."""
    alternatives = parse_where(text)
    mask = np.zeros(len(frame), bool)
    for terms in alternatives:
        part = np.ones(len(frame), bool)
        for c in terms:
            part &= _condition(frame, c, source)
        mask |= part
    if not mask.any():
        held = "; ".join(f"column {c!r} holds {_held_values(frame[c])}"
                         for c in dict.fromkeys(c.column for terms in alternatives for c in terms))
        raise LogError(f"{source}: --where {text!r} selects nothing: {held}")
    return mask, _described(f"--where {text!r} selects", mask, frame["t"].to_numpy(float))


def _fit(cmd: np.ndarray, delta: np.ndarray) -> tuple[np.ndarray, float]:
    """(residual of delta = a cmd + b, the RMS of the rows kept) by a trimmed least-squares fit."""
    keep = np.ones(len(cmd), bool)
    for _ in range(3):
        a_mat = np.column_stack([cmd[keep], np.ones(keep.sum())])
        (a, b), *_ = np.linalg.lstsq(a_mat, delta[keep], rcond=None)
        e = delta - a * cmd - b
        keep = np.abs(e) <= 3 * max(float(np.median(np.abs(e))), 1e-12)
    return e, float(np.sqrt(np.mean(e[keep] ** 2)))


def unexplained_mask(frame: pd.DataFrame) -> tuple[np.ndarray, dict]:
    """Rows where delta_cmd does not explain delta (the module's docstring), and the fit: delay,
    the residual's median RMS and the threshold."""
    t = frame["t"].to_numpy(float)
    if "delta_cmd" not in frame or "delta" not in frame or len(t) < 20:
        return np.zeros(len(t), bool), {}
    step = float(np.median(np.diff(t)))
    cmd, delta = frame["delta_cmd"].to_numpy(float), frame["delta"].to_numpy(float)
    best = None
    for k in range(0, max(int(round(1.0 / step)), 1) + 1, max(int(round(0.05 / step)), 1)):
        e, rms = _fit(cmd[:len(cmd) - k], delta[k:])
        if best is None or rms < best[2]:
            best = (k, e, rms)
    k, e, _ = best
    e = np.concatenate([np.full(k, np.nan), e])
    fitted = np.concatenate([np.full(k, np.nan), delta[k:] - e[k:]])
    n = max(int(round(UNEXPLAINED_WINDOW / step)), 3)

    def window(x):
        return pd.Series(x).rolling(n, center=True, min_periods=max(n // 2, 2))
    rolling = window(e ** 2).mean().pow(0.5).to_numpy()
    motion = np.fmax(window(delta).std().to_numpy(), window(fitted).std().to_numpy())
    typical = float(np.nanmedian(rolling))
    limit = max(UNEXPLAINED_RATIO * typical, UNEXPLAINED_FLOOR)
    unrelated = rolling > UNRELATED * np.fmax(np.nan_to_num(motion), UNEXPLAINED_FLOOR)
    mask = (np.nan_to_num(rolling, nan=0.0) > limit) & unrelated
    # blips under half a window dropped, shorter agreements inside a stretch joined, short stretches dropped
    for value, shorter in ((True, UNEXPLAINED_WINDOW / 2), (False, UNEXPLAINED_MIN), (True, UNEXPLAINED_MIN)):
        for a, b in index_runs(mask == value):
            if (b - a) * step < shorter and (value or (0 < a and b < len(mask))):
                mask[a:b] = not value
    return mask, {"delay_s": k * step, "typical_rms_rad": typical, "threshold_rad": limit}


def judged(frame: pd.DataFrame, source, options) -> pd.DataFrame:
    """The rows of ``frame`` that are judged: those ``options.where`` selects, less the stretches
    the command does not explain (unless ``options.keep_unexplained``), less the stretches left
    shorter than ``options.min_stretch`` s; what was chosen is printed (to stderr) and kept in
    frame.attrs["selection"], the stretches judged (start, end) in frame.attrs["stretches"], the log's
    first and last time in frame.attrs["log_span"]."""
    where = getattr(options, "where", None)
    keep = np.ones(len(frame), bool)
    lines = []
    if where:
        keep, line = where_mask(frame, where, source)
        lines.append(line)
    else:
        found, fit = unexplained_mask(frame)
        if found.any():
            what = _described("the command does not explain the steering (driven by hand or by remote?)", found,
                              frame["t"].to_numpy(float))
            lines.append(what + f"; delta - (a delta_cmd(t - {fit['delay_s']:.2f} s) + b) has an RMS over "
                         f"{UNEXPLAINED_WINDOW:g} s above {fit['threshold_rad']:.3g} rad there ("
                         f"{fit['typical_rms_rad']:.2g} rad elsewhere): "
                         + ("kept (--keep-unexplained)" if getattr(options, "keep_unexplained", False) else
                            "left out (--keep-unexplained keeps them; --where selects stretches by a mode channel)"))
            if not getattr(options, "keep_unexplained", False):
                keep = ~found
    if not lines:
        return frame
    keep, line = long_enough(frame["t"].to_numpy(float), keep, getattr(options, "min_stretch", 15.0), source,
                             refuse=bool(where))
    lines.append(line)
    _say(lines, options)
    attrs = dict(frame.attrs)
    t = frame["t"].to_numpy(float)
    out = frame[keep].reset_index(drop=True) if not keep.all() else frame
    out.attrs.update(attrs)
    out.attrs["selection"] = lines
    out.attrs["stretches"] = stretches(keep, t)
    out.attrs["log_span"] = (float(t[0]), float(t[-1]))
    return out


def long_enough(t: np.ndarray, keep: np.ndarray, least: float, source, refuse: bool = True) -> tuple[np.ndarray, str]:
    """(``keep`` less its stretches shorter than ``least`` s, the line naming every stretch judged
    with its times and share of the log, and those left out). None that long: a LogError
    (``refuse``: a --where the user gave), else the longest alone, said."""
    keep = keep.copy()
    short = [(a, b) for a, b in index_runs(keep) if t[b - 1] - t[a] < least]
    if not refuse and len(short) == len(index_runs(keep)) and short:
        short.remove(max(short, key=lambda ab: t[ab[1] - 1] - t[ab[0]]))      # none long enough: the longest kept
    for a, b in short:
        keep[a:b] = False
    if not keep.any():
        raise LogError(f"{source}: no selected stretch lasts --min-stretch {least:g} s; the longest lasts "
                       f"{max(t[b - 1] - t[a] for a, b in short):.1f} s (a smaller --min-stretch takes it)")
    span = float(t[-1] - t[0]) or 1.0
    judged = "; ".join(f"{t[a]:.2f}-{t[b - 1]:.2f} s ({100 * (t[b - 1] - t[a]) / span:.0f} %)" for a, b in index_runs(keep))
    line = f"judged: {len(index_runs(keep))} stretch(es) of at least {least:g} s (--min-stretch), each on its own: {judged}"
    if any(t[b - 1] - t[a] < least for a, b in index_runs(keep)):
        line = f"judged: none lasts {least:g} s (--min-stretch): the longest alone, {judged}"
    if short:
        line += (f"; left out, shorter: {len(short)} ("
                 + ", ".join(f"{t[a]:.2f}-{t[b - 1]:.2f} s" for a, b in short[:8]) + (" ..." if len(short) > 8 else "") + ")")
    return keep, line


def _say(lines: list[str], options) -> None:
    """Print each selection line once (``options.said`` remembers those printed)."""
    said = getattr(options, "said", None)
    for line in lines:
        if said is None or line not in said:
            print(f"selection: {line}", file=sys.stderr)
            if said is not None:
                said.add(line)
