"""The replay of a log, the baseline fit and the least-squares fit of any set of parameters
(the selection of several effects is diagnosis.selection).

The log is split in time: the first ``fit_fraction`` is for fitting, the rest is held out; when the
held-out part drives beyond the conditions of the fit part (``split_conditions``: its lateral
acceleration or speed well above what the fit saw), it would test extrapolation rather than the
model, and every third ``window`` of the log is held out instead (``split="blocks"``). Each
stage's residual is normalised by the baseline's noise level, so a fit that touches two stages
(the gyro bias changes the yaw stage and the dead-reckoned track) weighs them fairly. The position stage's residual is each window's aligned track residual whitened
by the dead reckoning's own noise, the gyro's drift and the speed's (replay.TrackWhitening), ordered
by time along each axis.

Score (Gaussian likelihood, per-stage unknown variance, autocorrelation-corrected sample size)::

    dBIC = sum_s n_eff,s ln(RSS_s,after / RSS_s,before) + k ln(sum_s n_eff,s)
    n_eff = n (1 - rho1) / (1 + rho1),  rho1 the lag-1 autocorrelation of the fitted residuals

(diagnosis.selection judges an effect with this score: supported when dBIC < -10, the held-out
RMS of its main signal falls by ``min_gain``, no other rises by 5%, and the value is material.)
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import pandas as pd
from scipy.ndimage import convolve1d

from agrobot.estimation import FitResult, effective_size, solution_covariance, updates_on
from agrobot.identification.ordinary_driving import similar_columns
from agrobot.measurements import LogError
from agrobot.measurements.log import check_units, resolution, speed_estimate

from .baseline import CORNERING_SCALES, IMPLAUSIBLE, Baseline, held_tyres, implausible_tyres, unpinned, widened_ranges
from .catalogue import UNCERTAIN, Parameter
from .noise_floor import track_level, track_samplings
from agrobot.measurements.own_samples import reading
from .replay import (SaturatedYawReplay, YawReplay, aligned_residuals, antenna_track, chords, exact, heading_estimate,
                     measured_yaw_rate, saturates, steering_plant, steering_replay, TrackWhitening, track_residual_vector,
                     wheel_angle_input)
from .fit_memo import recalled, remembered
from .steering_map import mapped_steering
from .weighted_search import WeightedSearch

STAGES = ("steering", "yaw", "position", "speed")


class CannotDecide(Exception):
    """The log holds too little to tell one model from another."""


# what each stage reads; "speed" is v, else the receiver's gnss_speed, else the GPS track's speed
STAGE_NEEDS = {"steering": ("delta_cmd", "delta"), "yaw": ("delta", "yaw_rate", "speed"),
               "position": ("x", "y", "yaw_rate", "speed not from the track"), "speed": ("x", "y", "yaw_rate", "v")}
NEED_TEXT = {"speed": "speed (v, gnss_speed, or x and y)",
             "speed not from the track": "measured speed (v or gnss_speed: the track's own speed cannot judge the track)"}
MIN_RATE = {"steering": 10.0, "yaw": 10.0, "position": 5.0, "speed": 5.0}      # Hz a stage needs
RATE_TOLERANCE = 1e-6   # a log averaged onto exactly MIN_RATE may compute a hair under it (time stamps' rounding)
MAX_POSITION_STEP = 0.01       # m: coarser positions (float32 latitude/longitude) cannot judge centimetres
COARSE_DELTA = 0.2 * math.pi / 180    # rad: a wheel-angle sensor this coarse biases the yaw refit
HARD_MIN_DURATION = 30.0      # s: shorter logs are refused; up to min_duration they are judged with a warning
MIN_COMMANDED_YAW = 0.0125     # rad/s: 0.5 deg of steering at 2 m/s on the paper tractor's 1.4 m wheelbase
SIDE_SLIP_LOOSENESS = 0.15     # the fraction of C_r a yaw-rate fit leaves loose (the truths' stiffness spread)
SIDE_SLIP_ARM = 0.15           # m: the smallest material lever arm (effects.antenna_lever_arm)
REWEIGHTS = 4                  # at most this many refits of a side-slip block at its own residual levels
SPLITS = ("auto", "tail", "blocks")
BEYOND = 1.5                   # the held-out part's 95th percentile above this x the fit part's: beyond its conditions
BEYOND_MARGIN = {"lateral acceleration |v yaw_rate|": 0.5, "speed": 0.5}    # m/s2, m/s: and by at least this much


def split_conditions(t: np.ndarray, speed: np.ndarray, gyro: np.ndarray, moving: np.ndarray,
                     t_split: float) -> str | None:
    """Why the part after ``t_split`` lies beyond the conditions of the part before (the 95th
    percentile of |a_y| = |v r| or of the speed, while moving, above BEYOND x the fit part's and by
    BEYOND_MARGIN), or None. A log driven harder in its last part (faster, nearer the grip limit)
    held out there judges a model fitted on gentler driving on conditions it never saw."""
    before, after = moving & (t < t_split), moving & (t >= t_split)
    if before.sum() < 20 or after.sum() < 20:
        return None
    a = np.abs(speed * gyro)
    for name, x, unit in (("lateral acceleration |v yaw_rate|", a, "m/s2"), ("speed", np.abs(speed), "m/s")):
        ok = np.isfinite(x)
        if (before & ok).sum() < 20 or (after & ok).sum() < 20:
            continue
        p0, p1 = (float(np.percentile(x[m & ok], 95)) for m in (before, after))
        if p1 > BEYOND * p0 and p1 - p0 >= BEYOND_MARGIN[name]:
            return (f"the log's last part (t >= {t_split:.1f} s) is driven beyond its first: 95th percentile of the "
                    f"{name} {p1:.3g} {unit} against {p0:.3g} {unit}")
    return None


def position_step(xy: np.ndarray) -> float:
    """The step positions move in when they are quantised (float32 latitude/longitude: 0.1-1 m),
    else 0: the smallest move between samples above a millimetre (the projection to east/north
    mixes a little of the other axis' steps into each), when nearly every such move is a whole
    number of it (on either axis)."""
    steps = []
    for col in np.asarray(xy, float).T:
        d = np.abs(np.diff(col))
        d = d[d > 1e-3]
        if len(d) < 20:
            continue
        q = float(np.percentile(d, 1))
        if q <= 0:
            continue
        r = d / q
        if np.mean(np.abs(r - np.round(r)) < 0.05) > 0.9:
            steps.append(q)
    return max(steps) if steps else 0.0


def near_joins(t: np.ndarray, joins, before: float, after: float) -> np.ndarray:
    """Samples from ``before`` s ahead of a join (the first sample of a joined stretch) to
    ``after`` s past it."""
    out = np.zeros(len(t), bool)
    for j in joins:
        out |= (t >= j - before - 1e-9) & (t < j + after)
    return out


@dataclass
class Replay:
    """The log's arrays, the split and the stage replays. A partial log replays the stages its
    columns allow (``stages``); ``not_judged`` says why each other one is not judged."""

    frame: pd.DataFrame
    baseline: Baseline
    fit_fraction: float = 0.6
    split: str = "auto"                 # SPLITS: the last part held out, every third window, or chosen
    burn_in: float = 3.0
    window: float = 10.0
    min_speed: float = 0.3
    min_duration: float = 60.0
    kernel: str = "auto"                # the stage replays in C or in Python (replay_kernels.KERNELS)

    def __post_init__(self) -> None:
        f = self.frame
        n = len(f)
        self.t = f["t"].to_numpy(float)
        self.h = float(np.median(np.diff(self.t)))

        def column(name):
            return f[name].to_numpy(float) if name in f else np.full(n, np.nan)

        self.cmd, self.delta, self.gyro = column("delta_cmd"), column("delta"), column("yaw_rate")
        self._read_yaw(f)
        vehicle = self.baseline.vehicle
        # no measured wheel angle, an angle-commanded steering: the yaw stage is driven by the
        # steering replayed from delta_cmd, whose parameters it then judges; ``delta`` holds the
        # baseline's replayed angle for the evidence (correlations, binning)
        self.command_only = "delta" not in f and "delta_cmd" in f and vehicle.steering == "angle"
        if self.command_only:
            self.delta = steering_replay(self.cmd, self.h, self.baseline.values, float(self.cmd[0]), self.kernel)
        self.gps = np.column_stack([column("x"), column("y")])
        speed, self.speed_source = speed_estimate(f)
        self.speed = speed if speed is not None else np.full(n, np.nan)
        self.stages, self.not_judged = self._stages(f)
        q = f.attrs.get("resolution", {}).get("delta") or (resolution(self.delta) if "delta" in f else 0.0)
        self.coarse_delta = q > COARSE_DELTA
        duration = self.t[-1] - self.t[0]
        if duration < HARD_MIN_DURATION:
            raise CannotDecide(f"the log lasts {duration:.2f} s; a diagnosis needs at least {HARD_MIN_DURATION:.0f} s: "
                               f"a fit part and a held-out part of {self.window:.0f} s windows each, after a "
                               f"{self.burn_in:.0f} s burn-in (record at least {self.min_duration:.0f} s, better 180 s)")
        if not self.stages:
            raise CannotDecide("nothing to judge: " + "; ".join(f"{s} {why}" for s, why in self.not_judged.items()))
        moving = self.speed > self.min_speed if speed is not None else np.ones(n, bool)
        if speed is not None and moving.mean() < 0.5 and set(self.stages) - {"steering"}:
            raise CannotDecide(f"the vehicle moves (v > {self.min_speed} m/s) in only {100 * moving.mean():.0f}% "
                               f"of the log; the yaw and position replays need it moving")
        if ("steering" in self.stages or self.command_only) and self.commanded_yaw() < MIN_COMMANDED_YAW:
            raise CannotDecide(f"delta_cmd hardly varies: it would turn the vehicle at {self.commanded_yaw():.3g} rad/s "
                               f"(std of v delta_cmd / wheelbase; below {MIN_COMMANDED_YAW} rad/s, 0.5 deg of steering "
                               f"at 2 m/s on the paper tractor): nothing excites the steering and yaw dynamics")
        try:
            check_units(f, "log")
        except LogError as exc:
            raise CannotDecide(str(exc).removeprefix("log: ")) from None
        self.t_split = t_split = self.t[0] + self.fit_fraction * duration
        settled = ~near_joins(self.t, f.attrs.get("joins", ()), 0.0, self.burn_in)    # each joined stretch burns in
        after_burn, moving = (self.t >= self.t[0] + self.burn_in) & settled, moving & settled
        held = self._held_out(t_split, moving)
        steering = {"fit": after_burn & ~held, "test": held & settled}
        # samples scored per stage and part (the yaw replay only where the tractor moves)
        self.masks = {"steering": steering, "yaw": {k: m & moving & self.yaw_measured for k, m in steering.items()}}
        # speed: the GPS chord speed (1 s chords, centred) where a chord exists and the tractor moves
        k, d = chords(self.gps, self.h)
        self.chord_k, self.chord_span = k, 2 * k * self.h
        self.track_speed = np.full(len(self.t), np.nan)
        self.track_speed[k:-k] = np.hypot(d[:, 0], d[:, 1]) / self.chord_span
        self.track_speed[near_joins(self.t, f.attrs.get("joins", ()), k * self.h, k * self.h)] = np.nan
        has_chord = np.isfinite(self.track_speed)
        self.masks["speed"] = {p: m & has_chord for p, m in self.masks["yaw"].items()}
        has_track = {"x", "y"} <= set(f.columns) and "yaw_rate" in f
        self.heading = heading_estimate(self.t, self.gps, self.gyro, self.speed) if has_track else np.zeros(n)
        if "yaw" in self.stages:
            self.yaw = YawReplay(self.baseline.yaw_model, self.baseline.tractor, self.h, self.delta, self.speed,
                                 self.heading, min_speed=self.min_speed, kernel=self.kernel,
                                 geometry=self.baseline.steering_geometry)
        L = int(round(self.window / self.h))
        starts = np.arange(0, len(self.t) - L + 1, L)
        rows = starts[:, None] + np.arange(L)[None, :]
        rows = rows[np.all(moving[rows], axis=1)]
        self.windows = {"fit": rows[~held[rows].any(axis=1)], "test": rows[held[rows].all(axis=1)]}
        if "position" in self.stages and (len(self.windows["fit"]) < 3 or len(self.windows["test"]) < 2):
            why = (f"too few {self.window:.0f} s stretches of driving for the position and speed replays "
                   f"({len(self.windows['fit'])} to fit, {len(self.windows['test'])} held out; need 3 and 2)")
            if self.stages == ("position",) or set(self.stages) <= {"position", "speed"}:
                raise CannotDecide(why)
            for stage in ("position", "speed"):
                if stage in self.stages:
                    self.not_judged[stage] = f"not judged: {why}"
            self.stages = tuple(s for s in self.stages if s not in ("position", "speed"))
        if "position" in self.stages:
            self.__dict__["track_noise"] = self.track_noise     # read once, before any fit's tracks

    def _read_yaw(self, f: pd.DataFrame) -> None:
        """What measures the yaw (identification.yaw_measurement): a yaw rate from the GNSS course
        says nothing on slow stretches (nan): not judged there (``yaw_measured``), bridged linearly
        for the dead-reckoned track; one derived from a heading averages the true one (``yaw_kernel``)."""
        self.yaw_measured = np.isfinite(self.gyro) if "yaw_rate" in f else np.ones(len(self.t), bool)
        derived = f.attrs.get("yaw_measurement")
        self.yaw_kernel = derived.kernel(self.h) if derived is not None else None
        self.yaw_sampling = reading(f, "yaw_rate", self.gyro) if derived is None and "yaw_rate" in f else None
        self.yaw_update_times = getattr(derived, "update_times", None)
        if "yaw_rate" in f and not self.yaw_measured.all() and self.yaw_measured.sum() >= 2:
            self.gyro = np.interp(self.t, self.t[self.yaw_measured], self.gyro[self.yaw_measured])

    def _held_out(self, t_split: float, moving: np.ndarray) -> np.ndarray:
        """The held-out samples: after ``t_split`` (split "tail"), or every third ``window`` of the
        log (split "blocks"; "auto" takes it when the last part lies beyond the first's conditions,
        split_conditions). Sets ``split`` to the one taken and ``split_note`` to why."""
        if self.split not in SPLITS:
            raise ValueError(f"split {self.split!r}: expected one of {SPLITS}")
        self.split_note = None
        if self.split == "auto":
            why = split_conditions(self.t, self.speed, self.gyro, moving, t_split)
            self.split = "blocks" if why else "tail"
            if why:
                self.split_note = (f"{why}: held out there, it would judge a model fitted on gentler driving on "
                                   f"conditions it never saw; every third {self.window:.0f} s of the log is held out "
                                   f"instead (--split tail holds out the last {100 * (1 - self.fit_fraction):.0f} %)")
        return self.unseen(self.t)

    def unseen(self, t: np.ndarray) -> np.ndarray:
        """Whether times ``t`` fall in the held-out part of the split taken."""
        t = np.asarray(t, float)
        if self.split == "tail":
            return t >= self.t_split
        return np.floor((t - self.t[0]) / self.window).astype(int) % 3 == 2

    def held_out_spans(self) -> list[tuple[float, float]]:
        """The held-out part as (start, end) times."""
        held = self.masks["steering"]["test"].astype(int)
        edges = np.flatnonzero(np.diff(np.r_[0, held, 0]))
        return [(float(self.t[a]), float(self.t[b - 1])) for a, b in zip(edges[::2], edges[1::2])]

    def updates(self, stage: str) -> int | None:
        """The measurement's own updates on a stage's fit part, which bound its effective samples
        (estimation.effective_size): a yaw rate derived from a 5 Hz heading on 20 Hz rows has a
        quarter of the rows'; None: one per row."""
        return self._fit_updates if stage == "yaw" else None

    @cached_property
    def _fit_updates(self) -> int | None:
        """``updates`` of the yaw stage, counted once (the fit part is fixed with the replay)."""
        if self.yaw_update_times is None:
            return None
        return updates_on(self.yaw_update_times, self.t, self.h, self.masks["yaw"]["fit"])

    def commanded_yaw(self) -> float:
        """The excitation of the steering command as the yaw rate it asks for, std(v delta_cmd / L):
        degrees of steering at a tractor's 2 m/s, tenths of a degree at a car's 30 m/s."""
        p = self.baseline.tractor
        v = np.nan_to_num(self.speed, nan=0.0) if self.speed_source != "none" else np.full(len(self.cmd), 2.0)
        return float(np.std(v * np.nan_to_num(self.cmd) / (p.l_f + p.l_r)))

    def _stages(self, f: pd.DataFrame) -> tuple[tuple[str, ...], dict[str, str]]:
        """The stages the log's columns, rate and resolution allow, and why not the others."""
        have = set(f.columns) | ({"speed"} if self.speed_source != "none" else set())
        if self.command_only:
            have.add("delta")
        if self.speed_source in ("v", "gnss_speed"):
            have.add("speed not from the track")
        rate = 1.0 / self.h
        step = position_step(self.gps) if {"x", "y"} <= set(f.columns) else 0.0
        stages, why = [], {}
        for stage, needs in STAGE_NEEDS.items():
            missing = [c for c in needs if c not in have]
            if stage == "steering" and self.command_only:
                missing = ["delta"]
            if stage in self.baseline.vehicle.not_applicable():
                why[stage] = "not judged: " + self.baseline.vehicle.not_applicable()[stage]
            elif missing:
                why[stage] = "not judged: no " + ", no ".join(_named(c, f.columns) for c in missing)
                if stage == "steering" and self.command_only and {"yaw_rate", "speed"} <= have:
                    why[stage] += (" (the log has only the command delta_cmd: the steering's delay, lag, dead-band and "
                                   "rate limit are judged through the yaw rate instead)")
            elif rate < MIN_RATE[stage] * (1.0 - RATE_TOLERANCE):
                why[stage] = (f"not judged: the log samples at {rate:.3g} Hz; the {stage} stage needs "
                              f"{MIN_RATE[stage]:g} Hz or more (steering time constants of tens of ms, yaw modes "
                              f"near 2 Hz)")
            elif stage in ("position", "speed") and getattr(f.attrs.get("yaw_measurement"), "kind", "") == "GNSS course":
                why[stage] = (f"not judged: the yaw rate comes from the GNSS course of these positions (no gyro, no "
                              f"heading): the {stage} stage would judge the positions against themselves")
            elif stage in ("position", "speed") and step > MAX_POSITION_STEP:
                why[stage] = (f"not judged: the positions move in steps of {step:.3g} m (float32 latitude/longitude?); "
                              f"the {stage} stage judges centimetres")
            else:
                stages.append(stage)
        if "speed" in stages and self.speed_source != "v":
            stages.remove("speed")
            why["speed"] = "not judged: no wheel speed v (the speed stage compares it with the GPS track)"
        return tuple(stages), why

    def predicted(self, stage: str, v: dict[str, float]) -> np.ndarray:
        """The stage's simulated signal on every sample (position: the dead-reckoned track)."""
        return self.predicted_many(stage, [v])[0]

    def predicted_many(self, stage: str, sets: list[dict[str, float]]) -> list[np.ndarray]:
        """``predicted`` under each of several value sets; the yaw stage replays them side by side
        (saturating tyres: one batched simulation; linear: one blocked recursion), so a Jacobian's
        stepped sets cost less than as many replays."""
        if stage == "steering":
            return [mapped_steering(self.cmd, self.h, v, self.delta[0], self.kernel) for v in sets]  # through the map
        if stage == "yaw":
            inputs = [self.yaw_input(v) for v in sets]
            saturated = [i for i, v in enumerate(sets) if saturates(v)]
            rates = dict(zip(saturated, self.saturated_yaw_rates([sets[i] for i in saturated],
                                                                 [inputs[i] for i in saturated])))
            linear = [i for i in range(len(sets)) if i not in rates]
            self.yaw.prepare([sets[i] for i in linear], [inputs[i] for i in linear])
            return [measured_yaw_rate(rates[i] if i in rates else self.yaw.yaw_rate(v, inputs[i]), v, self.h)
                    for i, v in enumerate(sets)]
        out = []
        for track in self.tracks(sets):
            if stage == "speed":
                k = self.chord_k
                speed = np.full(len(self.t), np.nan)
                d = track[2 * k:] - track[:-2 * k]
                speed[k:-k] = np.hypot(d[:, 0], d[:, 1]) / self.chord_span
                track = speed
            out.append(track)
        return out

    def tracks(self, sets: list[dict[str, float]]) -> list[np.ndarray]:
        """The dead-reckoned antenna track under each set; the last batch's are kept (exact keys), so
        the speed stage reads the tracks the position stage of the same sets replayed."""
        last = self.__dict__.get("_last_tracks", {})
        keys = [tuple(sorted(v.items())) for v in sets]
        todo = [(v, key) for v, key in zip(sets, keys) if key not in last]
        inputs = [self.yaw_input(v) for v, _ in todo] if "yaw" in self.stages else [None] * len(todo)
        if "yaw" in self.stages and any(d is not None for d in inputs):
            self.yaw.prepare([v for v, _ in todo], inputs)    # the side-slips of the sets' wheel angles at once
        fresh = {key: antenna_track(self.t, self.gyro, self.speed, v, self.lateral(v, delta))
                 for (v, key), delta in zip(todo, inputs)}
        self._last_tracks = {key: fresh[key] if key in fresh else last[key] for key in keys}
        return [self._last_tracks[key] for key in keys]

    def yaw_input(self, v: dict[str, float]) -> np.ndarray | None:
        """The wheel angle driving the yaw stage under ``v``: None for the measured one as it is,
        else the angle replayed from the command or the reading, through the effects' transforms of
        the steering (replay.wheel_angle_input)."""
        return wheel_angle_input(self.delta, self.replayed_steering(v) if self.command_only else None, self.t, v)

    def replayed_steering(self, v: dict[str, float]) -> np.ndarray:
        """The wheel angle replayed from delta_cmd under ``v`` (memoised on the steering's values:
        a fit of the yaw stage's other parameters replays it once)."""
        key = exact(steering_plant(v).values())
        cache = self.__dict__.setdefault("_steering_cache", {})
        if key not in cache:
            if len(cache) > 32:
                cache.clear()
            cache[key] = steering_replay(self.cmd, self.h, v, float(self.cmd[0]), self.kernel)
        return cache[key]

    def saturated_yaw_rates(self, sets: list[dict[str, float]], inputs: list[np.ndarray | None]) -> list[np.ndarray]:
        """The yaw stage with Magic Formula tyres (SaturatedYawReplay) under each set, driven by its
        wheel angle (None: the measured one), all in one batched simulation, plus the linear model's
        response to a side slope."""
        if not sets:
            return []
        inputs = [self.delta if d is None else d for d in inputs]
        if getattr(self, "_saturated", None) is None:
            self._saturated = SaturatedYawReplay(self.baseline.yaw_model, self.baseline.tractor, self.t, self.h,
                                                 inputs[0], self.speed, self.min_speed,
                                                 geometry=self.baseline.steering_geometry)
        out = self._saturated.yaw_rates(sets, inputs)
        return [self.yaw.with_slope(rate, v) for rate, v in zip(out, sets)]

    def lateral(self, v: dict[str, float], delta: np.ndarray | None = None) -> np.ndarray | None:
        """The rear axle's lateral velocity (side-slip) from the yaw model under ``v``, where the
        yaw stage is replayed (nothing for a tractor at 2 m/s; metres over 10 s for a car at 30 m/s),
        driven by the wheel angle that drives the yaw stage (``delta``: yaw_input(v), given when
        known; through the steering map, so a gain error slips the rear axle as it turns the car).
        With a wheel angle quantised coarser than COARSE_DELTA the refitted stiffnesses carry the
        input's errors (a 1-deg potentiometer halves the rear one): the study's own values then."""
        if "yaw" not in self.stages:
            return None
        delta = self.yaw_input(v) if delta is None else delta
        if self.coarse_delta:
            v = {**v, **{k: self.baseline.values[k] for k in ("cornering_front_scale", "cornering_rear_scale",
                                                             "relaxation_scale")}}
        return self.yaw.rear_lateral_velocity(v, delta)

    def side_slip_arm(self) -> float:
        """The rear axle's steady side-slip velocity per unit yaw rate at the log's 95th-percentile
        speed, m l_f v^2 / (L C_r) [m] (the rear tyres carry m a_y l_f / L at a slip angle u_R / v):
        the same track as a point that far from the axle. 0.05 m for the paper tractor at 3 m/s,
        6 m for a car at 30 m/s."""
        p = self.baseline.tractor
        moving = self.speed[np.isfinite(self.speed) & (self.speed > self.min_speed)]
        v = float(np.percentile(moving, 95)) if len(moving) else 0.0
        return p.m * p.l_f * v * v / ((p.l_f + p.l_r) * p.C_r)

    def _track_reads_side_slip(self) -> bool:
        """The yaw stage is replayed and a track stage (position, speed) reads its side-slip."""
        return "yaw" in self.stages and bool({"position", "speed"} & set(self.stages))

    @cached_property
    def side_slip_block(self) -> tuple[str, ...]:
        """The stages fitted and scored as one block because the track reads the yaw model's
        side-slip (lateral): yaw, position and speed, when SIDE_SLIP_LOOSENESS of the side-slip
        arm reaches the smallest material lever arm (SIDE_SLIP_ARM); otherwise (a tractor at
        field speeds, no yaw stage, a coarse wheel angle whose side-slip takes the study's own
        stiffnesses) empty. The yaw rate fixes the understeer gradient m/L (l_r/C_f - l_f/C_r)
        and the yaw mode but leaves C_r loose by a tenth, which at 30 m/s is a side-slip error of
        0.6 m x the yaw rate: a forward antenna point would soak it up."""
        if not self._track_reads_side_slip() or self.coarse_delta:
            return ()
        if SIDE_SLIP_LOOSENESS * self.side_slip_arm() < SIDE_SLIP_ARM:
            return ()
        return tuple(s for s in STAGES if s in ("yaw", "position", "speed") and s in self.stages)

    def side_slip_note(self) -> str:
        """The block choice in words (the selection's trace)."""
        arm = self.side_slip_arm()
        joined = bool(self.side_slip_block)
        if not self._track_reads_side_slip():
            return ""
        why = (f"the rear axle's side-slip at the log's 95th-percentile speed is that of a point {arm:.2f} m "
               f"from it; {100 * SIDE_SLIP_LOOSENESS:.0f} % of it, what the yaw rate leaves C_r loose by, is "
               f"{SIDE_SLIP_LOOSENESS * arm:.2f} m {'>=' if joined else '<'} {SIDE_SLIP_ARM:g} m (the smallest "
               f"material lever arm)")
        if self.coarse_delta:
            return f"side-slip: the study's own stiffnesses (a coarse wheel angle); {why}"
        if joined:
            return (f"side-slip: the cornering stiffnesses fitted on the yaw rate and the track together, each fit "
                    f"of these stages weighed by its own residual levels: {why}")
        return f"side-slip: the cornering stiffnesses fitted on the yaw rate alone: {why}"

    def measured(self, stage: str) -> np.ndarray:
        return {"steering": self.delta, "yaw": self.gyro, "position": self.gps, "speed": self.track_speed}[stage]

    def residuals(self, stage: str, v: dict[str, float], *parts: str) -> np.ndarray | tuple[np.ndarray, ...]:
        """The stage's residuals on each named part ("fit", "test"), from one simulation; one
        part gives an array, several a tuple."""
        return self.residuals_many(stage, [v], *parts)[0]

    def residuals_many(self, stage: str, sets: list[dict[str, float]], *parts: str) -> list:
        """``residuals`` under each of several value sets (predicted_many: batched where the stage
        simulates)."""
        out = []
        for pred in self.predicted_many(stage, sets):
            pred = self.seen(stage, pred)
            if stage == "position":
                res = tuple(self.track_residuals(pred, self.windows[p]) for p in parts)
            else:
                r = self.measured(stage) - pred
                res = tuple(r[self.masks[stage][p]] for p in parts)
            out.append(res[0] if len(parts) == 1 else res)
        return out

    def track_residuals(self, predicted: np.ndarray, rows: np.ndarray, measured: np.ndarray | None = None) -> np.ndarray:
        """The position stage's residual on the windows ``rows`` (W, L): each window's aligned
        residual (measured: the GPS track) through its generalised-least-squares transform
        (replay.TrackWhitening, at the log's sensor levels ``track_noise``), ordered by time within
        each window's east, then north, series (replay.track_residual_vector)."""
        res = aligned_residuals(predicted, self.gps if measured is None else measured, rows)
        if not len(rows):
            return track_residual_vector(res)
        cache = self.__dict__.setdefault("_whitenings", {})
        for row in rows:
            if int(row[0]) not in cache:
                cache[int(row[0])] = TrackWhitening(self.gps[row], self.h, *self.track_noise)
        return np.concatenate([cache[int(row[0])](track_residual_vector(r[None])) for row, r in zip(rows, res)])

    @cached_property
    def track_noise(self) -> tuple[float, float, float]:
        """(sigma_gps, sigma_gyro, sigma_speed) per row, the white levels the dead-reckoned track's
        residual carries (noise_floor.track_level, on each sensor's own samples; an integrated
        channel held m rows adds m x the variance per row to its random walk): the GPS's from the
        aligned residual of the study's track, the gyro's from the yaw stage's residual under the
        study's values (or the gyro itself without a yaw stage; none for a yaw rate derived from a
        heading, whose integral is that heading), the speed's from the speed itself."""
        v = self.baseline.values
        rows = np.concatenate([self.windows["fit"], self.windows["test"]])
        track = antenna_track(self.t, self.gyro, self.speed, v, self.lateral(v))     # the fits' tracks kept (tracks)
        res, on = aligned_residuals(track, self.gps, rows), track_samplings(self)
        sigma_gps = track_level(self, np.concatenate([res[..., 0], res[..., 1]]), np.concatenate([self.t[rows]] * 2),
                                on["gps"], integrated=False)
        derived = self.frame.attrs.get("yaw_measurement")
        sigma_gyro = 0.0
        if derived is None or derived.kind == "gyro":
            sigma_gyro = track_level(self, self.gyro - self.predicted("yaw", v) if "yaw" in self.stages else self.gyro,
                                     self.t, on["yaw_rate"], integrated=True)
        return sigma_gps, sigma_gyro, track_level(self, self.speed, self.t, on["v"], integrated=True)

    def scored(self, stage: str) -> np.ndarray:
        """Samples of a time-series stage scored in either part (for plots and evidence)."""
        return self.masks[stage]["fit"] | self.masks[stage]["test"]

    def residual_series(self, stage: str, v: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
        """(t, residual) over both parts, for the plots; position: the along-window norm."""
        if stage == "position":
            rows = np.concatenate([self.windows["fit"], self.windows["test"]])
            r = aligned_residuals(self.predicted(stage, v), self.gps, rows)
            return self.t[rows].ravel(), np.hypot(r[..., 0], r[..., 1]).ravel()
        keep = self.scored(stage)
        return self.t[keep], (self.measured(stage) - self.seen(stage, self.predicted(stage, v)))[keep]

    def seen(self, stage: str, pred: np.ndarray) -> np.ndarray:
        """A stage's prediction as its measurement sees it: a yaw rate derived from a heading or a
        course averages the true one (identification.yaw_measurement's kernel), a gyro interpolated
        from its own samples reads the yaw rate at them (own_samples.reading): the model's alike."""
        if stage == "yaw" and self.yaw_sampling is not None:
            return self.yaw_sampling @ pred
        if stage != "yaw" or self.yaw_kernel is None:
            return pred
        return convolve1d(pred, self.yaw_kernel[::-1], mode="nearest")


def _named(need: str, columns) -> str:
    """A missing need in words, with the log's column that looks like it (YawRate for yaw_rate)."""
    text = NEED_TEXT.get(need, need)
    near = similar_columns(columns, need) if need in ("delta", "delta_cmd", "yaw_rate", "v", "x", "y") else []
    return text + (f" (the log has {', '.join(near)}: rename it to {need} if it is that, in SI units)" if near else "")


def refit_free(replay: "Replay", stages, effects, joining=()) -> list[Parameter]:
    """The parameters a fit of ``effects`` on ``stages`` frees: the stages' uncertain ones but the
    cornering scales such a fit holds (class_held: ``joining``, effects whose own parameters are
    freed beside these, count for that), then the effects', each once (selection._refit fits them,
    screen.Screen linearises the same set)."""
    held = class_held(replay, list(effects) + list(joining))
    return list(dict.fromkeys([p for s in stages for p in uncertain(replay, s) if p.name not in held] +
                              [p for e in effects for p in e.parameters]))


def class_held(replay: "Replay", effects) -> dict[str, float]:
    """{name: the study's value} of the cornering scales a refit of ``effects`` holds: when the
    baseline refit held one because freed it gave the vehicle an understeer gradient
    K = m/L (l_r / (s_f C_f) - l_f / (s_r C_r)) its class does not have (baseline.implausible_tyres),
    every cornering scale it held (the other, left unpinned, reaches the same K from its axle),
    unless one of ``effects`` is what such a gradient reads (frees_scales): with it in the model the
    scales are the vehicle's again. Freed beside any other effect, they take up a steering map's
    gain as a yaw gain v / (L + K v^2), and every candidate (a clock shift, a gyro bias) scores the
    tyres' dBIC, not its own."""
    selection = replay.__dict__.get("held_in_selection", {})
    held = {k: why for k, why in getattr(replay, "held_uncertain", {}).items()
            if k in CORNERING_SCALES and k not in selection}
    if not any(why.kind == IMPLAUSIBLE for why in held.values()) or any(frees_scales(e) for e in effects):
        return {}
    return {k: replay.baseline.values[k] for k in held}


def uncertain(replay: "Replay", stage: str) -> tuple[Parameter, ...]:
    """The baseline parameters refitted with a stage: the yaw stage of a command-only log also
    carries the steering's time constant."""
    extra = UNCERTAIN["steering"] if stage == "yaw" and getattr(replay, "command_only", False) else ()
    wider = getattr(replay, "widened_uncertain", {})       # ranges fit_baseline widened to their limits
    held = replay.__dict__.get("held_in_selection", getattr(replay, "held_uncertain", ()))    # and those it holds
    return tuple(wider.get(p.name, p) for p in tuple(UNCERTAIN[stage]) + tuple(extra) if p.name not in held)


def frees_scales(effect) -> bool:
    """Whether ``effect`` is what an implausible understeer gradient reads (plausibility.understeer):
    tyres past their linear range (Effect.on_tyres: saturation, a stiffness changing with speed) or a
    steering map off in gain, shape or symmetry (tested on the actuator's stage, Effect.tested_on),
    so that its refit frees the cornering scales class_held holds for the others."""
    return effect.on_tyres() or "steering" in effect.tested_on


def class_held_note(replay: "Replay") -> str | None:
    """The trace's line for class_held: the scales held in the candidates' refits, what is passed
    over (their stiffness freed) and the effects that still free them; None when none is held."""
    held = class_held(replay, [])
    if not held:
        return None
    return (f"cornering scales held at the study's in the refits of effects that do not act on the tyres: "
            f"{', '.join(held)} (the baseline refit held them, freed they give a gradient the class does not "
            f"have); tyre effects and steering maps (gain, ratio curve, asymmetry) free them")


class Speculated(Exception):
    """A fit asked for while its arguments are being collected (diagnosis.parallel_fits), to stop
    the caller at its first fit."""


def fit_key(base_values: dict[str, float], free: list[Parameter], stages: tuple[str, ...],
            starts: list[dict[str, float]], sigma: dict[str, float]) -> tuple:
    """Everything a fit's result depends on besides the replay, exact: two fits of one key are the
    same fit (the replays are pure functions of the values)."""
    return (tuple(sorted(base_values.items())), tuple(free), tuple(stages),
            tuple(tuple(sorted(s.items())) for s in starts), tuple(sorted(sigma.items())))


def _fit(replay: Replay, base_values: dict[str, float], free: list[Parameter], stages: tuple[str, ...],
         starts: list[dict[str, float]], sigma: dict[str, float]) -> FitResult:
    """``fitted``, unless the same fit was computed ahead (``replay.fits_ahead``, by worker processes:
    diagnosis.parallel_fits); while the fits ahead are being collected (``replay.collecting``), the
    fit is noted and a stand-in returned (or Speculated raised)."""
    args = (base_values, list(free), tuple(stages), starts, sigma)
    collecting = replay.__dict__.get("collecting")
    if collecting is not None:
        collecting.append(args)
        if replay.__dict__.get("collect_first"):
            raise Speculated
        k = len(free)
        return FitResult(dict(base_values), tuple(free), np.full((k, k), np.nan), {s: 1.0 for s in stages},
                         {s: 1 for s in stages}, {s: 1.0 for s in stages}, {s: 1.0 for s in stages})
    ahead = replay.__dict__.get("fits_ahead")
    if ahead:
        hit = ahead.pop(fit_key(*args), None)
        if hit is not None:
            return hit
    return fitted(replay, *args)


def fitted(replay: Replay, base_values: dict[str, float], free: list[Parameter], stages: tuple[str, ...],
           starts: list[dict[str, float]], sigma: dict[str, float]) -> FitResult:
    """Least squares over ``free`` (scaled by each parameter's typical size) from each start
    (diagnosis.weighted_search: a search again at new levels starts from the last one's residuals); a
    fit computed before on the replay is recalled (diagnosis.fit_memo)."""
    key = fit_key(base_values, free, stages, starts, sigma)
    known = recalled(replay, key)
    if known is not None:
        return known
    def values_of(x: np.ndarray) -> dict[str, float]:
        v = dict(base_values)
        for p, xi in zip(free, x):
            v[p.name] = float(xi) * p.scale
        return v

    best = None
    if free:
        lo = np.array([p.lower / p.scale for p in free])
        hi = np.array([p.upper / p.scale for p in free])
        search = WeightedSearch(replay, stages, values_of, lo, hi)
        for start in starts:
            x0 = np.clip([start.get(p.name, base_values[p.name]) / p.scale for p in free], lo + 1e-9, hi - 1e-9)
            sol = search.search(x0, sigma)
            if best is None or sol.cost < best.cost:
                best = sol
        block = getattr(replay, "side_slip_block", ())
        if len(block) > 1 and set(block) <= set(stages):
            # the block's stages weighed by their own levels, sigma_s^2 = RSS_s / n_eff,s (iterated): the
            # stationary point of the score's sum_s n_eff,s ln RSS_s. The baseline's levels would weigh a
            # track misfit by an unmodelled effect (a latency: 20x the noise) 400x too little against the
            # yaw rate, leaving the side-slip where the yaw rate alone puts it
            sigma = dict(sigma)
            for _ in range(REWEIGHTS):
                level = {s: math.sqrt(float(r @ r) / max(effective_size(r, updates=replay.updates(s)), 1.0)) or sigma[s]
                         for s, r in search.by_stage(best).items()}
                if all(abs(level[s] / sigma[s] - 1.0) < 0.02 for s in stages):
                    break
                sigma.update(level)
                best = search.search(best.x, sigma, after=best)
        values = values_of(best.x)
    else:
        values = dict(base_values)
    rss, n, n_eff, rmse = {}, {}, {}, {}
    for s in stages:
        r, rt = replay.residuals(s, values, "fit", "test")
        rss[s], n[s], n_eff[s] = float(r @ r), len(r), effective_size(r, updates=replay.updates(s))
        rmse[s] = float(np.sqrt(np.mean(rt ** 2)))
    cov = np.zeros((0, 0))
    if best is not None:          # one on its bound held there
        cov = solution_covariance(best.jac, best.cost, best.x, free, sum(n.values()), sum(n_eff.values()))
    return remembered(replay, key, FitResult(values, tuple(free), cov, rss, n, n_eff, rmse))


def fit_baseline(replay: Replay) -> tuple[FitResult, dict[str, float]]:
    """Re-fit each stage's uncertain parameters (no extension); returns the fit and the per-stage
    noise levels used to normalise later fits. Where the track reads the yaw model's side-slip
    (Replay.side_slip_block) the yaw stage's parameters are then refitted on the whole block
    (each stage weighed by its own residual level, _fit), and the levels taken again from that
    fit: the yaw rate fixes the understeer gradient
    m/L (l_r/C_f - l_f/C_r) and the yaw mode but hardly C_r, which sets the rear axle's side-slip
    m l_f a_y / (L C_r) that the track sees. A parameter the log does not pin (baseline.unpinned: its
    95 % interval from the stage's refit wider than half its value, or none), and cornering scales
    that would give the vehicle an understeer gradient its class does not have
    (baseline.implausible_tyres), are held at the study's and listed with why in
    ``replay.held_uncertain``; the selection's refits, where an effect can pin them, free them again
    (``replay.held_in_selection``: only the kinematic regime's)."""
    values = dict(replay.baseline.values)
    sigma = {s: 1.0 for s in replay.stages}
    kinematic_held = held_tyres(replay)
    replay.widened_uncertain, replay.held_uncertain = {}, dict(kinematic_held)
    replay.__dict__.pop("held_in_selection", None)
    for s in replay.stages:
        start = values
        fit = _fit(replay, start, list(uncertain(replay, s)), (s,), [{}], sigma)
        wider = widened_ranges(uncertain(replay, s), fit.values)
        if wider:                   # a value on a prior edge is no estimate: searched again out to the limit
            replay.widened_uncertain.update(wider)
            fit = _fit(replay, fit.values, list(uncertain(replay, s)), (s,), [{}], sigma)
        values = _held_where_loose(replay, fit, start, s, sigma).values
    block = replay.side_slip_block
    for joint in ((False, True) if block else (False,)):
        if joint:                   # on a prior edge here too: searched again out to the limit
            free = list(dict.fromkeys(p for s in block for p in uncertain(replay, s)))
            values = _fit(replay, values, free, block, [{}], sigma).values
            if wider := widened_ranges(free, values):
                replay.widened_uncertain.update(wider)
                values = _fit(replay, values, [wider.get(p.name, p) for p in free], block, [{}], sigma).values
        fit = _fit(replay, values, [], replay.stages, [{}], sigma)
        for s in replay.stages:
            sigma[s] = math.sqrt(fit.rss[s] / fit.n[s]) or 1.0
    # the selection frees again what only this refit held: an effect in the model can pin it
    replay.held_in_selection = kinematic_held
    return fit, sigma


def _held_where_loose(replay: Replay, fit: FitResult, start: dict[str, float], stage: str,
                      sigma: dict[str, float]) -> FitResult:
    """``fit`` (a stage's baseline refit) with what the log does not pin (baseline.unpinned) and
    cornering scales its class does not have (baseline.implausible_tyres) put back to ``start`` (the
    study's) and held there, the others refitted, until none is left."""
    while fit.free:
        loose = unpinned(fit)
        loose |= implausible_tyres(replay, {**fit.values, **{k: start[k] for k in loose}},
                                   {p.name for p in fit.free} - set(loose))
        if not loose:
            break
        replay.held_uncertain = {**replay.held_uncertain, **loose}
        fit = _fit(replay, {**fit.values, **{k: start[k] for k in loose}}, list(uncertain(replay, stage)), (stage,),
                   [{}], sigma)
    return fit


def merged(model: FitResult, part: FitResult, reset: dict[str, float] | None = None) -> FitResult:
    """``model`` with the stages that ``part`` scored, and the parameters it moved, taken from
    ``part`` (``reset``: further values, those of an effect that leaves the model): FitResult.merged."""
    return model.merged(part, reset)
