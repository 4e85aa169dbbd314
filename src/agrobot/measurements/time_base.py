"""The time base of each file, checked before the files are joined: a clock that stepped inside a
file, a receiver's GPS week-number rollover, and the receiver's GPS time against UTC.

- Clock step (``clock_jump``): a file's rows come at a cadence h (the median step of its stamps).
  A stamp that steps back by more than 2 h while the rows after it go on at the cadence (the first
  and 80 % of the next 20: rows written late return to the old sequence at once, out of order, not
  a clock; one among them does not hide a step) is a step of the
  logger's clock; so is a stamp that leaps forward by more than max(5 h, 0.5 s) (from the latest
  stamp before it: the return to the sequence after a row written late is no leap) while the values
  change across it as they change over one row, not as over the time the stamps skip (a silence
  moves every signal on: the positions as far as the machine drives). Per numeric column, with
  d the change across the step, D1 and Dn its changes over one row and over the n rows the
  stamps skip, a column that moves over n rows (median Dn at least 3 median D1) says "one row"
  when d is within D1's 95 % and below Dn's 5 %, "a silence" when d is beyond D1's 99 %; the step
  is a clock's when more than twice as many columns say one row as say a silence (a column of a
  clock step says a silence by chance 1 %, one of a silence says one row under 5 %: one noisy
  column among several does not veto the others); where no column tells (a file of noise about a
  constant), a single leap forward is a clock's when the file starts with the recording's other
  files and its end overruns theirs by the leap (span_step: a silence ends with the others). The
  stamps after it are moved back by the step onto the clock the file starts on (named, with its
  size and moment).
- GPS week rollover (``gps_week_rollover``): a receiver with a 10-bit week counter dates its fixes
  1024 weeks (WEEK_ROLLOVER = 619,315,200 s) early once its epoch has passed. A file whose stamps
  are k x 1024 weeks (within a day) before the other files', and overlap them once moved, is moved
  by that much (named); a file alone whose last stamp is k x 1024 weeks before the time it was last
  written (its modification time; up to a year later, a copy) is named, not moved (the log's
  times from its start do not change).
- Leap seconds: GPS time runs ahead of UTC by the leap seconds since 1980 (``gps_minus_utc``, 18 s
  since 2017); an offset between a receiver's file and the others within 0.5 s of that count is
  named as GPS time against UTC (measurements.audit's clock offsets).
"""
from __future__ import annotations

import datetime
import math
from pathlib import Path

import numpy as np

from .findings import finding
from .streams import iso

WEEK_ROLLOVER = 1024 * 7 * 86400.0      # s: a 10-bit GPS week counter's period
DAY = 86400.0
# (first POSIX second it holds from, GPS - UTC [s]): IERS Bulletin C
LEAP_TABLE = ((915148800.0, 13.0), (1136073600.0, 14.0), (1230768000.0, 15.0), (1341100800.0, 16.0),
              (1435708800.0, 17.0), (1483228800.0, 18.0))
BACK_STEPS = 2.0        # cadences: a step back larger than this, the rows after it regular, is a clock step
AHEAD_STEPS, AHEAD_MIN = 5.0, 0.5      # cadences, s: a leap forward at least this large is judged
REGULAR_AFTER = 20      # rows after a step back that must come at the cadence ...
REGULAR_SHARE = 0.8     # ... this share of them, the first always
MOVES = 3.0             # a column informs when its change over the skipped rows is this many times its one-row change
LEAP_TOLERANCE = 0.5    # s: an offset between a receiver and another clock this close to the leap count is that count


def gps_minus_utc(posix: float) -> float:
    """GPS time - UTC [s] on that date (0 before 1999: not tabulated here)."""
    return next((s for start, s in reversed(LEAP_TABLE) if posix >= start), 0.0)


def leap_meaning(late: float, when: float) -> str:
    """The words for an offset of ``late`` s between a receiver and the other clocks when it is
    the GPS - UTC leap seconds of the date (within LEAP_TOLERANCE), else ''."""
    leap = gps_minus_utc(when)
    if leap and abs(abs(late) - leap) < LEAP_TOLERANCE:
        return (f"; {abs(late):.3f} s is GPS time against UTC ({leap:.0f} leap seconds on "
                f"{iso(when)[:10]}): one side's stamps are on GPS time, the other's on UTC")
    return ""


# --- clock steps inside one file ----------------------------------------------------------------------
def _cadence(t: np.ndarray) -> float:
    dt = np.diff(t)
    ahead = dt[dt > 0]
    return float(np.median(ahead)) if len(ahead) else math.nan


def _regular_after(t: np.ndarray, k: int, h: float) -> bool:
    """The rows after row k + 1 come at the cadence (within half a step): the first of them, and
    REGULAR_SHARE of the REGULAR_AFTER after it (a row written late among them does not hide the
    step; a row written late itself is followed at once by a leap back to the old sequence)."""
    dt = np.diff(t[k + 1:k + 2 + REGULAR_AFTER])
    at = np.abs(dt - h) <= 0.5 * h
    return len(dt) >= min(REGULAR_AFTER, 5) and bool(at[0]) and float(np.mean(at)) >= REGULAR_SHARE


def _votes(columns: list[np.ndarray], k: int, n: int) -> tuple[int, int]:
    """(columns saying one row, columns saying a silence) across rows k, k + 1 (module docstring)."""
    one, silence = 0, 0
    for x in columns:
        if not (np.isfinite(x[k]) and np.isfinite(x[k + 1])) or len(x) <= n + 10:
            continue
        d1 = np.abs(np.diff(x))
        dn = np.abs(x[n:] - x[:-n])
        d1, dn = d1[np.isfinite(d1)], dn[np.isfinite(dn)]
        if len(d1) < 20 or len(dn) < 20 or not np.median(dn) >= MOVES * max(float(np.median(d1)), 1e-300):
            continue
        d = abs(float(x[k + 1] - x[k]))
        if d > np.percentile(d1, 99):
            silence += 1
        elif d <= np.percentile(d1, 95) and d < np.percentile(dn, 5):
            one += 1
    return one, silence


def clock_steps(t: np.ndarray, columns: list[np.ndarray], label: str) -> tuple[np.ndarray, list[dict]]:
    """(stamps with each clock step undone, [{finding, at}]) of a file's stamps in file order and
    its numeric columns (module docstring); ``at`` the POSIX moment of each step."""
    t = np.asarray(t, float).copy()
    found: list[dict] = []
    h = _cadence(t[np.isfinite(t)]) if np.isfinite(t).sum() > 30 else math.nan
    if not h > 0 or not np.isfinite(t).all():
        return t, found
    for _ in range(5):
        dt = np.diff(t)
        back = np.flatnonzero(dt < -BACK_STEPS * h)
        latest = t[1:] - np.maximum.accumulate(t)[:-1]       # a row written late opens no leap: from the latest stamp
        ahead = np.flatnonzero((dt > max(AHEAD_STEPS * h, AHEAD_MIN)) & (latest > max(AHEAD_STEPS * h, AHEAD_MIN)))
        step = next((int(k) for k in back if _regular_after(t, int(k), h)), None)
        if step is None:
            for k in ahead:
                one, silence = _votes(columns, int(k), max(1, int(round(dt[k] / h))))
                if one > 2 * silence:
                    step = int(k)
                    break
        if step is None:
            break
        found.append(undo_step(t, step, h, label, "the values change across the step as over one row"))
    return t, found


def undo_step(t: np.ndarray, step: int, h: float, label: str, evidence: str) -> dict:
    """{finding, at} of the clock step between rows ``step`` and ``step`` + 1 of stamps ``t`` at
    cadence ``h``, the stamps after it moved back by it in place; ``evidence`` says why a clock's."""
    by = float(t[step + 1] - t[step] - h)
    at = float(t[step] + h)
    t[step + 1:] -= by
    return {"at": at, "finding": finding(
        "clock_jump", [label], by, None, "s",
        f"{label}: the logger's clock stepped {by:+.3f} s between rows {step + 1} and {step + 2} (stamps "
        f"{iso(at - h)} then {iso(at + by)}; the rows come every {h:.4g} s and {evidence}): the stamps after it "
        f"moved {-by:+.3f} s back onto the clock the file starts on", resolved=True)}


def span_step(t: np.ndarray, others: list[tuple[float, float]], tol: float) -> int | None:
    """The row after which a file's clock stepped forward, told by the other files of the recording
    (its columns too quiet to tell, clock_steps): its one leap forward (beyond max(AHEAD_STEPS h,
    AHEAD_MIN)) is the amount by which its last stamp overruns theirs, within ``tol``, while it
    starts with them and they agree with each other (a silence ends with the others; a clock that
    stepped carries the file's end on by the step). None otherwise."""
    if not others or len(t) < 30 or not np.isfinite(t).all():
        return None
    h = _cadence(t)
    dt = np.diff(t)
    ahead = np.flatnonzero(dt > max(AHEAD_STEPS * h, AHEAD_MIN))
    starts, ends = np.array(others).T
    if len(ahead) != 1 or np.ptp(starts) > tol or np.ptp(ends) > tol:
        return None
    k = int(ahead[0])
    over = float(t[-1] - np.median(ends))
    return k if abs(t[0] - np.median(starts)) <= tol and over > tol and abs(over - (dt[k] - h)) <= tol else None


# --- GPS week rollover -------------------------------------------------------------------------------
def rollover_between(spans: dict[str, tuple[float, float]]) -> dict[str, float]:
    """{file: seconds to add} for the files dated k x 1024 weeks (within a day) before the latest
    file's start and overlapping it once moved."""
    if len(spans) < 2:
        return {}
    ref = max(spans, key=lambda n: spans[n][0])
    lo, hi = spans[ref]
    out = {}
    for name, (a, b) in spans.items():
        k = round((lo - a) / WEEK_ROLLOVER)
        if name != ref and k >= 1 and abs(lo - a - k * WEEK_ROLLOVER) < DAY:
            move = k * WEEK_ROLLOVER
            if a + move < hi and b + move > lo:
                out[name] = move
    return out


def rollover_finding(label: str, move: float, start: float, against: str) -> dict:
    """The finding of a file moved by ``move`` (k x 1024 weeks) onto the others' dates."""
    k = round(move / WEEK_ROLLOVER)
    return finding("gps_week_rollover", [label], move, None, "s",
                   f"{label}: its dates ({iso(start)[:10]}) are {k * 1024} weeks ({move:.0f} s) before {against} "
                   f"({iso(start + move)[:10]}): a GPS week-number rollover (a receiver's 10-bit week counter); its "
                   f"stamps moved {move:.0f} s later onto the other files' dates (without it they share no time)",
                   resolved=True)


def rollover_by_written(path: Path, last: float, label: str) -> dict | None:
    """A finding when a file's last stamp is k x 1024 weeks before the time it was last written
    (up to a year later: a copy), else None (module docstring)."""
    try:
        written = path.stat().st_mtime
    except OSError:
        return None
    if not math.isfinite(last) or last < 1e8:
        return None
    k = math.floor((written - last + DAY) / WEEK_ROLLOVER)
    late = written - last - k * WEEK_ROLLOVER
    if k < 1 or not -DAY <= late <= 366 * DAY:
        return None
    when = datetime.datetime.fromtimestamp(written, datetime.timezone.utc).strftime("%Y-%m-%d")
    return finding("gps_week_rollover", [label], k * WEEK_ROLLOVER, None, "s",
                   f"{label}: its fixes are dated {iso(last)[:10]}, {k * 1024} weeks ({k * WEEK_ROLLOVER:.0f} s) and "
                   f"{late / DAY:.0f} days before the file was last written ({when}): a GPS week-number rollover (a "
                   f"receiver's 10-bit week counter) is the likely cause; the log's times from its start are "
                   f"unaffected, its dates are {k * WEEK_ROLLOVER:.0f} s early", resolved=True)
