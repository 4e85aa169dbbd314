"""RTK-GPS sensor (paper section II): antenna position and velocity, 2 cm noise at 20 Hz, and the
fix quality a receiver reports in NMEA GGA (4 RTK fixed, 5 RTK float, 2 DGPS, 1 single, 0 none).

Error model: white noise (``position_noise_std``, the default worst case) plus, as an option, a
correlated RTK error per axis, first-order Gauss-Markov (``bias_std``, ``bias_time_constant``):
b_k+1 = exp(-dt/T) b_k + sqrt(1 - exp(-2 dt/T)) sigma_b w_k.

Output at sample k is the true antenna state of sample k - latency/dt plus white Gaussian noise.
Dropouts: a two-state chain; each sample starts an outage with probability
``dropout_probability``, an outage lasts ``dropout_duration`` seconds; during it the last fix is
held, ``fix_valid`` = 0, ``fix_quality`` = 0 (no fix) and ``fix_age`` grows.

Quality drops, as a receiver has them when it loses its corrections or its sky:
``outages = [[start_s, end_s], ...]`` (no fix) or ``[[start_s, end_s, quality], ...]`` (that GGA
quality over the window), and ``quality_log``, a recorded NMEA log whose GGA qualities the receiver
replays (from ``quality_log_start`` on, by the time since the log's first GGA; a pause of more than
a second in its GGAs is no fix; after its last GGA the receiver is back to RTK fixed). A degraded
fix (quality 1, 2, 5) carries, besides the white noise, an error per axis of that quality's std
(models.sensor_grades.FIX_ERROR_STD) that wanders as a Gauss-Markov process of
``degraded_error_time_constant``; a quality of 0, 6, 7 or 8 carries no position (``fix_valid`` 0).

A window's third item may name the mode instead: ``"none"`` (0), ``"float"`` (5), ``"dgps"`` (2),
``"single"`` (1) or ``"bridging"``: the receiver keeps its satellites and bridges the lost RTK
corrections with satellite-delivered ones (Trimble xFill, NovAtel RTK ASSIST), reporting the RTK
quality it had (4) for up to ``bridging_timeout`` and DGPS (2) after it. Its error grows with the
correction age a as the vendors document it, horizontal RMS

    sigma_h(a) = bridging_error_start + bridging_error_rate a

(the defaults, 0.81 cm + 0.758 cm/min, are the least-squares line through the Trimble TMX-2050 manual's
xFill table: 1-5 cm after 1-5 min, 5-9 cm after 6-10 min, 10-15 cm after 11-20 min), each axis
sigma_h(a) / sqrt(2) times a unit Gauss-Markov wander of ``bridging_time_constant`` (the bridged
solution drifts slowly, it is not white). ``correction_age`` is a (0 with live corrections).

Imported where used: pynmeagps (the hardware extra).
"""
from __future__ import annotations

import math
from collections import deque
from pathlib import Path

import numpy as np

from agrobot.orchestrator.compiled.cores import CoreDescription, capacity
from agrobot.orchestrator.component import Component, inp, out, par
from agrobot.orchestrator.units import FILE_UNIT

from .hardware.nmea import FIX_RANK, RTK_FIXED
from .models.c_sources import delay_steps
from .models.sensor_grades import DEGRADED_ERROR_TIME_CONSTANT, FIX_ERROR_STD, gauss_markov_step
from .models.loop_blocks import Block, Ground, LEVEL, delay_line

GGA_QUALITIES = tuple(range(10))
BRIDGING = -1                                  # the bridging mode's code in a window (not a GGA quality)
MODES = {"none": 0, "float": 5, "dgps": 2, "single": 1, "bridging": BRIDGING}
BRIDGED_QUALITY, AFTER_BRIDGING = RTK_FIXED, 2  # reported while bridging, and after its timeout
XFILL_START, XFILL_RATE = 0.0081, 0.00758 / 60.0  # m, m/s: horizontal RMS of the bridged fix (fitted, see above)


def bridging_error(age, start: float = XFILL_START, rate: float = XFILL_RATE):
    """sigma_h(a) [m]: the horizontal RMS error of a bridged fix a seconds after the corrections were lost."""
    return start + rate * np.asarray(age, float)


def gga_qualities(path: str) -> tuple[np.ndarray, np.ndarray]:
    """(time since the first GGA [s], quality) of every GGA of an NMEA log (bad sentences skipped;
    time of day wrapping past midnight continues)."""
    from pynmeagps import VALCKSUM, NMEAReader

    times, qualities = [], []
    try:
        lines = open(path, "rb").read().splitlines()
    except OSError as exc:
        raise ValueError(f"cannot read {path}: {exc.strerror or exc}") from None
    day = 0.0
    for line in lines:
        start = line.find(b"$")
        if start < 0 or line[start + 3:start + 6] != b"GGA":
            continue
        try:
            msg = NMEAReader.parse(line[start:].strip() + b"\r\n", validate=VALCKSUM)
            clock = msg.time
            q = int(msg.quality) if msg.quality != "" else 0
            t = clock.hour * 3600.0 + clock.minute * 60.0 + clock.second + clock.microsecond * 1e-6
        except Exception:                           # noqa: BLE001 - a bad sentence is skipped, as a receiver's would be
            continue
        if times and t + day < times[-1] - 43200.0:  # past midnight
            day += 86400.0
        times.append(t + day)
        qualities.append(q if q in GGA_QUALITIES else 0)
    if not times:
        raise ValueError(f"{path}: no GGA sentence with a time and a quality")
    t = np.asarray(times)
    return t - t[0], np.asarray(qualities, int)


def _gps_compiled(comp, period: float) -> str:
    lag = delay_steps(comp.p["latency"], period)
    return f"#define LAG {lag}\n#define LATENCY {float(comp.p['latency'])!r}\n"


def _gps_runtime(comp, period: float) -> tuple[str, dict[str, float]]:
    lag = delay_steps(comp.p["latency"], period)
    return (f"#define LAG_CAPACITY {capacity(lag)}\n#define LAG ((int)p[P__lag])\n#define LATENCY (p[P__latency])\n",
            {"_lag": float(lag), "_latency": float(comp.p["latency"])})


def _gps_seed(comp, name: str) -> dict[str, float]:
    return {"seed": float(int(comp.rng.integers(0, 2**52)))}


# what the C core leaves out: its receiver has an RTK fix or random dropouts (no outage windows, no
# quality log, no degraded fixes or bridged corrections)
NOT_IN_C_CORE = ("outages", "quality_log", "quality_log_start", "rtk_float_error_std", "dgps_error_std",
                 "single_error_std", "degraded_error_time_constant", "bridging_error_start", "bridging_error_rate",
                 "bridging_timeout", "bridging_time_constant")


class GPSSensor(Component):
    sampled = True
    roles = ("gps",)
    c_core = CoreDescription(Path(__file__).with_suffix(".c"), _gps_compiled, ("latency",), NOT_IN_C_CORE,
                             extra_parameters=(("seed", 0.0, "1", "seed of the noise generator (xoshiro256**)"),),
                             extra_values=_gps_seed, runtime=_gps_runtime)      # its C model core, beside this file
    variables = (
        inp("x_true", "m", 0.0, "true antenna east position"),
        inp("y_true", "m", 0.0, "true antenna north position"),
        inp("vel_east_true", "m/s", 0.0, "true antenna east velocity"),
        inp("vel_north_true", "m/s", 0.0, "true antenna north velocity"),
        par("position_noise_std", "m", 0.02, "position noise (1 sigma, per axis)"),
        par("velocity_noise_std", "m/s", 0.02, "velocity noise (1 sigma, per axis)"),
        par("latency", "s", 0.0, "measurement delay, a multiple of the sensor step"),
        par("dropout_probability", "1", 0.0, "probability per sample that an outage starts"),
        par("dropout_duration", "s", 1.0, "length of an outage"),
        par("bias_std", "m", 0.0, "correlated RTK error: stationary std per axis of a Gauss-Markov bias (0: off)"),
        par("bias_time_constant", "s", 60.0, "correlated RTK error: correlation time of the bias"),
        par("outages", "", [], "windows [[start_s, end_s], ...] without a fix, or [[start_s, end_s, quality], ...] "
            "with that GGA quality"),
        par("quality_log", FILE_UNIT, "", "an NMEA log whose GGA qualities the receiver replays (empty: none)"),
        par("quality_log_start", "s", 0.0, "run time at which the log's first GGA plays"),
        par("rtk_float_error_std", "m", FIX_ERROR_STD[5], "error of an RTK float fix (quality 5), per axis"),
        par("dgps_error_std", "m", FIX_ERROR_STD[2], "error of a DGPS fix (qualities 2, 3, 9), per axis"),
        par("single_error_std", "m", FIX_ERROR_STD[1], "error of a single-point fix (quality 1), per axis"),
        par("degraded_error_time_constant", "s", DEGRADED_ERROR_TIME_CONSTANT, "correlation time of those errors"),
        par("bridging_error_start", "m", XFILL_START, "bridging: horizontal RMS error when the corrections are lost"),
        par("bridging_error_rate", "m/s", XFILL_RATE, "bridging: its growth with the correction age"),
        par("bridging_timeout", "s", 1200.0, "bridging: how long the receiver bridges (then DGPS)"),
        par("bridging_time_constant", "s", 300.0, "bridging: correlation time of its error's wander"),
        out("x", "m", 0.0, "measured east position"),
        out("y", "m", 0.0, "measured north position"),
        out("vel_east", "m/s", 0.0, "measured east velocity"),
        out("vel_north", "m/s", 0.0, "measured north velocity"),
        out("fix_valid", "1", 1.0, "1 when this sample carries a new fix, else 0"),
        out("fix_age", "s", 0.0, "time since the last valid fix"),
        out("fix_quality", "1", float(RTK_FIXED), "GGA fix quality: 4 (RTK fixed) with a fix, 0 in an outage"),
        out("correction_age", "s", 0.0, "age of the RTK corrections the fix uses (GGA's age of differential data): "
            "0 with live corrections, the time since they were lost while bridging"),
    )
    feedthrough = {k: ("x_true", "y_true", "vel_east_true", "vel_north_true")
                   for k in ("x", "y", "vel_east", "vel_north")}

    def initialize(self, t0: float, dt: float) -> None:
        p = self.p
        lag = p["latency"] / dt
        self.require(p["latency"] >= 0 and math.isclose(lag, round(lag), abs_tol=1e-9),
                     f"latency {p['latency']} s must be a non-negative multiple of the step {dt} s")
        self.require(0 <= p["dropout_probability"] <= 1, "dropout_probability must be in [0, 1]")
        self.lag = delay_steps(p["latency"], dt)
        self.history: deque = deque(maxlen=self.lag + 1)
        self.outage_left = 0
        self.last_fix_time = t0
        self.require(p["bias_std"] >= 0 and p["bias_time_constant"] > 0,
                     "bias_std must be >= 0 and bias_time_constant > 0")
        # b_k+1 = phi b_k + sqrt(1 - phi^2) sigma_b w_k, phi = exp(-dt / T): stationary std sigma_b
        self.bias_phi = math.exp(-dt / p["bias_time_constant"])
        self.bias = (self.rng.standard_normal(2) * p["bias_std"]).tolist() if p["bias_std"] > 0 else (0.0, 0.0)
        self.windows = self._windows(p["outages"])
        self.log = None
        if p["quality_log"]:
            try:
                times, qualities = gga_qualities(str(p["quality_log"]))
            except ValueError as exc:
                self.require(False, f"parameter quality_log: {exc}")
            steps = np.diff(times)
            gap = max(1.0, 5.0 * float(np.median(steps))) if len(steps) else 1.0
            self.log = (times + float(p["quality_log_start"]), qualities, gap)
        for key in ("rtk_float_error_std", "dgps_error_std", "single_error_std"):
            self.require(p[key] >= 0, f"parameter {key} must be >= 0, got {p[key]}")
        self.require(p["degraded_error_time_constant"] > 0, "parameter degraded_error_time_constant must be > 0")
        self.error_std = {5: p["rtk_float_error_std"], 2: p["dgps_error_std"], 3: p["dgps_error_std"],
                          9: p["dgps_error_std"], 1: p["single_error_std"]}
        self.degraded_phi = math.exp(-dt / p["degraded_error_time_constant"])
        self.degraded = any(q not in (0, RTK_FIXED) for _, _, q in self.windows) or self.log is not None
        self.wander = self.rng.standard_normal(2).tolist() if self.degraded else [0.0, 0.0]    # unit-std Gauss-Markov
        for key in ("bridging_error_start", "bridging_error_rate", "bridging_timeout"):
            self.require(p[key] >= 0, f"parameter {key} must be >= 0, got {p[key]}")
        self.require(p["bridging_time_constant"] > 0, "parameter bridging_time_constant must be > 0")
        self.bridging = any(q == BRIDGING for _, _, q in self.windows)
        self.bridging_phi = math.exp(-dt / p["bridging_time_constant"])
        self.bridge_wander = self.rng.standard_normal(2).tolist() if self.bridging else [0.0, 0.0]

    def _windows(self, value) -> list[tuple[float, float, int]]:
        """The outage windows, checked: each [start_s, end_s] or [start_s, end_s, quality]."""
        where = "parameter outages"
        self.require(isinstance(value, (list, tuple)), f"{where} = {value!r}: expected a list of [start_s, end_s] "
                     "or [start_s, end_s, quality]")
        windows = []
        for i, item in enumerate(value):
            ok = isinstance(item, (list, tuple)) and len(item) in (2, 3) and all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in item[:2]) and (
                len(item) == 2 or isinstance(item[2], str) or (isinstance(item[2], (int, float))
                                                               and not isinstance(item[2], bool) and math.isfinite(item[2])))
            self.require(ok, f"{where}, item {i} = {item!r}: expected [start_s, end_s] or [start_s, end_s, quality] "
                         "(finite numbers)")
            start, end = float(item[0]), float(item[1])
            quality = item[2] if len(item) == 3 else 0
            self.require(start < end, f"{where}, item {i} = {item!r}: the window must end after it starts")
            if isinstance(quality, str):
                self.require(quality in MODES, f"{where}, item {i} = {item!r}: outage mode {quality!r} does not exist; "
                             f"expected {', '.join(MODES)} or a GGA fix quality (0 to 9)")
                quality = MODES[quality]
            else:
                self.require(quality in GGA_QUALITIES and quality == int(quality),
                             f"{where}, item {i} = {item!r}: quality {quality!r} is not a GGA fix quality (0 to 9) "
                             f"nor an outage mode ({', '.join(MODES)})")
            windows.append((start, end, int(quality)))
        return windows

    def bridged_since(self, t: float) -> float | None:
        """The start of the bridging window holding t (None: not bridging at t)."""
        start_of = None
        for start, end, q in self.windows:
            if start - 1e-9 <= t < end - 1e-9:
                start_of = start if q == BRIDGING else None
        return start_of

    def quality_at(self, t: float) -> int:
        """The GGA quality the receiver has at time t (before random dropouts)."""
        quality = RTK_FIXED
        if self.log is not None:
            times, qualities, gap = self.log
            i = int(np.searchsorted(times, t + 1e-9, side="right")) - 1
            if 0 <= i < len(times) - 1 or (i == len(times) - 1 and t - times[-1] <= gap):
                quality = int(qualities[i]) if t - times[i] <= gap else 0
        for start, end, q in self.windows:
            if start - 1e-9 <= t < end - 1e-9:
                quality = q
        if quality == BRIDGING:
            since = self.bridged_since(t)
            quality = BRIDGED_QUALITY if t - since <= self.p["bridging_timeout"] else AFTER_BRIDGING
        return quality

    def step(self, t: float, dt: float) -> None:
        u, p, y = self.u, self.p, self.y
        self.history.append((u["x_true"], u["y_true"], u["vel_east_true"], u["vel_north_true"]))
        if self.outage_left == 0 and p["dropout_probability"] > 0 and self.rng.random() < p["dropout_probability"]:
            self.outage_left = max(1, int(round(p["dropout_duration"] / dt)))
        noise = self.rng.standard_normal(4).tolist()      # Python floats downstream
        if p["bias_std"] > 0:
            w = self.rng.standard_normal(2).tolist()
            self.bias = [gauss_markov_step(b, self.bias_phi, p["bias_std"], wi) for b, wi in zip(self.bias, w)]
        degraded = (0.0, 0.0)
        quality = self.quality_at(t)
        if self.degraded:
            std = self.error_std.get(quality, 0.0)
            degraded = (std * self.wander[0], std * self.wander[1])
            w = self.rng.standard_normal(2).tolist()
            self.wander = [gauss_markov_step(g, self.degraded_phi, 1.0, wi) for g, wi in zip(self.wander, w)]
        since = self.bridged_since(t) if self.bridging else None
        age = 0.0 if since is None else t - since
        if self.bridging:
            w = self.rng.standard_normal(2).tolist()
            self.bridge_wander = [gauss_markov_step(g, self.bridging_phi, 1.0, wi) for g, wi in zip(self.bridge_wander, w)]
            if since is not None and quality == BRIDGED_QUALITY:
                axis = bridging_error(age, p["bridging_error_start"], p["bridging_error_rate"]) / math.sqrt(2.0)
                degraded = (degraded[0] + axis * self.bridge_wander[0], degraded[1] + axis * self.bridge_wander[1])
        y["correction_age"] = age
        if self.outage_left > 0 or FIX_RANK.get(quality, 0) == 0:
            y["fix_valid"] = 0.0
            y["fix_quality"] = 0.0 if self.outage_left > 0 else float(quality)
            y["fix_age"] = t - self.last_fix_time
            self.outage_left = max(self.outage_left - 1, 0)
            return
        x, yy, ve, vn = self.history[0]
        sp, sv = p["position_noise_std"], p["velocity_noise_std"]
        bx, by = self.bias
        y["x"], y["y"] = x + sp * noise[0] + bx + degraded[0], yy + sp * noise[1] + by + degraded[1]
        y["vel_east"], y["vel_north"] = ve + sv * noise[2], vn + sv * noise[3]
        y["fix_valid"], y["fix_quality"] = 1.0, float(quality)
        self.last_fix_time = t
        y["fix_age"] = p["latency"]

    def linear_model(self, step: float, speed: float, ground: Ground = LEVEL) -> Block:
        """The true antenna position and velocity ``latency`` / step samples late (noise, bias and
        dropouts left out); on a slope the east position too (its lateral-channel share: the leaning
        antenna turning with the heading)."""
        ports = ["y", "vel_north"] + ([] if ground.level else ["x"])
        return delay_line(self.name, [f"{p}_true" for p in ports], ports, delay_steps(self.p["latency"], step))


COMPONENT = GPSSensor
