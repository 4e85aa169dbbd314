"""The audit of a recording before any log is used: every channel's timing, and what the channels
say about each other's clocks, scales and labels.

Per channel (a log column on its own stamps, or the receiver's fixes ``gnss``): samples, rate
(1 / median step of its updates: a channel held in faster rows is judged on its own updates,
measurements.channel_updates, and its rows' rate and hold factor are given beside), gaps (silences
longer than max(3 steps, 0.2 s): count, longest, when), repeated stamps, and its group (the file,
topic or bus it came from: one clock; the receiver's fixes given as a table's lat/lon columns
share that table's).

Between channels, from signals that must agree (Kayacan et al. section 2's kinematic relations):

- two speeds: the wheel speed ``v`` against the receiver's speed over ground (its scale read where
  the fix holds the quality it holds longest: a degraded fix's noise biases a speed from positions
  upwards);
- gyro against the GNSS course: ``yaw_rate`` against d(course)/dt of the track (1 s chords, |v| > 1 m/s);
- ``v r`` against the lateral acceleration (a column ``ay``, ``a_y``, ``lat_acc``, ``acc_y``);
- two yaw-rate sources (``yaw_rate`` and ``yaw_rate_*`` or a wheel odometry's ``odom_yaw_rate``);
- steering x speed against yaw rate, ``v tan(delta) / L`` -> ``r``: the only pair with a physical
  lag (actuator, tyres), so it gives no clock offset but the causality check: a response never
  leads its input.

The lag is the peak of the normalised cross-correlation of the two signals on a common grid
(masked where either is silent or the vehicle is too slow), refined by a parabola; its interval
is the spread of the lags of up to 8 separate stretches (lag +- 2 s.e., at least one grid step).
The scale is the least-squares slope of the second signal on the first at that lag.

Findings: dicts {kind, channels, value, interval ([lo, hi] or None), unit, meaning, resolved}.
Kinds:

- ``clock_offset``: the second group's stamps are ``value`` s late against the first's (a pair
  with no physical lag); acted on (aligned by ``--align auto``) only on evidence: correlation at
  least STRONG_RHO over at least EVIDENCE_S s of samples compared, an interval of half-width at
  most HALF_WIDTH s that excludes zero and is narrower than the offset, the offset at least
  ALIGN_MIN; below that it is "too weak to judge",
  resolved (not acted on, no blocker); unresolved while a strong offset stays unaligned;
- ``clock_unchecked``: a clock that no pair compared, where it or the reference counts from a
  logger's start (unchecked_clocks): joined as if started together, value 0 s (the offset assumed;
  not known; resolved: said, not moved);
- ``sensor_latency``: a lag between two channels of one group (one file's rows, one topic: one
  clock): a sensor's own latency (a filter, a fix's age), never a realignment (resolved);
- ``held_samples``: a channel updated slower than its rows (``value`` rows per update), judged on
  its updates (resolved); it alone also carries ``updates_hz``, its updates' rate;
- ``reversing``: stretches where the course is opposite the heading or the steering (or a declared
  direction channel says so), measurements.direction: resolved when the speed is negative there
  or made so by ``--sign-speed``; otherwise the import is refused;
- ``response_leads_input``: the yaw rate answers ``value`` s before the steering x speed that
  causes it; resolved when an alignment removed it;
- ``response_lag``: the lag of that causal pair when it is causal (information, resolved);
- ``scale_disagreement``: the second channel is ``value`` times the first (two speeds, gyro vs
  course, ``v r`` vs lateral acceleration, two gyros);
- ``opposite_sign``: the same, ``value`` negative: the second channel (or the yaw rate against
  v tan(delta) / L, by the correlation or over a steady turn by the means) has the opposite sign, a
  sign convention; named with its evidence, never as a scale;
- ``mislabelled_channel``: a "gyro" whose mean is g, a gyro/accelerometer pair swapped, an
  "angle" that is a rate;
- ``ambiguous_channel``: two plausible sources of one quantity that disagree;
- ``position_is_estimate``: x, y from a localisation or odometry, not a receiver's fixes: their
  noise held to the course or absent (measurements.position_source);
- ``gap_bridged``: a channel's gaps up to ``--max-gap`` bridged (linear; held for a command);
- ``gap_split``: a channel's gaps longer than ``--max-gap`` (they split the log);
- ``clock_jump``: a file's clock stepped (measurements.time_base; an offset of the date's leap
  seconds is a ``clock_offset`` named so);
- ``gps_week_rollover``: a file's dates 1024 weeks early (measurements.time_base);
- ``out_of_range``: samples beyond a ground vehicle's physical range (PHYSICAL);
- ``mode_stretches``: a mode column's stretches away from the value it holds longest;
- ``fix_quality_changes``: the receiver's fix quality's stretches away from the one it holds longest;
- ``stamp_vs_receive``: header stamps against the receive times of the same messages;
- ``terminal_clock``: a terminal's clock against the GNSS time of the same records.

Imported where used: scipy.signal (start-up: 0.35 s CPU on every command, which loads this module
through measurements.recording), scipy.ndimage (start-up: 0.035 s CPU), scipy.integrate (start-up:
0.025 s CPU).
"""
from __future__ import annotations

import math

import numpy as np

from agrobot.components.tractor_yaw_plant import steer_input

from .channel_updates import ROWS_KEPT, SUM_SAID
from .clocks import parabolic_peak
from .direction import angle_rate, check_direction, chord_steps, position_noise
from .findings import finding
from .imu_axes import axis_findings
from .log import CANONICAL, LogError, slope_through_origin
from .options import ImportOptions
from .position_source import estimate_evidence, named_estimate, track_noise
from .streams import Streams, gnss_speed, is_boot_clock
from .time_base import LEAP_TOLERANCE, gps_minus_utc, leap_meaning

SEARCH = 3.0            # s: lags searched either way
WIDE_SEARCH = 30.0      # s: ... and this far between two clocks that no lag within SEARCH explains
LEAD_TOLERANCE = 0.05   # s: a response this far ahead of its input is still within the stamps' jitter
ALIGN_MIN = 0.08        # s: a smaller offset is not corrected (within a GNSS epoch's latency)
STRONG_RHO = 0.6        # a lag trusted for alignment: correlation at least this
HALF_WIDTH = 0.1        # s: ... and its interval's half-width at most this
EVIDENCE_S = 30.0       # s: ... on at least this much of the two signals compared (a slow machine's course
                        # read above MOVING for 10 s correlates by chance somewhere in a +-30 s search)
STEADY = 0.02          # rad/s: a kinematic yaw rate whose mean is above this (and twice its spread) is a steady turn
MIN_INPUT_CHANGES = 10  # an input (steering and speed) that changes fewer times gives no lag to judge
SCALE_SPAN = 2.0        # s: a scale is the slope of both channels averaged over this span
SCALE_TOLERANCE = 0.05  # a scale off 1 by more than this (and its interval) is named ...
SCALE_EVIDENCE_S = 10.0     # s: ... read on at least this much of the two signals compared (5 of the 2 s averages)
MOVING = 0.3            # m/s: the GNSS course is read above this speed ...
COURSE_SIGMAS = 40.0    # ... where its chord is this many position sigmas long (the course within ~2 deg)
LATERAL = ("ay", "a_y", "lat_acc", "acc_y", "lateral_acceleration")
GAP_PERIODS, GAP_MIN = 3.0, 0.2
G = 9.80665


# --- channels ---------------------------------------------------------------------------------
def channel_gaps(t: np.ndarray, least: float = GAP_MIN) -> tuple[np.ndarray, np.ndarray]:
    """(start index, length [s]) of the silences longer than max(3 median steps, ``least``)."""
    if len(t) < 3:
        return np.array([], int), np.array([])
    dt = np.diff(t)
    limit = max(GAP_PERIODS * float(np.median(dt[dt > 0])) if (dt > 0).any() else 0.0, least)
    i = np.flatnonzero(dt > limit)
    return i, dt[i]


def channel_row(name: str, group: str, t: np.ndarray, t0: float, updates: dict | None = None) -> dict:
    """One channel's line of the table: its rate is that of its updates (``updates``: how a held
    channel was found, measurements.channel_updates: its updates' rate, which a channel read at
    irregular times has as a mean, its rows' rate and the hold factor; a set point keeps its rows,
    each a message sent, and their rate)."""
    t = np.asarray(t, float)
    dt = np.diff(t)
    step = float(np.median(dt[dt > 0])) if (dt > 0).any() else math.nan
    i, length = channel_gaps(t)
    held = {"rows_hz": float(updates["rows_hz"]), "held": float(updates["held"])} if updates else {}
    return {"channel": name, "group": group, "samples": int(len(t)), **held,
            "start_s": float(t[0] - t0) if len(t) else math.nan, "end_s": float(t[-1] - t0) if len(t) else math.nan,
            "rate_hz": float(updates["updates_hz"]) if updates and not updates.get("set_point")
            else 1.0 / step if step > 0 else math.nan,
            "repeated_stamps": int(np.sum(dt == 0)),
            "gaps": int(len(i)), "longest_gap_s": float(length.max()) if len(i) else 0.0,
            "gaps_at_s": [round(float(t[k] - t0), 2) for k in i[:5]]}


# --- lags ---------------------------------------------------------------------------------------
def _on_grid(t: np.ndarray, x: np.ndarray, grid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """x interpolated onto ``grid``, and where it is valid (within its span, not inside a gap)."""
    t, x = np.asarray(t, float), np.asarray(x, float)
    ok = np.isfinite(x)
    t, x = t[ok], x[ok]
    if len(t) < 3:
        return np.zeros(len(grid)), np.zeros(len(grid), bool)
    y = np.interp(grid, t, x)
    j = np.clip(np.searchsorted(t, grid, side="right"), 1, len(t) - 1)
    i, length = channel_gaps(t)
    limit = length.min() if len(length) else np.inf
    valid = (grid >= t[0]) & (grid <= t[-1]) & (t[j] - t[j - 1] < limit)
    return y, valid


def _xcorr(a: np.ndarray, b: np.ndarray, ok: tuple, shift: int) -> np.ndarray:
    """Normalised correlation of a[i] with b[i + k], k = -shift..shift, over the samples valid in
    both (six FFT correlations of the masked sums; -inf where fewer than 20 samples overlap)."""
    from scipy.signal import correlate

    ma, mb = ok[0].astype(float), ok[1].astype(float)
    a, b = np.where(ok[0], a, 0.0), np.where(ok[1], b, 0.0)
    a = a - (a.sum() / max(ma.sum(), 1.0)) * ma          # centred: the sums below lose no digits
    b = b - (b.sum() / max(mb.sum(), 1.0)) * mb
    n = len(a)

    def c(x, y):       # sum_i x[i] y[i + k] for k = -shift..shift
        full = correlate(y, x, mode="full", method="fft")
        return full[n - 1 - shift:n + shift]
    N = np.round(c(ma, mb))
    sa, sb, sab = c(a, mb), c(ma, b), c(a, b)
    saa, sbb = c(a * a, mb), c(ma, b * b)
    with np.errstate(invalid="ignore", divide="ignore"):
        cov = sab - sa * sb / N
        var = (saa - sa ** 2 / N) * (sbb - sb ** 2 / N)
        rho = cov / np.sqrt(var)
    return np.where((N >= 20) & (var > 0) & np.isfinite(rho), rho, -np.inf)


def _peak(rho: np.ndarray, step: float, shift: int) -> tuple[float, float]:
    """(lag [s], correlation) at the refined peak of a correlation over lags -shift..shift."""
    k, best = parabolic_peak(rho)
    return ((k - shift) * step, best) if math.isfinite(k) else (math.nan, 0.0)


def lag(ta, xa, tb, xb, search: float = SEARCH, mask=None, through_origin: bool = False,
        scale_mask=None) -> dict | None:
    """How late b is against a: b(t) = s a(t - lag). {lag, interval, rho, scale, scale_interval,
    seconds, inverted, edge} or None when they share too little: where the correlation's most
    negative value outweighs its most positive, b answers a with the opposite sign (``inverted``,
    rho that of -b, the scale negative); ``edge``: the peak sits on the search's bound. ``mask(grid) -> bool`` limits the samples
    (e.g. moving); ``scale_mask(grid) -> bool`` limits further those the scale is read on."""
    ta, tb = np.asarray(ta, float), np.asarray(tb, float)
    if len(ta) < 20 or len(tb) < 20:
        return None
    lo, hi = max(ta[0], tb[0]), min(ta[-1], tb[-1])
    if hi - lo < 10.0:
        return None
    search = min(search, max(SEARCH, (hi - lo) / 3))     # a wide search keeps two thirds of the span compared
    da, db = np.median(np.diff(ta)), np.median(np.diff(tb))
    step = float(np.clip(min(da, db) / 2, 0.02, 0.05))
    if (hi - lo) / step > 400_000:
        step = (hi - lo) / 400_000
    grid = np.arange(lo, hi, step)
    a, oka = _on_grid(ta, xa, grid)
    b, okb = _on_grid(tb, xb, grid)
    if mask is not None:
        m = mask(grid)
        oka, okb = oka & m, okb & m
    if oka.sum() < 50 or okb.sum() < 50 or np.ptp(a[oka]) == 0 or np.ptp(b[okb]) == 0:
        return None
    shift = int(round(search / step))
    rho = _xcorr(a, b, (oka, okb), shift)
    finite = rho[np.isfinite(rho)]
    inverted = bool(finite.size) and -float(finite.min()) > float(finite.max())
    if inverted:                        # b answers a with the opposite sign: judged as -b, the scale negative
        b, rho = -b, np.where(np.isfinite(rho), -rho, -np.inf)
    whole, r = _peak(rho, step, shift)
    if not math.isfinite(whole):
        return None
    if search > SEARCH and abs(whole) > SEARCH:       # a wide search: b moved by its peak, judged again near it
        fine = lag(ta, xa, tb - whole, xb, SEARCH, mask, through_origin, scale_mask)
        if fine is None:
            return None
        iv = fine["interval"]
        return {**fine, "lag": fine["lag"] + whole, "interval": None if iv is None else [iv[0] + whole, iv[1] + whole]}
    k = int(round(whole / step))
    width = int(round(SCALE_SPAN / step))
    oks = oka & scale_mask(grid) if scale_mask is not None else oka
    scale = _slope(a, b, oks, okb, k, through_origin, width)
    back = _slope(b, a, okb, oks, -k, through_origin, width)     # a on b: the noise in a no longer shrinks it
    reverse = 1.0 / back if math.isfinite(back) and back != 0 else math.nan
    # stretches: up to 8 separate ones of at least 15 s of valid samples
    parts = min(8, int(np.sum(oka & okb) * step // 15.0))
    lags, scales = [], []
    if parts >= 3:
        edges = np.linspace(0, len(grid), parts + 1).astype(int)
        for e0, e1 in zip(edges[:-1], edges[1:]):
            sel = np.zeros(len(grid), bool)
            sel[e0:e1] = True
            p = _xcorr(a, b, (oka & sel, okb), shift)
            lp, rp = _peak(p, step, shift)
            if math.isfinite(lp) and rp > 0.3:
                lags.append(lp)
                scales.append(_slope(a, b, oks & sel, okb, int(round(lp / step)), through_origin, width))
    if len(lags) >= 3:
        se = 2.0 * float(np.std(lags, ddof=1)) / math.sqrt(len(lags))
        interval = [whole - max(se, step), whole + max(se, step)]
        ss = 2.0 * float(np.std(scales, ddof=1)) / math.sqrt(len(scales))
        scale_interval = [scale - ss, scale + ss]
    else:
        half = _half_width(rho, step, shift, r)
        interval = [whole - half, whole + half] if half is not None else None
        scale_interval = None
    if inverted:
        scale, reverse = -scale, -reverse
        scale_interval = None if scale_interval is None else [-scale_interval[1], -scale_interval[0]]
    return {"lag": whole, "interval": interval, "rho": r, "scale": scale, "scale_interval": scale_interval,
            "scale_reverse": reverse,
            "seconds": float(np.sum(oka & okb) * step), "stretches": len(lags), "inverted": inverted,
            "edge": abs(whole) >= search - 2 * step,
            "scale_share": float(np.sum(oks & okb) / max(1, np.sum(oka & okb)))}


def _half_width(rho: np.ndarray, step: float, shift: int, peak: float) -> float | None:
    """Lags within 0.01 of the peak correlation: a crude interval where stretches are too few."""
    near = np.flatnonzero(rho >= peak - 0.01)
    if len(near) == 0 or peak < 0.3:
        return None
    return max(float(near.max() - near.min()) * step / 2, step)


def _masked_mean(x: np.ndarray, ok: np.ndarray, width: int) -> np.ndarray:
    """The centred moving average of x over ``width`` samples, of its valid samples only."""
    from scipy.ndimage import uniform_filter1d

    if width <= 1:
        return x
    w = ok.astype(float)
    return uniform_filter1d(np.where(ok, x, 0.0), width, mode="nearest") / np.maximum(
        uniform_filter1d(w, width, mode="nearest"), 1e-12)


def _slope(a, b, oka, okb, k, through_origin, width: int = 1):
    """The regression slope of b[i + k] on a[i], both averaged over ``width`` samples first (the
    same linear filter on both keeps their scale; it removes the sample noise of a derived rate, a
    course from quantised or held positions, that would shrink a regression on it)."""
    a, b = _masked_mean(a, oka, width), _masked_mean(b, okb, width)
    n = len(a)
    lo, hi = max(0, -k), min(n, n - k)
    sel = oka[lo:hi] & okb[lo + k:hi + k]
    x, y = a[lo:hi][sel], b[lo + k:hi + k][sel]
    if len(x) < 10:
        return math.nan
    return slope_through_origin(x, y) if through_origin else slope_through_origin(x - x.mean(), y - y.mean())


# --- the signals that must agree ---------------------------------------------------------------
COURSE_HALF_CHORD = 0.5  # s: gnss_rates reads the course on chords this far either side (1 s chords)
RATE_SPAN = 0.25        # s: the course rate is the chords' course differenced this far either side (at least a fix)


def rate_step(h: float) -> int:
    """Fixes either side over which gnss_rates differences the chords' course (RATE_SPAN at a fix
    interval h): a 20 Hz course differenced per fix is its noise over 0.1 s, larger than a
    machine's turning (the gyro compared with it is smoothed by the same 2 m h box)."""
    return chord_steps(h, RATE_SPAN)


def gnss_rates(gnss) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(utc, speed over ground [m/s], course rate [rad/s]) of the receiver's fixes: the course
    of 1 s chords of the track (a sphere is enough for a rate), differenced over rate_step fixes
    either side (a 2 m h box), NaN where the track is slower
    than MOVING m/s, or than a chord of COURSE_SIGMAS position sigmas, within 1 s of the chord's
    centre (a chord across a stop, where a machine may turn back, has no course)."""
    t = gnss["utc"].to_numpy(float)
    lat, lon = gnss["lat"].to_numpy(float), gnss["lon"].to_numpy(float)
    north = np.radians(lat - lat[0]) * 6.371e6
    east = np.radians(lon - lon[0]) * 6.371e6 * math.cos(math.radians(float(lat[0])))
    speed = gnss_speed(gnss)
    rate = np.full(len(t), np.nan)
    if len(t) > 5:
        h = float(np.median(np.diff(t)))
        k = chord_steps(h, COURSE_HALF_CHORD)
        if len(t) > 2 * k + 2:
            course = np.unwrap(np.arctan2(north[2 * k:] - north[:-2 * k], east[2 * k:] - east[:-2 * k]))
            tc = t[k:-k]
            r = angle_rate(tc, course, RATE_SPAN)
            sigma = position_noise(east, north)         # the chord long against the fixes' own noise ...
            need = np.maximum(MOVING, COURSE_SIGMAS * sigma[k:-k] / (2 * k * h))
            from scipy.ndimage import minimum_filter1d

            least = minimum_filter1d(speed, 4 * k + 1, mode="nearest")[k:-k]    # ... and moving all along it
            slow = least < need
            r[slow] = np.nan
            rate[k:-k] = r
    return t, speed, rate


def smoothed(t: np.ndarray, x: np.ndarray, span: float) -> np.ndarray:
    """The centred moving average of x over ``span`` seconds, on its own stamps (no lag added)."""
    from scipy.ndimage import uniform_filter1d

    h = float(np.median(np.diff(t)))
    width = int(round(span / h)) if h > 0 else 1
    return uniform_filter1d(np.asarray(x, float), width, mode="nearest") if width > 1 else np.asarray(x, float)


def _moving(t_v, v, threshold=MOVING):
    return lambda grid: np.abs(np.interp(grid, t_v, v)) > threshold


def _good(t_v, v, threshold, best):
    """mask(grid): moving above ``threshold`` where the receiver's fix is at its usual quality
    (a speed or course from degraded fixes is noise, not a signal to correlate)."""
    moving, usual = _moving(t_v, v, threshold), _usual(best)
    return moving if usual is None else (lambda grid: moving(grid) & usual(grid))


def _usual(best):
    """mask(grid): where the receiver's fix is at its usual quality (``best``: usual_fix), or None."""
    if best is None:
        return None
    tb, ok = best
    return lambda grid: np.interp(grid, tb, ok.astype(float)) > 0.5


def _scale_stretch(est: dict) -> str:
    """What a scale was read on when the receiver's degraded fixes were passed over (``scale_share``)."""
    share = est.get("scale_share", 1.0)
    return ("" if share >= 0.999 else f" (the scale read where the fix is at its usual quality, {100 * share:.0f} % of "
            f"the samples compared; the degraded fixes' {100 * (1 - share):.0f} % passed over)")


def held_longest(codes: np.ndarray) -> float:
    """The code a receiver (or mode channel) holds on most of its finite samples."""
    values, counts = np.unique(codes[np.isfinite(codes)], return_counts=True)
    return float(values[np.argmax(counts)])


def usual_fix(gnss):
    """(utc, whether each fix is at the quality the receiver holds longest), or None when it does not
    say its quality or holds it on less than half of its fixes."""
    q = gnss["quality"].to_numpy(float) if "quality" in gnss else np.zeros(0)
    if not np.isfinite(q).any():
        return None
    usual = q == held_longest(q)
    return (gnss["utc"].to_numpy(float), usual) if 0.5 <= usual.mean() < 1.0 else None


class Auditor:
    """Collects the channel table and the findings of one recording (measurements.recording)."""

    def __init__(self, streams, groups: dict, wheelbase: float, t0: float):
        self.streams, self.groups, self.L, self.t0 = streams, groups, wheelbase, t0
        self.findings: list[dict] = []
        self.pairs: list[dict] = []
        self.unit_converted: set[str] = set()     # channels the audit divided by a unit factor

    def divide(self, channel: str, k: float, unit: str, against: str) -> None:
        """``channel`` found in ``unit`` (k times its SI value): divided by k in place, its column
        description says so, and it is not converted twice."""
        t, x = self.streams.signals[channel]
        self.streams.signals[channel] = (t, x / k)
        columns = self.streams.report.setdefault("columns", {})
        columns[channel] = f"{columns.get(channel, channel)}; / {k:.4g}: {unit} (the audit's scale against {against})"
        self.unit_converted.add(channel)

    def group(self, channel: str) -> str:
        """The channel's clock: its file, topic or bus; the receiver's (``gnss``, its speed, course
        and positions) is the file of the lat/lon columns where a table holds them."""
        if channel in ("gnss", "gnss_speed", "course_rate", "x", "y", "heading") and channel not in self.streams.signals:
            return self.groups.get("gnss", "gnss")
        return self.groups.get(channel, channel)

    def clock(self, channel: str) -> str:
        """The clock the channel's times are on: its group's, or one that groups share (the topics
        of a bag on its receive clock, Streams.clocks)."""
        return self.group_clock(self.group(channel))

    def group_clock(self, group: str) -> str:
        """The clock a group's times are on (Streams.clocks), the group itself where it has its own."""
        return (getattr(self.streams, "clocks", None) or {}).get(group, group)

    def stamped(self, only=None) -> list[tuple[list[str], np.ndarray]]:
        """([channels], stamps): the channels that share their stamps exactly, together (the
        receiver's fixes as ``gnss``); ``only`` limits the channels."""
        out: list[tuple[list[str], np.ndarray]] = []
        g = self.streams.gnss
        if g is not None:
            out.append((["gnss"], g["utc"].to_numpy(float)))
            own = np.isfinite(g["heading"].to_numpy(float)) if "heading" in g else np.zeros(len(g), bool)
            if own.sum() >= 20 and "heading" not in self.streams.signals:      # the receiver's own heading
                out.append((["heading"], g["utc"].to_numpy(float)[own]))
        for c, (t, _) in self.streams.signals.items():
            if only is not None and c not in only:
                continue
            same = next((names for names, s in out if len(s) == len(t) and np.array_equal(s, t)), None)
            if same is not None:
                same.append(c)
            else:
                out.append(([c], np.asarray(t, float)))
        return out

    def channels(self) -> list[dict]:
        """A row per set of channels on the same stamps whose updates were found alike (a sum of
        signals kept on its rows has its own rate: measurements.channel_updates)."""
        updates = self.streams.report.get("updates", {})
        rows = []
        for names, t in self.stamped():
            alike: dict[tuple, list[str]] = {}
            for n in names:
                alike.setdefault(tuple(sorted((updates.get(n) or {}).items())), []).append(n)
            rows += [channel_row(", ".join(same), self.group(same[0]), t, self.t0, updates.get(same[0]))
                     for same in alike.values()]
        return rows

    def zero_lag_pairs(self, search: float = SEARCH) -> list[dict]:
        """Every pair with no physical lag: (name, a, b, lag dict), lags searched +-``search`` s."""
        sig, out = self.streams.signals, []
        gnss = self.streams.gnss
        if gnss is not None and len(gnss) > 20:
            tg, speed, course_rate = gnss_rates(gnss)
            best = usual_fix(gnss)
            if "v" in sig:          # the speed over ground is a magnitude: |v| against it
                out.append(("two speeds", "gnss_speed", "v", lag(tg, speed, sig["v"][0], np.abs(sig["v"][1]), search,
                                                               through_origin=True, mask=_good(tg, speed, 0.3, best),
                                                               scale_mask=_usual(best)), "m/s"))
            gyros = [c for c in sig if c == "yaw_rate" or c.startswith("yaw_rate_")]
            for gyro in sorted(gyros) if np.isfinite(course_rate).sum() > 20 else ():
                ok = np.isfinite(course_rate)
                h = float(np.median(np.diff(tg)))
                t, r = sig[gyro]
                r = smoothed(t, smoothed(t, r, 2 * chord_steps(h, COURSE_HALF_CHORD) * h), 2 * rate_step(h) * h)  # as the chords
                out.append(("gyro vs GNSS course", "course_rate", gyro,
                            lag(tg[ok], course_rate[ok], t, r, search, mask=_good(tg, speed, MOVING, best)), "rad/s"))
        lateral = next((c for c in LATERAL if c in sig), None)
        if lateral and "v" in sig and "yaw_rate" in sig:
            t, r = sig["yaw_rate"]
            vr = np.interp(t, *sig["v"]) * r
            out.append(("v r vs lateral acceleration", "yaw_rate", lateral, lag(t, vr, *sig[lateral], search), "m/s2"))
        for other in sorted(c for c in sig if c.startswith("yaw_rate_") or c == "odom_yaw_rate"):
            if "yaw_rate" in sig:
                out.append(("two gyros" if other != "odom_yaw_rate" else "gyro vs wheel odometry", "yaw_rate", other,
                            lag(*sig["yaw_rate"], *sig[other], search), "rad/s"))
        return [p for p in out if p[3] is not None]

    def causal(self) -> dict | None:
        """Steering x speed -> yaw rate: {lag dict, input} or None."""
        sig = self.streams.signals
        steer = "delta" if "delta" in sig else "delta_cmd" if "delta_cmd" in sig else None
        if steer is None or "v" not in sig or "yaw_rate" not in sig:
            return None
        t, d = sig[steer]
        u = np.interp(t, *sig["v"]) * steer_input(d, "tan") / self.L
        found = lag(t, u, *sig["yaw_rate"], mask=_moving(*sig["v"], 0.3))
        changes = int(np.count_nonzero(np.diff(d))) + int(np.count_nonzero(np.diff(sig["v"][1])))
        return None if found is None else {**found, "input": steer, "input_changes": changes}

    def steady_sign(self) -> dict | None:
        """An opposite_sign finding where the yaw rate's mean and the kinematic v tan(delta) / L's,
        over a steady turn while moving (|mean| above STEADY rad/s and twice its spread), have
        opposite signs; None otherwise."""
        sig = self.streams.signals
        steer = "delta" if "delta" in sig else "delta_cmd" if "delta_cmd" in sig else None
        if steer is None or "v" not in sig or "yaw_rate" not in sig:
            return None
        t, r = sig["yaw_rate"]
        v = np.interp(t, *sig["v"])
        u = v * steer_input(np.interp(t, *sig[steer]), "tan") / self.L
        moving = np.abs(v) > 0.3
        if moving.sum() < 100:
            return None
        mu, spread, mr = float(np.mean(u[moving])), float(np.std(u[moving])), float(np.mean(r[moving]))
        if abs(mu) < max(STEADY, 2 * spread) or mr / mu >= 0:
            return None
        seconds = float(np.sum(np.diff(t)[moving[1:]]))
        return opposite_sign([steer, "v", "yaw_rate"], mr / mu, None,
                             f"a steady turn ({seconds:.0f} s moving): yaw_rate's mean {mr:+.3g} rad/s is {mr / mu:.3g} "
                             f"times v tan({steer}) / L's {mu:+.3g} rad/s (L {self.L:g} m)")


def _interval_text(iv, unit="s", digits=3) -> str:
    return f" [{iv[0]:+.{digits}f}, {iv[1]:+.{digits}f}] {unit}" if iv else " (no interval: too few stretches)"


def _judged(est: dict) -> bool:
    """A lag strong enough to act on: correlation at least STRONG_RHO over at least EVIDENCE_S s
    of samples compared, an interval within +-HALF_WIDTH s, the peak inside the search."""
    iv = est["interval"]
    return (est["rho"] >= STRONG_RHO and est["seconds"] >= EVIDENCE_S and iv is not None
            and (iv[1] - iv[0]) / 2 <= HALF_WIDTH and not est["edge"])


def _agreeing(est: dict) -> bool:
    """Evidence enough to say two clocks agree: a realignment's correlation over its time."""
    return est["rho"] >= STRONG_RHO and est["seconds"] >= EVIDENCE_S


def widened(aud: Auditor, pairs: list) -> list:
    """The pairs of two clocks that no lag within +-SEARCH s explains, searched again over
    +-WIDE_SEARCH s (at most a third of the time they share: leap seconds, a clock set by hand);
    the wider lag replaces the first where it is strong (_judged) and beyond SEARCH."""
    weak = {(p[0], p[1], p[2]) for p in pairs if aud.clock(p[1]) != aud.clock(p[2]) and not _judged(p[3])}
    if not weak:
        return pairs
    wide = {(p[0], p[1], p[2]): p for p in aud.zero_lag_pairs(WIDE_SEARCH) if (p[0], p[1], p[2]) in weak}
    return [wide[k] if (k := (p[0], p[1], p[2])) in wide and abs(wide[k][3]["lag"]) > SEARCH
            and (_judged(wide[k][3]) or _leap(aud, wide[k][3], aud.group(k[1]), aud.group(k[2])) is not None)
            else p for p in pairs]


def _leap(aud: Auditor, est: dict, ga: str, gb: str) -> float | None:
    """The GPS - UTC leap seconds of the recording's date (signed as the lag) when a strong lag
    (correlation at least STRONG_RHO over EVIDENCE_S s, not on the search's bound) between the receiver's clock and
    another has an interval that excludes zero and holds that count, or is judged (_judged) within
    LEAP_TOLERANCE of it (the signals compared add their own latencies to the clocks'); else None."""
    iv, leap = est["interval"], gps_minus_utc(aud.t0)
    if not leap or iv is None or est["rho"] < STRONG_RHO or est["seconds"] < EVIDENCE_S or est["edge"] \
            or aud.group("gnss") not in (ga, gb):
        return None
    signed = math.copysign(leap, est["lag"])
    holds = iv[0] <= signed <= iv[1] or (_judged(est) and abs(est["lag"] - signed) < LEAP_TOLERANCE)
    return signed if holds and (iv[0] > 0 or iv[1] < 0) else None


def estimate_offsets(aud: Auditor) -> tuple[dict[str, tuple[float, list, str]], list[dict]]:
    """({group: (seconds late, interval, evidence)} of the groups an offset was found for against
    the reference (the receiver, else the gyro's group), the pairs' findings)."""
    pairs = widened(aud, aud.zero_lag_pairs())
    findings, offsets = [], {}
    agreeing: dict[frozenset, list] = {}    # group pairs a direct comparison finds on one clock: its interval
    reference = aud.group("gnss") if aud.streams.gnss is not None else aud.group("yaw_rate")
    for name, a, b, est, unit in pairs:
        ga, gb = aud.group(a), aud.group(b)
        late, iv = est["lag"], est["interval"]
        judged = _judged(est)
        leap = _leap(aud, est, ga, gb)
        if leap is not None:            # a known count of seconds inside the interval: that count, exactly
            late, judged = leap, True
        strong = judged and abs(late) >= ALIGN_MIN and (iv[0] > 0 or iv[1] < 0) and iv[1] - iv[0] < abs(late)
        small = iv is not None and abs(late) < ALIGN_MIN and _agreeing(est)
        meaning = (f"{name}: {b} ({gb}) follows {'-' if est['inverted'] else ''}{a} ({ga}) {late:+.3f} s late "
                   f"(correlation {est['rho']:.2f} over {est['seconds']:.0f} s)"
                   + (f"; the peak sits on the search's bound (+-{SEARCH:g} s): no lag found" if est["edge"] else ""))
        if leap is not None and not iv[0] <= leap <= iv[1]:
            meaning += (f"; measured {est['lag']:+.3f} s{_interval_text(iv)}: the leap count, the rest "
                        f"({est['lag'] - leap:+.3f} s) a latency of the signals compared, not moved")
        if aud.clock(a) == aud.clock(b):
            one = f"one row, one clock ({ga})" if ga == gb else f"one clock ({aud.clock(a)})"
            findings.append(finding("sensor_latency", [a, b], late, iv, "s", meaning + (
                f"; {one}: a sensor's own latency (a filter, a fix's age), not a clock; nothing "
                f"moved" if judged else f"; {one}: too weak to judge (correlation below "
                f"{STRONG_RHO}, under {EVIDENCE_S:g} s compared or interval wider than +-{HALF_WIDTH} s); nothing "
                f"moved"), resolved=True))
        elif small:
            meaning += f"; below {ALIGN_MIN} s: the clocks agree, nothing to correct"
            if ga != gb and est["rho"] >= STRONG_RHO:
                agreeing[frozenset((ga, gb))] = iv
        elif strong:
            meaning += leap_meaning(late, aud.t0) if "gnss" in (ga, gb) or aud.group("gnss") in (ga, gb) else ""
            meaning += ("; the clocks disagree: identification and diagnosis would take it for a delay or a lever arm "
                        "until aligned (--align)")
            base = {reference: 0.0, **{g: o[0] for g, o in offsets.items()}}
            half = (iv[1] - iv[0]) / 2
            if leap is not None and late == leap and reference == aud.group("gnss") in (ga, gb) \
                    and reference not in offsets:    # GPS time against UTC: the receiver's stamps are the ones off
                own = -late if ga == reference else late
                offsets[reference] = (own, [own - half, own + half], name)
            elif ga in base and gb not in base and abs(base[ga] + late) >= ALIGN_MIN:   # on the reference's clock: none
                offsets[gb] = (base[ga] + late, [base[ga] + iv[0], base[ga] + iv[1]], name)
            elif gb in base and ga not in base and abs(base[gb] - late) >= ALIGN_MIN:
                offsets[ga] = (base[gb] - late, [base[gb] - iv[1], base[gb] - iv[0]], name)
        else:
            meaning += (f"; too weak to judge (a realignment needs correlation at least {STRONG_RHO} over at least "
                        f"{EVIDENCE_S:g} s, an interval within +-{HALF_WIDTH} s that excludes zero and is narrower "
                        f"than the offset): not acted on")
        if aud.clock(a) != aud.clock(b):
            findings.append(finding("clock_offset", [a, b], late, iv, "s", meaning, resolved=small or not strong))
        s, siv = est["scale"], est["scale_interval"]
        if math.isfinite(s) and s < 0 and est["rho"] >= 0.5 and not est["edge"]:
            findings.append(opposite_sign([a, b], s, siv, f"{name}: {b} is {s:.3g} times {a} (correlation "
                                                          f"{est['rho']:.2f} with the sign turned)"))
        elif math.isfinite(s) and est["rho"] >= 0.5 and est["seconds"] >= SCALE_EVIDENCE_S:
            if _scale_off(s, siv, est.get("scale_reverse", math.nan)):
                what = _scale_meaning(name, a, b, s, est.get("scale_reverse", math.nan)) + _scale_stretch(est)
                findings.append(finding("scale_disagreement", [a, b], s, siv, "ratio", what))
        if name == "two gyros" and (strong or (math.isfinite(s) and abs(s - 1) > SCALE_TOLERANCE)):
            course = {p[2]: p[3]["scale"] for p in pairs if p[0] == "gyro vs GNSS course" and p[2] in (a, b)}
            says = ("; against the GNSS course: " + ", ".join(f"{c} x {k:.3g}" for c, k in course.items())
                    if len(course) == 2 else "")
            findings.append(finding("ambiguous_channel", [a, b], s, siv, "ratio",
                                    f"two yaw-rate sources disagree ({b} is {s:.3g} times {a}, {late:+.3f} s late)"
                                    f"{says}: {a} is the one identification and diagnosis use; --signal yaw_rate=... "
                                    f"chooses the other"))
    # an offset that a direct comparison of the same two groups excludes is not a clock
    for group in [g for g in offsets if frozenset((reference, g)) in agreeing
                  and not agreeing[frozenset((reference, g))][0] <= offsets[g][0] <= agreeing[frozenset((reference, g))][1]]:
        late, _, evidence = offsets.pop(group)      # evidence that disagrees: not a clock, not aligned
        for f in findings:
            if f["kind"] == "clock_offset" and evidence.split(":")[0] in f["meaning"]:
                f["meaning"] += (f"; not aligned: a direct comparison finds {group} and {reference} on one clock, so "
                                 f"this {late:+.3f} s is a lag of the signals compared (a filter, a latency), not a clock")
                f["resolved"] = True
    return offsets, findings


def opposite_sign(channels: list[str], s: float, interval, what: str) -> dict:
    """A negative scale between channels that measure one quantity: a sign finding (``what``
    gives its evidence), not a scale."""
    return finding("opposite_sign", channels, s, interval, "ratio",
                   f"{what}: {channels[-1]}'s sign is opposite to the one "
                   f"expected from {', '.join(channels[:-1])}, at {abs(s):.3g} times the size; a sign convention (a "
                   f"steering angle's, an axis mounted upside down): declare it with --signal "
                   f"{channels[-1]}=-COLUMN, or diagnosis takes it for a fault")


SPEED_CHANNELS = ("v", "gnss_speed", "track_speed", "speed_cmd")    # a km/h vs m/s mix-up needs two speeds


def _scale_off(s: float, siv, rev: float) -> bool:
    """A scale off 1 by more than SCALE_TOLERANCE, its interval too, and on both regressions: b on a
    (shrunk by the noise in a) and the inverse of a on b (grown by the noise in b) bracket the true
    ratio; a bracket that holds 1 is no disagreement, only noise (a course rate from wandering fixes
    against a clean gyro)."""
    if not abs(s - 1) > SCALE_TOLERANCE or (siv is not None and siv[0] <= 1 <= siv[1]):
        return False
    if not math.isfinite(rev):
        return True
    lo, hi = min(s, rev), max(s, rev)
    return not lo - SCALE_TOLERANCE <= 1 <= hi + SCALE_TOLERANCE


def _scale_meaning(name: str, a: str, b: str, s: float, rev: float = math.nan) -> str:
    text = f"{name}: {b} is {s:.3g} times {a}"
    if math.isfinite(rev) and abs(rev - s) > 0.02 * abs(s):
        text += f" ({rev:.3g} by {a} on {b}: the true ratio lies between, the noise shrinking each)"
    k = 180 / math.pi
    if any(min(abs(s), abs(rev)) <= f <= max(abs(s), abs(rev)) for f in (k, 1 / k)) if math.isfinite(rev) else False:
        return text + ": a degrees/radians mix-up (declare the unit with --signal COLUMN=EXPR[unit])"
    if abs(abs(s) - 180 / math.pi) < 3 or abs(abs(s) - math.pi / 180) < 0.002:
        return text + ": a degrees/radians mix-up (declare the unit with --signal COLUMN=EXPR[unit])"
    if (abs(s - 3.6) < 0.2 or abs(s - 1 / 3.6) < 0.02) and a in SPEED_CHANNELS and b in SPEED_CHANNELS:
        return text + ": a km/h vs m/s mix-up"
    if s < 0:
        return text + ": the sign is opposite (a mounting or axis convention); diagnosis would take it for a fault"
    if b == "odom_yaw_rate" and s > 1:
        return (text + ": a skid-steered vehicle's wheels slip sideways in a turn, so it turns 1/K times less than "
                "its wheel speeds say (identify's skid-steer model fits K), or the track or a wheel radius is off")
    return (text + ": a wheel radius, a calibration or slip; identification takes the first as the truth, "
            "diagnosis may name it a gain fault")


def mislabelled(aud: Auditor) -> list[dict]:
    """A gyro whose mean is g; a gyro/accelerometer pair swapped; an angle that is a rate."""
    sig, out = aud.streams.signals, []
    if "yaw_rate" in sig:
        r = sig["yaw_rate"][1]
        m, s = float(np.median(r)), float(np.std(r))
        if abs(abs(m) - G) < 0.12 * G and s < 0.3 * abs(m):
            aud.streams.signals.pop("yaw_rate")          # not a yaw rate: never written as one
            out.append(finding("mislabelled_channel", ["yaw_rate"], m, None, "rad/s",
                               f"the 'gyro' yaw_rate sits at {m:.3g} (std {s:.2g}): that is g in m/s2, an "
                               f"accelerometer's vertical axis, not a yaw rate: left out of the log; map the gyro's z "
                               f"axis (--signal yaw_rate=...)"))
            sig = aud.streams.signals
    lateral = next((c for c in LATERAL if c in sig), None)
    if lateral and "v" in sig and "yaw_rate" in sig:
        t, r = sig["yaw_rate"]
        v = np.interp(t, *sig["v"])
        ay = np.interp(t, *sig[lateral])
        moving = np.abs(v) > 0.5
        if moving.sum() > 100:
            # a_y = v r: the relative misfit of that relation, and of the one with the two exchanged
            normal = _misfit(ay[moving], v[moving] * r[moving])
            swapped = _misfit(r[moving], v[moving] * ay[moving])
            if swapped < 0.3 and normal > 2 * swapped and normal > 0.3:
                out.append(finding("mislabelled_channel", ["yaw_rate", lateral], swapped, None, "relative misfit",
                                   f"yaw_rate and {lateral} look swapped: v x {lateral} matches yaw_rate (relative "
                                   f"misfit {swapped:.2f}) while v x yaw_rate misses {lateral} by {normal:.2f}; a gyro "
                                   f"and an accelerometer's channels exchanged: map each to the other"))
    return out


def angle_as_rate(aud: Auditor) -> list[dict]:
    """A steering angle that is a rate: integrated, it follows yaw rate / speed better than as an
    angle. Judged once the speed is signed where the machine reverses (check_direction): with an
    unsigned speed, r = v tan(delta) / L turns its sign in every reversing stretch."""
    sig, out = aud.streams.signals, []
    for steer in ("delta", "delta_cmd"):
        if steer in sig and "v" in sig and "yaw_rate" in sig:
            t, d = sig[steer]
            if len(t) < 100:
                continue
            v = np.interp(t, *sig["v"])
            r = np.interp(t, *sig["yaw_rate"])
            moving = np.abs(v) > 0.5
            if moving.sum() < 100:
                continue
            from scipy.integrate import cumulative_trapezoid
            from scipy.ndimage import uniform_filter1d

            h = float(np.median(np.diff(t)))
            integral = cumulative_trapezoid(d, t, initial=0.0)
            integral = integral - uniform_filter1d(integral, max(3, int(20.0 / h)), mode="nearest")
            as_angle = _corr(v[moving] * d[moving], r[moving])
            as_rate = _corr(v[moving] * integral[moving], r[moving])
            if as_rate > 0.8 and as_rate > as_angle + 0.3:
                out.append(finding("mislabelled_channel", [steer], as_rate, None, "correlation",
                                   f"the angle {steer} behaves as a rate: integrated, it follows the yaw rate / speed "
                                   f"(correlation {as_rate:.2f}, as an angle {as_angle:.2f}); map the steering "
                                   f"angle, not its rate"))
    return out


def _misfit(x, model) -> float:
    """rms(x - model) / rms(x), offsets removed (a bias is not a mislabel)."""
    x, model = np.asarray(x, float), np.asarray(model, float)
    e = (x - x.mean()) - (model - model.mean())
    return float(np.sqrt(np.mean(e ** 2)) / max(np.std(x), 1e-12))


def _corr(x, y) -> float:
    x, y = np.asarray(x, float) - np.mean(x), np.asarray(y, float) - np.mean(y)
    den = math.sqrt(float(x @ x) * float(y @ y))
    return float(x @ y) / den if den > 0 else 0.0


def gaps_findings(aud: Auditor, max_gap: float) -> list[dict]:
    """The gaps of the channels that set the log's span (the receiver's fixes, the canonical
    columns; runs.assemble): bridged up to ``max_gap``, else splitting the log."""
    out = []
    for names, t in aud.stamped(only=CANONICAL + ("heading",)):
        if names == ["gnss"] or (names[0] == "gnss" and len(names) > 1):
            names = ["gnss"] + [n for n in names if n != "gnss"]
        c = ", ".join(names)
        i, length = channel_gaps(t)
        if not len(i):
            continue
        held = all(n in aud.streams.held for n in names)
        short = length <= max_gap
        if short.any():
            out.append(finding("gap_bridged", names, float(length[short].max()), [float(length[short].min()),
                                                                              float(length[short].max())], "s",
                               f"{int(short.sum())} gap(s) of {c} up to {max_gap:g} s bridged "
                               f"({'held: a command stays in force' if held else 'linear'}), the longest "
                               f"{length[short].max():.2f} s; --max-gap 0 splits the log there instead",
                               resolved=True))
        if (~short).any():
            out.append(finding("gap_split", names, float(length[~short].max()), [float(length[~short].min()),
                                                                             float(length[~short].max())], "s",
                               f"{int((~short).sum())} gap(s) of {c} longer than --max-gap {max_gap:g} s split the "
                               f"log (the longest {length[~short].max():.2f} s; --max-gap "
                               f"{math.ceil(10 * length[~short].max()) / 10:g} would bridge them all)"))
    return out


def stamp_findings(report: dict) -> list[dict]:
    """Header stamps against receive times, per source that has both (report["stamp_vs_receive"]:
    {source: {median, p95, min, max}} in s, receive - stamp)."""
    out = []
    for name, s in (report.get("stamp_vs_receive") or {}).items():
        out.append(finding("stamp_vs_receive", [name], s["median"], [s["min"], s["max"]], "s",
                           f"{name}: the messages arrive {s['median']:.3f} s after their header stamps (median; 95 % "
                           f"within {s['p95']:.3f} s, from {s['min']:.3f} to {s['max']:.3f} s); the log uses the header "
                           f"stamps (the time of the measurement), not the receive times", resolved=True))
    return out


def time_base_findings(report: dict, t0: float) -> list[dict]:
    """The readers' findings on their files' clocks (report["time_base"]: {finding, at},
    measurements.time_base), each moment given in s from the recording's start."""
    out = []
    for x in report.get("time_base") or []:
        f = dict(x["finding"])
        if x.get("at") is not None:
            f["meaning"] += f" (at {x['at'] - t0:.2f} s from the recording's start)"
        out.append(f)
    return out


FIX_NAMES = {0: "no fix", 1: "GPS", 2: "DGPS", 3: "PPS", 4: "RTK fixed", 5: "RTK float", 6: "dead reckoning",
             7: "manual", 8: "simulation"}      # NMEA GGA fix quality codes


def fix_quality_findings(gnss, t0: float) -> list[dict]:
    """The receiver's fix quality where it leaves the one it holds longest: each stretch with its
    code, s from the recording's start (the positions' noise differs there)."""
    if gnss is None or "quality" not in gnss:
        return []
    q, t = gnss["quality"].to_numpy(float), gnss["utc"].to_numpy(float)
    ok = np.isfinite(q)
    q, t = q[ok], t[ok]
    if len(q) < 2 or len(np.unique(q)) < 2:
        return []
    cuts = np.flatnonzero(q[1:] != q[:-1]) + 1
    runs = [(q[a], t[a], t[b - 1]) for a, b in zip(np.concatenate([[0], cuts]), np.concatenate([cuts, [len(q)]]))]
    main = held_longest(q)
    others = [(c, a, b) for c, a, b in runs if c != main]
    when = "; ".join(f"{FIX_NAMES.get(int(c), 'code')} ({int(c)}) at {a - t0:.1f}-{b - t0:.1f} s" for c, a, b in others[:20])
    return [finding("fix_quality_changes", ["fix_quality"], len(others), None, "stretches",
                    f"the receiver's fix is {FIX_NAMES.get(int(main), 'code')} ({int(main)}) on "
                    f"{100 * float(np.mean(q == main)):.0f} % of its epochs, and {when}"
                    + (f" (and {len(others) - 20} more)" if len(others) > 20 else "")
                    + ": the positions' noise differs there; the log's fix_quality column holds the source's codes",
                    resolved=True)]


def mode_findings(report: dict, t0: float) -> list[dict]:
    """A declared mode or engagement column's stretches (report["mode_columns"]: {label: [(value,
    start, end)]}): every value but the one held longest named with its stretches, s from the
    recording's start."""
    out = []
    for label, runs in (report.get("mode_columns") or {}).items():
        total: dict[str, float] = {}
        for value, a, b in runs:
            total[value] = total.get(value, 0.0) + b - a
        if len(total) < 2:
            continue
        main = max(total, key=total.get)
        others = [(v, a, b) for v, a, b in runs if v != main]
        when = "; ".join(f"{v} at {a - t0:.1f}-{b - t0:.1f} s" for v, a, b in others)
        out.append(finding("mode_stretches", [label], len(others), None, "stretches",
                           f"{label}: {main} for {total[main]:.0f} s, and {when}: stretches driven otherwise, where "
                           f"the steering need not follow its command; identify and diagnose leave out the stretches "
                           f"the command does not explain (--keep-unexplained keeps them)", resolved=True))
    return out


def held_findings(report: dict) -> list[dict]:
    """The channels held in slower updates than their rows (report["updates"],
    measurements.channel_updates): judged on their updates, so resolved."""
    out = []
    for name, u in (report.get("updates") or {}).items():
        what = "the positions" if name == "gnss" else name
        out.append(finding("held_samples", [name], u["held"], None, "rows per update",
                           f"{what}: {u['updates_hz']:.3g} Hz updates in {u['rows_hz']:.3g} Hz rows (held x"
                           f"{u['held']:.2g}): " + ("a set-point, held as it is sent" if u.get("set_point") else
                                                    (SUM_SAID if u.get("sum") else "") + (
                                                        ROWS_KEPT if u.get("rows_kept") else
                                                        "its rate, noise, derived speed, course and lags are judged "
                                                        "on its updates at their own times")), resolved=True))
        out[-1]["updates_hz"] = float(u["updates_hz"])      # a noise floor is read on them (diagnosis.noise_floor)
    return out


def position_estimate(aud: Auditor, report: dict) -> list[dict]:
    """x, y given as columns whose noise says they are an estimate (a localisation, odometry), not
    a receiver's fixes (measurements.position_source: a receiver's noise is the same across the
    track as along it; an estimate's is held to the course, or absent), or whose source's name
    says so (an odometry, a pose, a filter)."""
    sig = aud.streams.signals
    if aud.streams.gnss is not None or not {"x", "y"} <= set(sig):
        return []
    t, x = sig["x"]
    y = np.interp(t, *sig["y"])
    how = report.get("columns", {}).get("x", "x")
    why = (estimate_evidence(track_noise(np.asarray(t, float), np.asarray(x, float), np.asarray(y, float)))
           or named_estimate(how))
    if why is None:
        return []
    jump = float(np.max(np.hypot(np.diff(x), np.diff(y)))) if len(t) > 1 else 0.0
    return [finding("position_is_estimate", ["x", "y"], jump, None, "m",
                    f"x, y come from {how}: an estimate (localisation, odometry), not a receiver's fixes ({why}); "
                    f"its largest step is {jump:.3g} m; a lever arm or a GNSS latency cannot be judged on it",
                    resolved=False)]


# --- alignment ---------------------------------------------------------------------------------
def parse_align(text: str | None) -> str | dict[str, float]:
    """``auto`` | ``none`` | ``GROUP=SECONDS[,GROUP=SECONDS]`` (seconds the group is late)."""
    text = (text or "auto").strip()
    if text in ("auto", "none"):
        return text
    out = {}
    for part in text.split(","):
        name, eq, value = part.partition("=")
        try:
            seconds = float(value)
        except ValueError:
            seconds = math.nan
        if not eq or not name.strip() or not math.isfinite(seconds):
            raise LogError(f"--align {text!r}: expected auto, none, or GROUP=SECONDS (the seconds GROUP's stamps are "
                           f"late, e.g. bywire=0.85; a group is a file, topic or column of the recording)")
        out[name.strip()] = seconds
    return out


def shift(streams, group_of, offsets: dict[str, float]) -> list[str]:
    """Every channel of each group (or clock that groups share) moved earlier by its offset; the
    channels moved."""
    moved = []
    for c, (t, x) in list(streams.signals.items()):
        g = group_of(c)
        if g in offsets:
            streams.signals[c] = (t - offsets[g], x)
            moved.append(c)
    g = group_of("gnss")
    if g in offsets and streams.gnss is not None:
        streams.gnss = streams.gnss.assign(utc=streams.gnss["utc"] - offsets[g])
        moved.append("gnss")
    return moved


def unchecked_clocks(aud: Auditor, pair_findings: list[dict], applied: dict | None = None,
                     causal: dict | None = None) -> list[dict]:
    """A ``clock_unchecked`` finding (value 0: the offset the join assumes, no interval; said, not
    acted on) for each clock that
    no pair of channels compared with the reference's (the receiver's, else the first), nor the
    ``causal`` check (Auditor.causal: the steering's clock against the gyro's, a response never
    leading its input), nor ``applied`` moved (--align GROUP=SECONDS: the user's word), where
    either counts from its logger's start rather than being a date: their stamps are joined as if
    the loggers started together, which nothing in the recording confirms (dates are taken as one
    time scale, UTC)."""
    channels: dict[str, list[str]] = {}
    stamps: dict[str, np.ndarray] = {}
    for names, t in aud.stamped():
        channels.setdefault(aud.clock(names[0]), []).extend(names)
        stamps.setdefault(aud.clock(names[0]), t)
    compared = {c for f in pair_findings if f["kind"] == "clock_offset" for c in map(aud.clock, f["channels"])}
    compared |= {aud.clock(c) for c in ((causal["input"], "yaw_rate") if causal else ())}
    out = []
    reference = next(iter(channels), None)
    for clock in list(channels)[1:]:
        boot = [c for c in (clock, reference) if is_boot_clock(stamps[c])]
        group = aud.group(channels[clock][0])
        if boot and clock not in compared and not {group, aud.group(channels[reference][0])} & set(applied or {}):
            out.append(finding("clock_unchecked", [channels[reference][0], channels[clock][0]], 0.0, None, "s",
                               f"{', '.join(channels[clock])} ({clock}) joined with {', '.join(channels[reference])} "
                               f"({reference}) as if their clocks started together ({' and '.join(boot)} "
                               f"{'counts' if len(boot) == 1 else 'count'} from a logger's start, not a date); no "
                               f"pair of channels compared them (two speeds, gyro vs GNSS course, v r vs lateral "
                               f"acceleration, two gyros): joined at 0 s, an offset between them is not known, not moved; --align "
                               f"{group}=SECONDS moves {group}'s stamps earlier", resolved=True))
    return out


def audit_streams(streams, options, source) -> dict:
    """The audit of a recording's streams, and the alignment ``options.align`` asks for, applied
    to the streams in place: {channels, findings, alignment}."""
    groups = dict(getattr(streams, "groups", {}) or {})
    t0 = min([float(t[0]) for t, _ in streams.signals.values() if len(t)]
             + ([float(streams.gnss["utc"].iloc[0])] if streams.gnss is not None and len(streams.gnss) else []),
             default=0.0)
    aud = Auditor(streams, groups, options.wheelbase or 1.4, t0)
    channels = aud.channels()
    findings = []
    offsets, pair_findings = estimate_offsets(aud)
    causal_before = aud.causal()
    align = parse_align(getattr(options, "align", "auto"))
    known = sorted({aud.group(c) for c in streams.signals} | ({"gnss"} if streams.gnss is not None else set()))
    span = max((r["end_s"] for r in channels if math.isfinite(r["end_s"])), default=0.0) - \
        min((r["start_s"] for r in channels if math.isfinite(r["start_s"])), default=0.0)
    applied: dict[str, float] = {}
    how = "none"
    if isinstance(align, dict):
        for name, seconds in align.items():
            group = name if name in known else aud.group(name) if name in streams.signals else None
            if group is None:
                raise LogError(f"{source}: --align {name}={seconds:g}: no group or column {name!r}; groups: "
                               f"{', '.join(known)}")
            if abs(seconds) >= span:
                raise LogError(f"{source}: --align {name}={seconds:g}: a realignment of {abs(seconds):g} s is larger "
                               f"than the recording ({span:.3g} s); expected the seconds {name}'s stamps are late")
            applied[group] = seconds
        how = "given (--align)"
    elif align == "auto":
        applied = {g: o[0] for g, o in offsets.items()}
        how = "auto: the offsets found strong (--align none keeps the stamps; --align GROUP=SECONDS sets one)"
    moved = shift(streams, aud.clock, {aud.group_clock(g): s for g, s in applied.items()}) if applied else []
    for f in pair_findings:
        if f["kind"] == "clock_offset" and applied:
            ga, gb = aud.group(f["channels"][0]), aud.group(f["channels"][1])
            if ga in applied or gb in applied:
                f["resolved"] = True
                f["meaning"] += f"; aligned: {', '.join(f'{g} moved {-s:+.3f} s' for g, s in applied.items())}"
    findings += pair_findings + unchecked_clocks(aud, pair_findings, applied, causal_before)
    for f in pair_findings:
        g = next((aud.group(c) for c in f["channels"] if aud.group(c) in offsets and aud.group(c) not in applied), None)
        if f["kind"] == "clock_offset" and not f["resolved"] and g is not None:
            f["meaning"] += f"; not aligned (--align {getattr(options, 'align', 'auto')}): --align {g}={offsets[g][0]:.3f} corrects it"
    causal = aud.causal() if applied else causal_before
    if causal is not None:
        findings.append(_causality(causal, causal_before, applied))
    steady = aud.steady_sign()
    if steady is not None and not any(f["kind"] == "opposite_sign" and "yaw_rate" in f["channels"] for f in findings):
        findings.append(steady)
    findings += mislabelled(aud)
    unit_mixups(aud, findings, options)
    findings += gyro_unit_by_steering(aud, causal, options)
    findings += out_of_range(aud)
    clock = streams.report.get("terminal_clock")
    if clock:
        findings.append(finding("terminal_clock", ["t", "gnss_time"], clock["offset_s"], clock["range_s"], "s",
                                f"the terminal's clock (labelled UTC) is {clock['offset_s']:+.3f} s from the GNSS time "
                                f"in the same records ({clock['terminal_start']} vs {clock['gnss_start']}); every "
                                f"channel is on the terminal's clock, so they agree with each other: only the "
                                f"absolute time is off", resolved=True))
    findings += stamp_findings(streams.report)
    findings += time_base_findings(streams.report, t0)
    findings += mode_findings(streams.report, t0)
    findings += fix_quality_findings(streams.gnss, t0)
    findings += held_findings(streams.report)
    findings += axis_findings(streams.report)
    try:
        findings += check_direction(streams, options, source, t0)
        refusal = None
    except LogError as exc:           # every other channel judged before it refuses
        refusal = exc
    findings += angle_as_rate(aud) + gaps_findings(aud, getattr(options, "max_gap", 0.5)) + position_estimate(aud, streams.report)
    if refusal is not None:
        raise with_findings(refusal, findings)
    return {"channels": channels, "findings": findings,
            "alignment": {"mode": how, "offsets_s": applied, "channels_moved": moved,
                          "found": {g: {"late_s": o[0], "interval_s": o[1], "evidence": o[2]}
                                    for g, o in offsets.items()}}}


def with_findings(exc: LogError, findings: list[dict]) -> LogError:
    """A refusal that lists the audit's other findings (one refusal hides none of them)."""
    said = [f"{f['kind']} ({', '.join(f['channels'])}): {f['meaning']}" for f in findings]
    if not said:
        return exc
    return LogError(f"{exc}\nthe audit's other findings ({len(said)}):\n" + "\n".join(f"  - {x}" for x in said))


MIXUPS = {"yaw_rate": (180 / math.pi, "deg/s", "rad/s"), "v": (3.6, "km/h", "m/s")}
MIXUP_TOLERANCE = 0.03      # a scale within 3 % of a unit factor is that unit


def unit_mixups(aud: Auditor, findings: list[dict], options) -> None:
    """A channel whose unit no one declared (taken as the log's SI convention) that a channel of
    another source measures at a unit factor's scale (57.3: deg/s for rad/s; 3.6: km/h for m/s;
    within MIXUP_TOLERANCE) is in that unit: converted in place, its finding
    resolved with the factor and the option that keeps it as it is."""
    columns = aud.streams.report.get("columns", {})
    for f in findings:
        b = f["channels"][-1]
        if f["kind"] != "scale_disagreement" or b not in MIXUPS or b not in aud.streams.signals:
            continue
        k, unit, si = MIXUPS[b]
        assumed = "the log's convention" in str(columns.get(b, ""))
        if not assumed or abs(f["value"] / k - 1) > MIXUP_TOLERANCE:
            continue
        aud.divide(b, k, unit, f["channels"][0])
        f["resolved"] = True
        f["meaning"] += (f"; {b} declared no unit and was taken as {si}: it is in {unit}, divided by {k:.4g} (declare "
                         f"its unit with --signal {b}=COLUMN[{si}] to keep it as written)")


GYRO_SUSPECT = 3.0          # rad/s: a yaw rate whose 99.5th percentile of |r| passes this may be deg/s
STEERING_EVIDENCE = 0.6     # the correlation of r with v tan(delta) / L that decides its unit


def gyro_unit_by_steering(aud: Auditor, causal: dict | None, options) -> list[dict]:
    """A yaw rate with no declared unit whose size passes GYRO_SUSPECT, with no other yaw source
    that decided it: its unit read from the turns the steering implies, r = s v tan(delta) / L
    (L the declared wheelbase, else 1.4 m). In rad/s s is the wheelbase's ratio and the tyres'
    (0.3-3 on any machine), in deg/s 57.3 times that: deg/s where s is nearer 57.3 than 1 (on a
    log scale: above sqrt(57.3) = 7.6) and the correlation reaches STEERING_EVIDENCE; then divided
    by 57.3 and named, with the option that keeps it. Undecided: a finding that says why."""
    sig, columns = aud.streams.signals, aud.streams.report.get("columns", {})
    if "yaw_rate" not in sig or "the log's convention" not in str(columns.get("yaw_rate", "")) \
            or "yaw_rate" in aud.unit_converted:
        return []
    t, r = sig["yaw_rate"]
    peak = float(np.percentile(np.abs(r), 99.5)) if len(r) else 0.0
    if not peak > GYRO_SUSPECT:
        return []
    k = 180 / math.pi
    L = f"L {aud.L:g} m" + (" declared" if getattr(options, "wheelbase", None) else " assumed: --wheelbase gives the machine's")
    if causal is None or not causal.get("rho", 0) >= STEERING_EVIDENCE or not math.isfinite(causal.get("scale", math.nan)):
        why = "no steering and speed to compare" if causal is None else \
            f"r against v tan({causal['input']}) / L correlates {causal.get('rho', math.nan):.2f} (below {STEERING_EVIDENCE})"
        return [finding("unit_undecided", ["yaw_rate"], peak, None, "as written",
                        f"yaw_rate reaches {peak:.3g} (99.5 %): rad/s or deg/s is not decided: {why}, and no other yaw "
                        f"source measures it; declare its unit (--signal yaw_rate=COLUMN[deg/s] or [rad/s])")]
    scale = abs(float(causal["scale"]))
    if not scale > math.sqrt(k):
        return [finding("unit_undecided", ["yaw_rate"], peak, None, "as written",
                        f"yaw_rate reaches {peak:.3g} (99.5 %), yet it is {scale:.3g} times v tan({causal['input']}) / L "
                        f"({L}; correlation {causal['rho']:.2f}): rad/s by the steering, too large by its size; declare "
                        f"its unit (--signal yaw_rate=COLUMN[deg/s] or [rad/s])")]
    aud.divide("yaw_rate", k, "deg/s", "the steering")
    return [finding("unit_by_steering", ["yaw_rate"], k, None, "factor",
                    f"yaw_rate is {scale:.3g} times v tan({causal['input']}) / L ({L}; correlation "
                    f"{causal['rho']:.2f}): nearer 57.3 (deg/s) than 1 (rad/s; passed over: the wheelbase and the tyres "
                    f"explain 0.3-3), and reaches {peak:.3g} as written: it is in deg/s, divided by {k:.4g} (declare "
                    f"--signal yaw_rate=COLUMN[rad/s] to keep it as written)", resolved=True)]


# a ground vehicle's channel beyond these is not a measurement (a sentinel, an overflow, a wrong field)
PHYSICAL = {"v": (100.0, "m/s"), "gnss_speed": (100.0, "m/s"), "yaw_rate": (10.0, "rad/s"), "delta": (1.57, "rad"),
            "delta_cmd": (1.57, "rad")}


def out_of_range(aud: Auditor) -> list[dict]:
    """Each channel with samples beyond its physical range (PHYSICAL): how many, the largest, when."""
    out = []
    for c, (bound, unit) in PHYSICAL.items():
        if c not in aud.streams.signals:
            continue
        t, x = aud.streams.signals[c]
        bad = np.abs(x) > bound
        if bad.any():
            i = np.flatnonzero(bad)
            out.append(finding("out_of_range", [c], float(np.max(np.abs(x[bad]))), None, unit,
                               f"{c}: {len(i)} of {len(x)} samples beyond {bound:g} {unit}, which no ground vehicle "
                               f"reaches (the largest {np.max(np.abs(x[bad])):.4g} {unit}, the first at "
                               f"{t[i[0]] - aud.t0:.2f} s): a sentinel, an overflow, a wrong field or unit; mask them "
                               f"(--time-range around them) or map the right field" + _in_degrees(c, x, bad, bound)))
    for s in aud.streams.report.get("spikes") or []:       # masked already as spikes: named for what they are
        bound, unit = PHYSICAL.get(s["column"], (math.inf, ""))
        beyond = [v for v in s["values"] if abs(v) > bound]
        if beyond:
            out.append(finding("out_of_range", [s["column"]], max(map(abs, beyond)), None, unit,
                               f"{s['column']}: {len(beyond)} spike(s) beyond {bound:g} {unit}, which no ground vehicle "
                               f"reaches (the largest {max(map(abs, beyond)):.4g} {unit}, at "
                               f"{', '.join(f'{x:g}' for x in s['times_s'][:5])} s): a sentinel or an overflow; "
                               + ("kept (--keep-spikes)" if s.get("kept") else "masked as spikes"),
                               resolved=not s.get("kept")))
    return out


def _in_degrees(c: str, x: np.ndarray, bad: np.ndarray, bound: float) -> str:
    """'; ...' when the channel, an angle or a yaw rate, is out of range in a tenth of its samples or
    more and every sample would be within it read as degrees (x / 57.3): the unit to declare."""
    k = 180 / math.pi
    if c not in ("yaw_rate", "delta", "delta_cmd") or bad.mean() < 0.1 or np.max(np.abs(x)) / k > bound:
        return ""
    unit = "deg/s" if c == "yaw_rate" else "deg"
    return (f"; read as {unit} every sample is within it (the largest {np.max(np.abs(x)) / k:.3g}): a channel in "
            f"{unit} declared in radians? --signal {c}=COLUMN[{unit}]")


def _causality(now: dict, before: dict | None, applied: dict) -> dict:
    """The causality finding of steering x speed -> yaw rate."""
    chans = [now["input"], "v", "yaw_rate"]
    late, iv = now["lag"], now["interval"]
    hi = iv[1] if iv else late
    what = f"yaw_rate follows v tan({now['input']}) / L {late:+.3f} s late (correlation {now['rho']:.2f})"
    weak = [why for why, bad in (("correlation below 0.3", now["rho"] < 0.3),
                                 (f"the peak on the search's bound (+-{SEARCH:g} s)", now.get("edge")),
                                 (f"an input that barely changes ({now.get('input_changes', 0)} changes of "
                                  f"{now['input']} and v)", now.get("input_changes", MIN_INPUT_CHANGES) < MIN_INPUT_CHANGES))
            if bad]
    if weak:
        return finding("response_lag", chans, late, iv, "s", what + ": too weak to judge causality ("
                       + "; ".join(weak) + ")", resolved=True)
    if now.get("inverted") and now["rho"] >= 0.5:
        return opposite_sign(chans, now["scale"], now["scale_interval"], f"yaw_rate is {now['scale']:.3g} times v "
                             f"tan({now['input']}) / L, {late:+.3f} s late (correlation {now['rho']:.2f} with the sign "
                             f"turned)")
    if hi < -LEAD_TOLERANCE:
        return finding("response_leads_input", chans, -late, None if iv is None else [-iv[1], -iv[0]], "s",
                       f"the yaw rate answers {-late:.3f} s BEFORE the steering x speed that causes it: the channels' "
                       f"clocks disagree; identification would put its delay on the zero bound and diagnosis name "
                       f"lever arms and biases that are not there. Align the clocks: --align GROUP=SECONDS (the "
                       f"steering's group late by about {-late:.2f} s plus the vehicle's own delay)")
    if before is not None and before["rho"] >= 0.3 and (before["interval"] or [0, before["lag"]])[1] < -LEAD_TOLERANCE:
        return finding("response_leads_input", chans, -before["lag"], None, "s",
                       f"before alignment the yaw rate answered {-before['lag']:.3f} s before the steering; after "
                       f"({', '.join(f'{g} {-s:+.3f} s' for g, s in applied.items())}) {what}", resolved=True)
    return finding("response_lag", chans, late, iv, "s", what + ": causal (the response follows its input)",
                   resolved=True)


# --- consumers ---------------------------------------------------------------------------------
FLOOR = 2.0 / 3.0       # a nominal minimum is guidance down to this fraction of it


def minimum(have: float, nominal: float, what: str, unit: str = "s", floor: float = FLOOR) -> str | None:
    """A stage's nominal minimum as guidance: None at or above it; a warning naming both numbers
    between ``floor`` x nominal and nominal; a LogError below the floor, naming both."""
    if have >= nominal:
        return None
    if have >= floor * nominal:
        return (f"warning: {what} is {have:.3g} {unit}, under the nominal {nominal:.3g} {unit} but above its floor "
                f"{floor * nominal:.3g} {unit}: used; the results are less certain")
    raise LogError(f"{what} is {have:.3g} {unit}, under the floor {floor * nominal:.3g} {unit} ({floor:.2g} of the "
                   f"nominal {nominal:.3g} {unit})")
def require_causal(frame, what: str) -> None:
    """A LogError when the log's audit found a response that leads its input, unresolved: its
    dynamics cannot be judged (``what``: the tool that refuses)."""
    for f in frame.attrs.get("audit", []) or []:
        if f.get("kind") == "response_leads_input" and not f.get("resolved"):
            raise LogError(f"{what}: the log's {', '.join(f['channels'])}: {f['meaning']}; the dynamics of a log whose "
                           f"response leads its input are not judged")


def describe_audit(audit: dict) -> list[str]:
    """The audit as terminal lines."""
    lines = ["  audit, per channel: rate, gaps (count, longest, when), repeated stamps, group (its clock)"]
    for r in audit.get("channels", []):
        names = r["channel"].split(", ")
        name = ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")
        lines.append(f"    {name:<14} {r['rate_hz']:7.3g} Hz"
                     + (f" updates in {r['rows_hz']:.3g} Hz rows (held x{r['held']:.2g})" if r.get("held") else "")
                     + f"  {r['samples']:>7} samples  {r['start_s']:8.2f}-"
                     f"{r['end_s']:.2f} s  gaps {r['gaps']}"
                     + (f" (longest {r['longest_gap_s']:.2f} s, at {', '.join(f'{x:g}' for x in r['gaps_at_s'])} s)"
                        if r["gaps"] else "")
                     + (f"  repeated stamps {r['repeated_stamps']}" if r["repeated_stamps"] else "")
                     + f"  group {r['group']}")
    for f in audit.get("findings", []):
        iv = f" {_interval_text(f['interval'], f['unit'])}" if f["interval"] else ""
        value = f"{f['value']:.4g} {f['unit']}" if math.isfinite(f["value"]) else "not known"
        lines.append(f"  audit {f['kind']}{' (resolved)' if f['resolved'] else ''}: {value}{iv}: {f['meaning']}")
    a = audit.get("alignment", {})
    if a.get("offsets_s"):
        lines.append(f"  aligned ({a['mode']}): " + ", ".join(f"{g} moved {-s:+.3f} s" for g, s in a["offsets_s"].items())
                     + f"; channels moved: {', '.join(a['channels_moved'])}")
    elif a.get("found"):
        lines.append(f"  not aligned ({a['mode']}): " + ", ".join(f"{g} {o['late_s']:+.3f} s late" for g, o in a["found"].items()))
    return lines



def audit_frame(frame) -> list[dict]:
    """The findings of a log table read as it is (one clock for every column, nothing moved):
    the causality check, the scales of redundant columns and the signs of a mislabel. A log
    that ``convert`` wrote carries its import's audit instead (measurements.log.persisted_audit)."""
    t = frame["t"].to_numpy(float)
    names = [c for c in frame.columns if c != "t" and (c in CANONICAL or c in LATERAL or str(c).startswith("yaw_rate_")
                                               or c == "odom_yaw_rate")]
    signals = {c: (t, frame[c].to_numpy(float)) for c in names}
    streams = Streams(None, signals, {}, {"delta_cmd"} & set(signals), {}, groups={c: "log" for c in signals})
    try:
        found = audit_streams(streams, ImportOptions(wheelbase=1.4, align="none", max_gap=0.0), "log")["findings"]
    except LogError:
        return []
    return [f for f in found if f["kind"] not in ("gap_bridged", "gap_split")]
