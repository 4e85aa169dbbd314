"""What each channel carries: its own updates, not the rows it is written in.

A logger that writes every channel on every row holds a slower channel's last value until it
updates (a 5 Hz heading in 20 Hz rows repeats each value about four times). Judged on its rows such
a channel looks 20 Hz, its noise looks smaller than it is, and a rate or a speed derived from it is
a spike at each update and zero between. The rule, on each channel's own samples (the receiver's
fixes as one channel: a fix updates when its latitude or longitude changes):

- an **update** is a sample whose value differs from the one before (exactly: a held value is a copy;
  a measured value with noise never repeats exactly);
- the channel is **held** when at least HELD_SHARE of its row steps are exact repeats, the median
  interval between updates is at least REGULAR row periods, at least REGULAR_SHARE of the intervals
  lie within half that period and a row of it (a sensor's rate, not a state that switches now and
  then), and its changes are not single steps of
  a grid (a quantised signal that moves slowly also repeats, but changes by one quantum at a time:
  the median change is then within SINGLE_STEP quanta; measurements.log.resolution finds the quantum);
  its update period P is the median interval between updates, ``held`` = P / the row period;
- a channel whose updates are not a whole number of rows apart (18.5 Hz in 25 Hz rows: one, then
  two rows, with jitter) or read at irregular times (polled in turn with others) is held too when
  at least HELD_SHARE of its row steps repeat and its repeats are copies, i.e. neither its grid nor
  chance explains them: its changes are not single steps of its grid (above), and after a change
  its value comes back to the one before less than RETURN_SHARE as often as a row repeats (noise on
  a grid meets a value again by chance about as often as it repeats) but at least NOISY as often,
  or, for a value that never returns, fewer than REVISITED of its changes land on a value it held
  before (off any grid a continuous value repeats exactly only as a copy; a noise-free signal on a
  grid, a quantised steering on a straight, comes back to its levels and may genuinely stand: not
  held, also where resolution() does not see the grid because some values lie between its levels);
  and it updates at least every POLLED rows on average (a state holds for many); its P is then the
  mean interval between updates (its rate the number of its changes over their span: what its
  values carry);
- a channel that repeats at least HELD_SHARE of its rows in single steps of its grid (a speed at a
  cruise) is not held, and the report says so with its grid (genuine_repeats);
- a run of repeats longer than STILL x P is no hold: while the machine stands (the speed ``v``,
  else the track, under STANDING m/s) it is a value that stays put and is kept every P (a measured
  constant, not a gap); for the positions, while the machine moves, it is a stale value (a dropped
  update: moving positions change) and only its first row is kept, so that the silence is a gap the
  audit names; any other channel (a speed at a cruise, a yaw rate on a straight) is kept every P;
- a held channel is replaced by its updates: each value once, at the middle between the last row
  that still holds the old value and the first that holds the new one (the update happened between
  them; the first row alone would make every update up to a row late, and a rate from such times
  spiky; the first row's held value, of an unknown age, is left out); where those times fit a regular clock (the sensor's: a receiver's epochs, a heading's
  fixed rate) within the rows' own jitter (residual std at most CLOCK_FIT rows after a running mean
  over CLOCK_WINDOW updates of a line through the update numbers, each the time since the first
  in periods, rounded), they are put on it, but for two updates that fall in one of its periods
  (they keep their own times: one clock slot would give them one time, a rate between them
  infinite). So
  every quantity the audit and the log derive from it (the track's speed and course, a rate from a
  heading, a noise level, a cross-correlation) is computed on them. Set-points (a command, held by
  nature) keep their rows; their update rate is still reported.

A sum of signals (``--signal v=0.25*(FL + FR + RL + RR)``, measurements.signal_expressions) changes
whenever any of its terms does, each change a part of an update: four wheel speeds held at 3 Hz
in 10 Hz messages make a mean that changes at 7 Hz. Combining sensors samples no faster than the
fastest of them, so a sum's rate is its fastest term's: that term's changes over the span they
share (standing time included, as a reference that reads one wheel counts it), per sample of the
sum (``term_share``; read where the expression is evaluated, where the terms' own samples are
known, and kept in report["sums"]), times the sum's sample rate, where its
fastest term repeats at least HELD_SHARE of the sum's samples and that is slower than the sum's own
changes. The sum's samples are judged as any channel's: replaced by its changes where its own
repeats are copies (terms held in the same rows), else kept (each change a part of an update). A
mean computed before the recording (one column) is judged on its own changes only.

A heading (``MUST_CHANGE``) that never changes while the course of the fixes turns by more than
TURNED rad is refused, and so is a recording in which
no channel changes at all: the error names the file, each channel with the value it holds, and
whether the vehicle stands (a speed below STANDING, positions that stay put) or a value was held.
"""
from __future__ import annotations

import math

import numpy as np

from .direction import course
from .log import COLUMNS, LogError, resolution
from .streams import Streams

HELD_SHARE = 0.2        # at least this share of row steps repeat exactly: the channel may be held (a hold of
                        # 1.25 rows on average repeats one row in five)
REGULAR = 1.5           # the median update interval at least this many row periods
REGULAR_SHARE = 0.6     # ... and this share of the intervals within half a period and a row of it
SINGLE_STEP = 1.5       # quanta: a median change up to this is a grid's single step (a slow signal on a grid)
STILL = 2.0             # a run of repeats longer than this many update periods is no hold
STANDING = 0.1          # m/s: below this the machine stands
CLOCK_WINDOW = 51       # updates: a sensor clock's drift is followed over this many
CLOCK_FIT = 0.6         # rows: the residual std of update times that fit a regular clock
MIN_SAMPLES = 20
RETURN_SHARE = 0.5      # an irregular hold's value returns after a change less than this share of its repeats
NOISY = 0.01            # ... and at least this often: noise on a grid tells its copies; a value that never returns
REVISITED = 0.1         # ... is held only when fewer than this share of its changes land on a value it had before:
                        # off any grid (a continuous value stands exactly only as a copy); a noise-free signal
                        # on a grid (a quantised steering) comes back to its levels, and its stands are genuine
POLLED = 4.0            # rows: a channel held at irregular intervals updates at least this often on average
TURNED = math.radians(30.0)   # rad: a course that turns this much turns any heading
SUM_SAID = ("a sum of signals: its rate is its fastest term's changes (combining sensors samples no faster than "
            "the fastest of them); ")
ROWS_KEPT = "its samples are kept, each change a part of an update"
MUST_CHANGE = {"heading": "a heading that changes as the machine turns (a dual-antenna or an INS heading: its "
                          "noise alone changes it)"}


def changed(values: np.ndarray) -> np.ndarray:
    """True at each sample whose value (any column of a 2-D array) differs from the one before
    (the first sample counts as an update)."""
    x = np.asarray(values, float).reshape(len(values), -1)
    out = np.ones(len(x), bool)
    out[1:] = np.any(x[1:] != x[:-1], axis=1) & ~np.all(np.isnan(x[1:]) & np.isnan(x[:-1]), axis=1)
    return out


def term_share(terms: list[np.ndarray], samples: int) -> float:
    """The changes of the fastest of a sum's ``terms`` (each its own samples within the span the
    sum covers) per sample of the sum (``samples`` of them): its rate over the sum's rows (module
    docstring)."""
    if samples < 2:
        return 1.0
    return max(float(changed(x)[1:].sum()) for x in terms) / (samples - 1)


def genuine_repeats(name: str, t: np.ndarray, values: np.ndarray) -> str | None:
    """What is said of a channel that repeats at least HELD_SHARE of its rows but moves in single
    steps of its grid (a slow or constant value on a grid: a speed at a cruise, a steering on a
    straight): its repeats are genuine, it is not held and its rate is its rows'; None otherwise."""
    x = np.asarray(values, float)
    if len(x) < MIN_SAMPLES or x.ndim != 1:
        return None
    change = changed(x)
    share = 1.0 - float(change[1:].mean())
    if share < HELD_SHARE or change.sum() < 5 or not _single_steps(x, change):
        return None
    return (f"{name}: {share:.0%} of its rows repeat its value, but it moves in single steps of its "
            f"{resolution(x):.3g} grid: a slow or constant value on a grid, its repeats genuine, not held (its rate is "
            f"its rows'; a median change above {SINGLE_STEP:g} steps would make them copies)")


def _single_steps(x: np.ndarray, change: np.ndarray) -> bool:
    """Whether a column moves one quantum at a time (a slow signal on a grid, not a held one)."""
    x = np.asarray(x, float)
    q = resolution(x)
    steps = np.abs(np.diff(x[change]))
    steps = steps[np.isfinite(steps) & (steps > 0)]
    return q > 0 and len(steps) > 0 and float(np.median(steps)) <= SINGLE_STEP * q


def holding(t: np.ndarray, values: np.ndarray, moving=None) -> dict | None:
    """{rows_hz, updates_hz, held, keep (indices of the samples kept), times (theirs: an update's
    between its row and the one before), stale (runs dropped)} of a
    held channel (module docstring), or None when it is not held. ``moving(times) -> bool``: the
    machine moves at those times (None: it is taken as standing in a long run)."""
    t = np.asarray(t, float)
    x = np.asarray(values, float).reshape(len(t), -1)
    if len(t) < MIN_SAMPLES:
        return None
    change = changed(x)
    if 1.0 - change[1:].mean() < HELD_SHARE or change.sum() < 5:
        return None
    dt = np.diff(t)
    row = float(np.median(dt[dt > 0])) if (dt > 0).any() else math.nan
    at = np.flatnonzero(change)
    intervals = np.diff(t[at])
    period = float(np.median(intervals))
    if not row > 0 or any(_single_steps(x[:, k], change) for k in range(x.shape[1])):
        return None
    if period < REGULAR * row or np.mean(np.abs(intervals - period) <= 0.5 * period + row) < REGULAR_SHARE:
        period = _polled_period(t, x, change, row)
        if period is None:
            return None                 # changes at irregular times: a state or an event, not a sampled hold
    keep, stale = _kept(t, at, period, row, moving)
    times = t[keep].copy()
    first = np.isin(keep, at) & (keep > 0)
    times[first] = regular_times(0.5 * (t[keep[first] - 1] + t[keep[first]]), period, row)
    ahead = times > np.maximum.accumulate(np.concatenate([[-np.inf], times[:-1]]))   # increasing, always
    keep, times = keep[ahead], times[ahead]
    return {"rows_hz": 1.0 / row, "updates_hz": 1.0 / period, "held": period / row, "keep": keep, "times": times,
            "stale": stale}


def _kept(t: np.ndarray, at: np.ndarray, period: float, row: float, moving=None) -> tuple[np.ndarray, int]:
    """(the rows kept of a channel held every ``period`` whose values change at rows ``at``: each
    change's row, and in a run of repeats longer than STILL x period one row every period where the
    machine stands (``moving`` None: taken as standing), the runs dropped as stale while it moves)."""
    keep, stale = [], 0
    ends = np.append(at[1:], len(t))
    every = max(1, int(round(period / row)))
    for a, b in zip(at, ends):
        short = t[b - 1] - t[a] <= STILL * period
        if a > 0 or not short:          # the first row's value is of an unknown age: not an update seen
            keep.append(a)
        if short:
            continue
        if moving is not None and np.mean(moving(t[a:b])) > 0.5:
            stale += 1
            continue
        keep.extend(range(a + every, b, every))
    return np.array(keep, int), stale


def counter_updates(t: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, str]:
    """(the rows a counter is differenced over, what was done): a counter read in rows faster than
    it updates (at least HELD_SHARE of its row steps repeat) is differenced over its updates, the
    rows where its count changes, P apart (the median interval between them), with one row every P
    in a run of repeats longer than STILL x P (the machine stands: a rate of 0 there); its rows
    otherwise. Differenced row by row, a count held for k rows gives k - 1 rates of 0 and one k times
    the true rate."""
    t = np.asarray(t, float)
    x = np.asarray(values, float).reshape(len(t), -1)
    change = changed(x)
    at = np.flatnonzero(change[1:]) + 1
    if len(t) < MIN_SAMPLES or 1.0 - change[1:].mean() < HELD_SHARE or len(at) < 5:
        return np.arange(len(t)), "differenced row by row"
    dt = np.diff(t)
    row = float(np.median(dt[dt > 0]))
    period = float(np.median(np.diff(t[at])))
    keep, _ = _kept(t, np.r_[0, at], period, row)
    return keep, (f"held in its rows ({1.0 - change[1:].mean():.0%} repeat): differenced over its updates, "
                  f"{period:.3g} s apart, not its rows (row by row would give rates of 0 between bursts)")


def _polled_period(t: np.ndarray, x: np.ndarray, change: np.ndarray, row: float) -> float | None:
    """The mean interval between the updates of a channel held at irregular intervals (a hold that
    is not a whole number of rows, with jitter; a value polled in turn with others, an OBD request
    answered when the bus allows), or None when its repeats are not copies. Its repeats are copies
    when, after a change, the value comes back to the one before it (x[i+2] = x[i] where x[i+1]
    differs) less than RETURN_SHARE as often as a row repeats (a signal that meets a value again by
    chance, noise on a grid, returns about as often as it repeats; single steps of a grid are
    refused before) but at least NOISY of the time, or, where it never returns (no noise on a grid
    to tell a copy by), when fewer than REVISITED of its changes land on a value it held before
    (_revisited: off any grid a continuous value repeats exactly only as a copy; a noise-free
    signal on a grid, a quantised steering, comes back to its levels and may stand); and it updates at least every POLLED rows on average (a state or an event holds for
    many rows), and the rows between its first and last change repeat HELD_SHARE of the time too. The mean interval is the span of the changes over their number: a channel's rate is
    that of the values it carries."""
    same = np.all(x[2:] == x[:-2], axis=1)
    after = change[1:-1]
    if after.sum() < MIN_SAMPLES:
        return None
    repeats, returns = 1.0 - change[1:].mean(), float(np.mean(same[after]))
    if returns > RETURN_SHARE * repeats:
        return None                     # a value met again by chance: its repeats are not copies
    if returns < NOISY and _revisited(x, change) >= REVISITED:
        return None                     # a noise-free signal on a grid: its repeats may be stands
    at = np.flatnonzero(change)
    period = float(t[at[-1]] - t[at[0]]) / (len(at) - 1)
    return period if row / (1.0 - HELD_SHARE) <= period <= POLLED * row else None


def _revisited(x: np.ndarray, change: np.ndarray) -> float:
    """The share of a channel's changes that land on a value (row) it held before: about 0 off any
    grid, a large share for a signal on a grid, seen or not by resolution() (levels met again)."""
    values = x[change]
    return 1.0 - len(np.unique(values, axis=0)) / len(values)


def regular_times(tm: np.ndarray, period: float, row: float) -> np.ndarray:
    """Update times ``tm`` (known to a row) on the sensor's regular clock where they fit one
    (module docstring), else as they are."""
    if len(tm) < 2 * CLOCK_WINDOW:
        return tm
    slope, offset = period, float(tm[0])
    for _ in range(3):                  # the update numbers, then the clock's period refined on them
        n = np.round((tm - offset) / slope)
        slope, offset = np.polyfit(n, tm, 1)
    r = tm - (offset + slope * n)
    pad = np.pad(r, CLOCK_WINDOW // 2, mode="edge")
    drift = np.convolve(pad, np.ones(CLOCK_WINDOW) / CLOCK_WINDOW, "valid")
    if float(np.std(r - drift)) > CLOCK_FIT * row:
        return tm
    shared = np.zeros(len(n), bool)         # two updates in one of the clock's slots: each keeps its own time
    shared[1:] |= np.diff(n) == 0
    shared[:-1] |= np.diff(n) == 0
    return np.where(shared, tm, offset + slope * n + drift)


def _motion(streams: Streams):
    """moving(times) from the speed v, else None (the track is judged after its own updates)."""
    if "v" in streams.signals and len(streams.signals["v"][0]) > 1:
        tv, v = streams.signals["v"]
        return lambda times: np.abs(np.interp(times, tv, v)) > STANDING
    return None


def _turned(streams: Streams) -> float:
    """How far the course of the fixes turns over the recording [rad] (0 without fixes)."""
    if streams.gnss is None or len(streams.gnss) < MIN_SAMPLES:
        return 0.0
    c = course(streams.gnss)[1]
    c = np.unwrap(c[np.isfinite(c)])
    return float(np.ptp(c)) if len(c) else 0.0


def _refuse_constant(streams: Streams, source) -> None:
    """A LogError for a recording in which nothing changes, or a MUST_CHANGE channel that never does."""
    series = {c: x for c, (_, x) in streams.signals.items() if len(x) >= MIN_SAMPLES}
    if streams.gnss is not None and len(streams.gnss) >= MIN_SAMPLES:
        series["gnss"] = streams.gnss[["lat", "lon"]].to_numpy(float)
    constant = {c for c, x in series.items() if changed(x).sum() == 1}
    labels = streams.report.get("columns", {})

    def named(c):
        return "the positions (lat, lon)" if c == "gnss" else f"{c} ({labels.get(c, c)})"
    if series and constant == set(series):
        raise LogError(f"{source}: no channel changes: " + _standing(streams, series, named)
                       + "; expected measurements that change as the machine drives")
    for c in sorted(c for c in constant & set(MUST_CHANGE) if _turned(streams) > TURNED):
        x = np.asarray(series[c], float).reshape(len(series[c]), -1)[0]
        raise LogError(f"{source}: channel {named(c)} never updates: all {len(series[c])} samples hold "
                       f"{', '.join(f'{v:g}' for v in x)} while other channels change; expected {MUST_CHANGE[c]}: "
                       f"map the channel that carries it (--signal {c if c != 'gnss' else 'lat'}=TABLE.COLUMN) or "
                       f"leave it out")


def _standing(streams: Streams, series: dict, named) -> str:
    """What a recording whose every channel holds one value says: each channel's value (SI, its
    unit), its span, and whether the vehicle moves (a speed below STANDING, or positions that stay
    put, say it stands; a constant speed above it is a value held, not a measurement)."""
    times = [t for t, _ in streams.signals.values() if len(t)]
    if streams.gnss is not None and len(streams.gnss):
        times.append(streams.gnss["utc"].to_numpy(float))
    span = max(float(t[-1]) for t in times) - min(float(t[0]) for t in times) if times else 0.0
    values = []
    for c in sorted(series):
        x = np.asarray(series[c], float).reshape(len(series[c]), -1)[0]
        unit = COLUMNS.get(c, ("", ""))[0] if c != "gnss" else "deg"
        values.append(f"{named(c)} holds {', '.join(f'{v:g}' for v in x)}{f' {unit}' if unit else ''}")
    speeds = [float(np.asarray(series[c], float).ravel()[0]) for c in ("v", "gnss_speed") if c in series]
    still = "gnss" in series or (speeds and all(abs(v) < STANDING for v in speeds))
    moving = [v for v in speeds if abs(v) >= STANDING]
    said = ("the vehicle does not move in the recording (a speed below "
            f"{STANDING:g} m/s{' and positions that stay put' if 'gnss' in series else ''}): nothing in it to identify "
            "or judge" if still and not moving else
            f"a speed of {moving[0]:g} m/s that never changes is a value held (a sender or a logger not updating), "
            "not a measurement" if moving else "nothing in it changes: no drive to judge")
    return f"over its {span:.0f} s " + "; ".join(values) + f" throughout: {said}"


def keep_updates(streams: Streams, source) -> list[dict]:
    """Every held channel of ``streams`` replaced by its updates, in place (module docstring); the
    notes per channel: {channel, rows_hz, updates_hz, held, stale} (also streams.report["updates"])."""
    _refuse_constant(streams, source)
    notes = []
    moving = _motion(streams)
    if streams.gnss is not None:
        g = streams.gnss
        found = holding(g["utc"].to_numpy(float), g[["lat", "lon"]].to_numpy(float), moving)
        if found is not None:
            g = _heading_apart(streams, g, found["keep"])
            streams.gnss = g.iloc[found["keep"]].reset_index(drop=True).assign(utc=found["times"])
            notes.append({"channel": "gnss", **_said(found)})
        notes += _receiver_heading(streams)
    sums = _sums(streams)
    for c, (t, x) in list(streams.signals.items()):
        # a speed, a rate or an angle may stay put while the machine moves (a cruise, a straight):
        # only positions must change then, so only theirs are judged stale
        found = holding(t, x, None)
        if found is None and c in sums:
            notes.append(sums[c])
        if found is None:
            genuine = None if c in sums or c in streams.held else genuine_repeats(c, t, x)
            if genuine:
                streams.report.setdefault("quirks", []).append(genuine)
            continue
        if c not in streams.held:
            streams.signals[c] = (found["times"], x[found["keep"]])
        notes.append(_as_sum({"channel": c, **_said(found), "set_point": c in streams.held}, sums.get(c)))
    if notes:
        streams.report["updates"] = {n["channel"]: {k: v for k, v in n.items() if k != "channel"} for n in notes}
        streams.report.setdefault("quirks", []).extend(note_text(n) for n in notes)
    return notes


def _as_sum(note: dict, term: dict | None) -> dict:
    """A held channel's note, at its fastest term's rate where it is a sum of signals that samples
    slower than its own changes (module docstring)."""
    if term is None or term["updates_hz"] >= note["updates_hz"]:
        return note
    return {**note, "updates_hz": term["updates_hz"], "held": note["rows_hz"] / term["updates_hz"], "sum": True}


def _sums(streams: Streams) -> dict[str, dict]:
    """Column -> the note of each sum of signals whose fastest term repeats at least HELD_SHARE of
    the sum's samples (report["sums"]: term_share): its rate is that term's (module docstring)."""
    notes = {}
    for c, share in (streams.report.get("sums") or {}).items():
        if c not in streams.signals or c in streams.held or share > 1.0 - HELD_SHARE or share <= 0:
            continue
        t = np.asarray(streams.signals[c][0], float)
        if len(t) < MIN_SAMPLES or not t[-1] > t[0]:
            continue
        rows = (len(t) - 1) / float(t[-1] - t[0])
        notes[c] = {"channel": c, "rows_hz": rows, "updates_hz": rows * share, "held": 1.0 / share, "stale": 0,
                    "set_point": False, "sum": True, "rows_kept": True}
    return notes


def _heading_apart(streams: Streams, g, keep: np.ndarray):
    """The receiver's frame with its own heading (HDT, THS) taken out as a channel of its own, on
    its epochs' stamps and the receiver's clock, where the positions' updates ``keep`` would drop
    some of its samples (a 10 Hz heading beside 5 Hz positions is judged at 10 Hz); else ``g``."""
    if "heading" not in g or "heading" in streams.signals:
        return g
    h = g["heading"].to_numpy(float)
    ok = np.isfinite(h)
    dropped = ok.copy()
    dropped[keep] = False
    if ok.sum() < MIN_SAMPLES or not dropped.any():
        return g
    streams.signals["heading"] = (g["utc"].to_numpy(float)[ok], h[ok])
    streams.groups["heading"] = streams.groups.get("gnss", "gnss")
    columns = streams.report.setdefault("columns", {})
    columns["heading"] = "the receiver's own heading (ENU yaw), on its epochs: a channel apart from its held positions"
    return g.assign(heading=np.nan)


def _receiver_heading(streams: Streams) -> list[dict]:
    """The receiver's own heading (HDT, THS) held in its epochs: kept at its updates only (NaN
    between them, where the epochs repeat it)."""
    g = streams.gnss
    h = g["heading"].to_numpy(float) if "heading" in g else np.zeros(0)
    ok = np.flatnonzero(np.isfinite(h))
    found = holding(g["utc"].to_numpy(float)[ok], h[ok], None) if len(ok) >= MIN_SAMPLES else None
    if found is None:
        return []
    kept = np.full(len(h), np.nan)
    kept[ok[found["keep"]]] = h[ok[found["keep"]]]
    streams.gnss = g.assign(heading=kept)
    return [{"channel": "heading", **_said(found)}]


def _said(found: dict) -> dict:
    return {k: v for k, v in found.items() if k not in ("keep", "times")}


def note_text(n: dict) -> str:
    """One held channel as the report says it."""
    what = "the positions" if n["channel"] == "gnss" else n["channel"]
    text = (f"{what}: {n['updates_hz']:.3g} Hz updates in {n['rows_hz']:.3g} Hz rows (held x{n['held']:.2g}): "
            + ("a set-point, kept as held" if n.get("set_point") else
               (SUM_SAID if n.get("sum") else "") + (ROWS_KEPT if n.get("rows_kept") else "judged and logged on its updates")))
    if n.get("stale"):
        text += f"; {n['stale']} value(s) held longer than {STILL:g} updates while moving dropped (a gap)"
    return text
