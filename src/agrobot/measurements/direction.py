"""Which way the machine moves: the sign of its speed checked against the course.

The course is the direction of motion, read from the receiver's fixes (on their own updates,
measurements.channel_updates): the chord of the fixes CHORD s either side, where the track moves
faster than MOVING m/s. Driving forward the course is the heading (plus a fixed mounting offset);
reversing it is the heading + pi. The evidence, the first available of:

1. a declared direction channel (``--signal direction=...`` or ``gear=...``): negative = reversing;
2. a heading (``heading``, else the receiver's own, any convention): its sense (clockwise or not) is the one whose rate follows
   the course rate (by the ranks' correlation); the offset between the course and the heading takes two values pi apart (the
   axis of the doubled angles), and forward is the one the machine keeps longer (a machine drives
   forward more than it reverses); a sample is forward within AGREE of it, reversing within AGREE
   of the other;
3. the steering (``delta``, else ``delta_cmd``): the course turns the way the wheels steer forward and
   the other way reversing (r = v tan(delta) / L with v < 0), the majority sign again forward;
   read where |delta| > STEERED rad and the course turns faster than TURNING rad/s, each vote
   weighed by |course rate x delta| against its median (at most 1): a vote where the wheels
   barely steer or the course barely turns counts less.

A machine changes direction only through a stop: each moving stretch between stops is judged
whole by its evidence's majority (a lag between the steering and the course, a noisy heading, do
not cut a drive into pieces), and named reversing when at least REVERSE_MIN s long. The speed ``v`` (else the receiver's) is then judged there: signed
when it is negative on most of them; otherwise it is unsigned and never passes as forward driving:
the import is refused, naming the stretches and the remedy, unless ``--sign-speed`` asks to make it
negative there (printed, with the stretches).
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

from .findings import finding
from .log import LogError
from .position_source import MAD_NORMAL, white_noise_sigma

CHORD = 0.25            # s: the course from the fixes this far either side (at least)
CHORD_NOISE = 8.0       # a chord at least this many position sigmas long: the course within ~10 deg
DIRECTION_NOISE = 4.0   # ... and for the direction alone (two values pi apart, told within AGREE): within ~20 deg
NOISE_WINDOW = 41       # fixes: the position noise is read over this many
MOVING = 0.2            # m/s: the course is read above this track speed
AGREE = math.radians(45.0)
STEERED, TURNING = 0.05, 0.05
RATE_CHORD = 0.5        # s: the course rate over chords this far either side
REVERSE_SHARE = 0.5     # a stretch reverses when its votes' net share is below -this (75 % reversing)
REVERSE_MIN = 1.0       # s: a shorter stretch of reversing evidence is not named
STOP = 0.1              # m/s: a reversing stretch is signed out to where the speed falls below this
SIGNED_SHARE = 0.8      # the speed is signed when negative on this share of the reversing samples
SCALE = 2.0             # a heading's rate within this factor of the course's (a gyro in deg/s is not one)
AXIS_WINDOW = 30        # s: the course-heading axis is read over this window (a drifting heading)
STILL, STILL_SAMPLES = 0.05, 20    # m/s, samples: a gyro's bias read at standstill
FLIP_STOP, FLIP_SPAN = 3.0, 0.5     # s: a stop at most this long; the course this long either side of it
RUN_MIN, RUN_VOTES = 2.0, 5     # s, votes: a run of reversing evidence alone inside a forward stretch (the
                                # duration decides above 2.5 Hz fixes; 5 votes, as a stretch needs, below)


def course(gnss, sigmas: float = CHORD_NOISE) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t, course [rad, ENU], track speed [m/s]) on the fixes' own updates (a held fix is not a new
    one); course NaN where the track moves slower than MOVING. The chord is CHORD s either side,
    lengthened (x2, x4, x8) where the positions' local noise sigma would turn it by more than
    about 10 deg: a chord shorter than ``sigmas`` sigma is not read (CHORD_NOISE: a DGPS fix at
    mower speed; DIRECTION_NOISE where only forward or backward is asked)."""
    t = gnss["utc"].to_numpy(float)
    lat, lon = gnss["lat"].to_numpy(float), gnss["lon"].to_numpy(float)
    new = np.r_[True, (np.diff(lat) != 0) | (np.diff(lon) != 0)]
    t, lat, lon = t[new], lat[new], lon[new]
    north = np.radians(lat - lat[0]) * 6.371e6
    east = np.radians(lon - lon[0]) * 6.371e6 * math.cos(math.radians(float(lat[0])))
    h = float(np.median(np.diff(t))) if len(t) > 1 else math.nan
    k0 = max(1, int(round(CHORD / h))) if h > 0 else 1
    c, speed = np.full(len(t), np.nan), np.zeros(len(t))
    if len(t) <= 2 * k0 + 2:
        return t, c, speed
    need = sigmas * position_noise(east, north)
    todo = np.ones(len(t), bool)
    for k in (k0, 2 * k0, 4 * k0, 8 * k0):
        if len(t) <= 2 * k + 2:
            break
        de, dn, dt = east[2 * k:] - east[:-2 * k], north[2 * k:] - north[:-2 * k], t[2 * k:] - t[:-2 * k]
        span = np.hypot(de, dn)
        take = np.zeros(len(t), bool)
        take[k:-k] = todo[k:-k] & (span >= need[k:-k])
        speed[take] = (span / np.maximum(dt, 1e-6))[take[k:-k]]
        c[take] = np.arctan2(dn, de)[take[k:-k]]
        todo &= ~take
    c[speed < MOVING] = np.nan
    return t, c, speed


def position_noise(east: np.ndarray, north: np.ndarray) -> np.ndarray:
    """Each fix's local position noise sigma [m]: the running median (NOISE_WINDOW fixes) of the
    second differences' size, / MAD_NORMAL / sqrt(6) (a second difference of white noise has variance 6 sigma^2; a
    smooth drive adds a h^2, which the median of a few fixes ignores only in part: an upper bound)."""
    d2 = np.hypot(np.diff(east, 2), np.diff(north, 2)) / math.sqrt(2.0)
    d2 = np.r_[d2[:1], d2, d2[-1:]] if len(d2) else np.zeros(len(east))
    local = pd.Series(d2).rolling(NOISE_WINDOW, center=True, min_periods=1).median().to_numpy()
    return white_noise_sigma(local / MAD_NORMAL)


def _wrap(x):
    return np.angle(np.exp(1j * np.asarray(x, float)))


def chord_steps(h: float, span: float) -> int:
    """Samples either side of a chord ``span`` s long at a sample interval h (at least one)."""
    return max(1, int(round(span / h))) if h > 0 else 1


def angle_rate(t: np.ndarray, angle: np.ndarray, span: float = RATE_CHORD) -> np.ndarray:
    """d(angle)/dt of a possibly interrupted angle by chords of ``span`` s either side (NaN where
    the angle is, and across its interruptions: the course is not read at a stop)."""
    out = np.full(len(t), np.nan)
    ok = np.isfinite(angle)
    if ok.sum() > 3:
        idx = np.flatnonzero(ok)
        k = chord_steps(float(np.median(np.diff(t))), span)
        u = np.unwrap(angle[idx])
        i = np.arange(len(idx))
        lo, hi = np.clip(i - k, 0, len(idx) - 1), np.clip(i + k, 0, len(idx) - 1)
        span = t[idx[hi]] - t[idx[lo]]
        whole = (idx[hi] - idx[lo] == hi - lo) & (span > 0)         # no interruption inside the chord
        out[idx[whole]] = (u[hi] - u[lo])[whole] / span[whole]
    return out


def rank_correlation(a: np.ndarray, b: np.ndarray) -> float:
    """Spearman's correlation (of the ranks): a course rate's spikes where the course flips at a
    turnaround or a stop do not outweigh the rest. Tied values take the mean of the ranks they span
    (a command or a deadbanded gyro exactly 0 through a stop: ranks handed out in sample order would
    correlate the ties' order in time, not their values)."""
    return float(np.corrcoef(mean_ranks(a), mean_ranks(b))[0, 1])


def mean_ranks(x: np.ndarray) -> np.ndarray:
    """The ranks of x (1 to n), each run of equal values given the mean of the ranks it spans."""
    _, where, count = np.unique(np.asarray(x), return_inverse=True, return_counts=True)
    return (np.cumsum(count) - (count - 1) / 2.0)[where.ravel()]


def by_heading(t, c, rate, heading, what: str = "the heading") -> tuple[np.ndarray, str] | None:
    """Evidence (+1 forward, -1 reversing, 0 none) from a heading (module docstring), or None when
    its rate does not follow the course's: in rank, and in size within SCALE where both turn (a
    heading that never turns while the course does, a gyro written 57.3 times too small, fails: it
    tells no U-turn from a reversal). Both rates are read on the same chords (angle_rate)."""
    th, h = heading
    inside = (t >= th[0]) & (t <= th[-1]) & np.isfinite(c)
    if inside.sum() < 20:
        return None
    hu = np.interp(t, th, np.unwrap(h))
    hr = angle_rate(t, hu)          # on the course rate's chords: a 20 Hz heading's noise not differentiated per step
    ok = inside & np.isfinite(rate) & np.isfinite(hr)
    if ok.sum() < 20 or np.std(rate[ok]) == 0 or np.std(hr[ok]) == 0:
        return None
    sense = rank_correlation(rate[ok], hr[ok])
    turning = ok & (np.abs(rate) > TURNING) & (np.abs(hr) > TURNING)
    course_turns = int(np.sum(ok & (np.abs(rate) > TURNING))) >= 20
    size = float(np.median(np.abs(rate[turning] / hr[turning]))) if turning.sum() >= 20 else \
        (math.inf if course_turns else 1.0)     # the course turns, the heading never does
    if not abs(sense) > 0.3 or not 1 / SCALE <= size <= SCALE:
        return None
    diff = _wrap(c - math.copysign(1.0, sense) * hu)
    axis = local_axis(t, diff, inside)
    near = np.abs(_wrap(diff - axis)) < math.pi / 2
    forward = axis if near[inside].mean() >= 0.5 else axis + math.pi
    off = np.abs(_wrap(diff - forward))
    e = np.where(off < AGREE, 1, np.where(off > math.pi - AGREE, -1, 0))
    return np.where(inside, e, 0), (f"the course against {what} (offset {math.degrees(float(np.median(_wrap(forward[inside])))):.0f}"
                                    f" deg, {'same' if sense > 0 else 'opposite'} sense)")


def local_axis(t: np.ndarray, diff: np.ndarray, inside: np.ndarray) -> np.ndarray:
    """The axis of the course less the heading [rad], per fix: half the angle of the mean of
    exp(2i diff) over AXIS_WINDOW s around it (doubled, a reversal's pi vanishes; local, a drifting
    heading, such as an integrated gyro's, is followed), unwrapped over time."""
    z = pd.Series(np.where(inside, np.exp(2j * diff), np.nan + 0j))
    when = pd.to_datetime(t - t[0], unit="s")
    re = pd.Series(z.to_numpy().real, index=when).rolling(f"{AXIS_WINDOW}s", center=True, min_periods=1).mean()
    im = pd.Series(z.to_numpy().imag, index=when).rolling(f"{AXIS_WINDOW}s", center=True, min_periods=1).mean()
    doubled = np.angle(re.to_numpy() + 1j * im.to_numpy())
    ok = np.isfinite(doubled)
    out = np.zeros(len(t))
    if ok.any():
        out[ok] = 0.5 * np.unwrap(doubled[ok])
        out = np.interp(np.arange(len(t)), np.flatnonzero(ok), out[ok])
    return out


def gyro_heading(streams) -> tuple[np.ndarray, np.ndarray] | None:
    """(t, the yaw rate integrated [rad]) of a gyro: its bias the median yaw rate at standstill
    (|v| < STILL on STILL_SAMPLES or more of its samples), else 0; None without a gyro."""
    sig = streams.signals
    if "yaw_rate" not in sig or len(sig["yaw_rate"][0]) < 20:
        return None
    tr, r = (np.asarray(x, float) for x in sig["yaw_rate"])
    bias = 0.0
    if "v" in sig:
        still = np.abs(np.interp(tr, *sig["v"])) < STILL
        bias = float(np.median(r[still])) if still.sum() >= STILL_SAMPLES else 0.0
    step = np.diff(tr)
    return tr, np.r_[0.0, np.cumsum(0.5 * (r[1:] + r[:-1] - 2 * bias) * step)]


def by_steering(t, c, rate, steer, name) -> tuple[np.ndarray, str] | None:
    """Evidence from the steering: the course turns with the wheels forward, against them reversing."""
    d = np.interp(t, *steer)
    ok = np.isfinite(rate) & (np.abs(d) > STEERED) & (np.abs(rate) > TURNING)
    if ok.sum() < 20:
        return None
    product = np.where(ok, rate * d, 0.0)          # a vote weighed by how clearly the course turns with the wheels
    e = np.clip(product / max(float(np.median(np.abs(product[ok]))), 1e-12), -1.0, 1.0)
    majority = 1 if e.sum() >= 0 else -1
    return e * majority, f"the course rate against the steering {name}"


def evidence(streams, t, c, wide=None) -> tuple[np.ndarray, str] | None:
    """The first evidence available (module docstring): (per fix +1/-1/0, how it was read); the
    rates from the course ``c`` (CHORD_NOISE), the votes on ``wide`` (DIRECTION_NOISE; default c)."""
    sig = streams.signals
    rate = angle_rate(t, c)
    c = c if wide is None else wide
    declared = next((n for n in ("direction", "gear") if n in sig), None)
    if declared:
        x = np.interp(t, *sig[declared])
        return np.where(np.isfinite(c), np.sign(x), 0).astype(int), f"the declared direction channel {declared}"
    heading = sig.get("heading")
    g = streams.gnss
    if heading is None and "heading" in g and np.isfinite(g["heading"].to_numpy(float)).sum() > 20:
        ok = np.isfinite(g["heading"].to_numpy(float))          # the receiver's own (HDT, THS)
        heading = (g["utc"].to_numpy(float)[ok], g["heading"].to_numpy(float)[ok])
    if heading is not None and len(heading[0]) > 3:
        found = by_heading(t, c, rate, heading)
        if found is not None:
            return found
    gyro = gyro_heading(streams)
    if gyro is not None:
        found = by_heading(t, c, rate, gyro, "the yaw rate integrated")
        if found is not None:
            return found
    steer = next((n for n in ("delta", "delta_cmd") if n in sig), None)
    return by_steering(t, c, rate, sig[steer], steer) if steer else None


def reversing(t: np.ndarray, c: np.ndarray, e: np.ndarray, steered: bool = False) -> list[tuple[float, float]]:
    """(start, end) of the reversing stretches: a machine changes direction only through a stop, so
    each moving stretch between stops (the course read, above MOVING) is judged whole, reversing
    when the net share of its evidence is below -REVERSE_SHARE, and named when at least
    REVERSE_MIN long with at least 5 votes; inside a stretch judged forward, a run of consecutive
    reversing votes (_reversing_runs) is one too. A machine that steers its wheels (``steered``:
    the evidence is its steering) cannot turn on the spot: a stretch whose course is turned by pi
    against both neighbours' across stops of at most FLIP_STOP s, its own evidence no forward
    majority (a straight reversal gives the steering little to say) and theirs forward, reverses
    too (_flipped)."""
    out = []
    moving = np.isfinite(c)
    edges = np.diff(np.concatenate([[0], moving.astype(int), [0]]))
    runs = list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))
    shares = [e[a:b].sum() / max(float(np.sum(np.abs(e[a:b]))), 1e-12) for a, b in runs]
    for j, (a, b) in enumerate(runs):
        votes, share = e[a:b], shares[j]
        seen = int(np.sum(votes != 0))
        if seen >= 5 and share < -REVERSE_SHARE and t[b - 1] - t[a] >= REVERSE_MIN:
            out.append((float(t[a]), float(t[b - 1])))
        elif steered and share <= 0 < min(shares[max(j - 1, 0)], shares[min(j + 1, len(runs) - 1)]) \
                and t[b - 1] - t[a] >= REVERSE_MIN and _flipped(t, c, runs, j):
            out.append((float(t[a]), float(t[b - 1])))
        else:           # a stop too brief for the fixes to show it: a run of reversing evidence alone
            out += _reversing_runs(t[a:b], votes)
    return out


def _flipped(t: np.ndarray, c: np.ndarray, runs: list, j: int) -> bool:
    """Run j's course turned by pi (within AGREE) against the runs either side across stops of at
    most FLIP_STOP s: its first and last FLIP_SPAN s against theirs next to it."""
    if j == 0 or j == len(runs) - 1:
        return False
    (pa, pb), (a, b), (na, nb) = runs[j - 1], runs[j], runs[j + 1]
    if t[a] - t[pb - 1] > FLIP_STOP or t[na] - t[b - 1] > FLIP_STOP:
        return False

    def mean(lo: int, hi: int) -> float:
        return float(np.angle(np.mean(np.exp(1j * c[lo:hi]))))
    span = max(1, int(round(FLIP_SPAN / float(np.median(np.diff(t))))))
    turned = (_wrap(mean(a, min(b, a + span)) - mean(max(pa, pb - span), pb) - math.pi),
              _wrap(mean(na, min(nb, na + span)) - mean(max(a, b - span), b) - math.pi))
    return all(abs(x) < AGREE for x in turned)


def _reversing_runs(t: np.ndarray, votes: np.ndarray) -> list[tuple[float, float]]:
    """(start, end) of the runs of consecutive reversing votes at least RUN_MIN s and RUN_VOTES
    votes long inside a stretch judged forward (a machine that backs up with a stop shorter than
    the fixes' chords between)."""
    edges = np.diff(np.concatenate([[0], (votes < 0).astype(int), [0]]))
    return [(float(t[a]), float(t[b - 1])) for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1))
            if b - a >= RUN_VOTES and t[b - 1] - t[a] >= RUN_MIN]


def _within(times: np.ndarray, stretches) -> np.ndarray:
    inside = np.zeros(len(times), bool)
    for a, b in stretches:
        inside |= (times >= a) & (times <= b)
    return inside


def _to_stops(ts: np.ndarray, vs: np.ndarray, a: float, b: float) -> tuple[float, float]:
    """A reversing stretch widened to the stops either side: the slowest sample up to 3 s away when
    it is slower than STOP or a quarter of the stretch's median speed (the course is read only
    above MOVING, the machine reverses from standstill to standstill; a quick turnaround is never
    quite at rest between two samples)."""
    inside = (ts >= a) & (ts <= b)
    slow = max(STOP, 0.25 * float(np.median(np.abs(vs[inside])))) if inside.any() else STOP
    out = []
    for lo, hi, edge in ((a - 3.0, a, a), (b, b + 3.0, b)):
        near = np.flatnonzero((ts >= lo) & (ts <= hi))
        k = near[int(np.argmin(np.abs(vs[near])))] if len(near) else None
        out.append(float(ts[k]) if k is not None and abs(vs[k]) < slow else edge)
    return out[0], out[1]

def judged_speed(streams):
    """(name, times, values) of the speed the log carries as the machine's: v, else the
    receiver's own speed; None when the log has only the track's (a magnitude by definition)."""
    if "v" in streams.signals:
        return ("v", *streams.signals["v"])
    g = streams.gnss
    speed = g["speed"].to_numpy(float)
    if np.isfinite(speed).mean() > 0.5:
        return "gnss_speed", g["utc"].to_numpy(float), speed
    return None


def check_direction(streams, options, source, t0: float) -> list[dict]:
    """The direction findings of a recording with fixes; a LogError for an unsigned speed while
    reversing unless ``options.sign_speed`` (then the speed is negated there, in place)."""
    if streams.gnss is None or len(streams.gnss) < 20:
        return []
    t, c, _ = course(streams.gnss)
    wide = course(streams.gnss, DIRECTION_NOISE)[1]       # same fixes, same t: the direction told on shorter chords
    own = judged_speed(streams)
    if own is not None and len(own[1]) > 1:     # the stops by the machine's own speed: a noisy chord bridges none
        wide[np.abs(np.interp(t, own[1], np.nan_to_num(own[2]))) < MOVING] = np.nan
    found = evidence(streams, t, c, wide)
    if found is None:
        return []
    e, how = found
    stretches = reversing(t, wide, e, steered=how.startswith("the course rate against the steering"))
    if not stretches:
        return []
    speed = judged_speed(streams)
    if speed is not None:       # from standstill to standstill: the evidence is read only while moving
        stretches = [_to_stops(speed[1], speed[2], a, b) for a, b in stretches]
    when = ", ".join(f"{a - t0:.1f}-{b - t0:.1f} s" for a, b in stretches)
    total = sum(b - a for a, b in stretches)
    chans = [speed[0] if speed else "track_speed", "course"]
    if speed is not None:
        name, ts, vs = speed
        inside = _within(ts, stretches) & (np.abs(vs) > 0.05)
        if inside.sum() and np.mean(vs[inside] < 0) >= SIGNED_SHARE:
            return [finding("reversing", chans, total, None, "s",
                            f"the machine reverses at {when} ({how}); {name} is negative there: a signed speed",
                            resolved=True)]
    if not getattr(options, "sign_speed", False) or speed is None:
        remedy = ("--sign-speed makes it negative there" if speed is not None else
                  "map the machine's signed speed (--signal v=...) and give --sign-speed if it is unsigned too")
        raise LogError(f"{source}: the machine reverses at {when} (by {how}) while "
                       f"{chans[0]} stays positive: an unsigned speed would pass as forward driving; expected a "
                       f"signed speed (negative reversing): {remedy} (a direction channel, --signal "
                       f"direction=TABLE.COLUMN negative reversing, says where)")
    name, ts, vs = speed
    flip = _within(ts, stretches)
    signed = np.where(flip, -np.abs(vs), vs)
    if name == "v":
        streams.signals["v"] = (ts, signed)
    else:
        streams.gnss = streams.gnss.assign(speed=signed)
    return [finding("reversing", chans, total, None, "s",
                    f"the machine reverses at {when} ({how}); {name} was unsigned: made negative there "
                    f"(--sign-speed; {int(flip.sum())} samples)", resolved=True)]
