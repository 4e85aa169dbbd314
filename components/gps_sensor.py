"""RTK-GPS sensor (paper section II): antenna position and velocity, 2 cm noise at 20 Hz.

Error model: white noise (``position_noise_std``, the default worst case) plus, as an option, a
correlated RTK error per axis, first-order Gauss-Markov (``bias_std``, ``bias_time_constant``):
b_k+1 = exp(-dt/T) b_k + sqrt(1 - exp(-2 dt/T)) sigma_b w_k.

Output at sample k is the true antenna state of sample k - latency/dt plus white Gaussian noise.
Dropouts: a two-state chain; each sample starts an outage with probability
``dropout_probability``, an outage lasts ``dropout_duration`` seconds; during it the last fix is
held, ``fix_valid`` = 0, ``fix_quality`` = 0 (no fix) and ``fix_age`` grows.
"""
from __future__ import annotations

import math
from collections import deque

from orchestrator.component import Component, inp, out, par

from .hardware.nmea import RTK_FIXED


class GPSSensor(Component):
    sampled = True
    roles = ("gps",)
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
        out("x", "m", 0.0, "measured east position"),
        out("y", "m", 0.0, "measured north position"),
        out("vel_east", "m/s", 0.0, "measured east velocity"),
        out("vel_north", "m/s", 0.0, "measured north velocity"),
        out("fix_valid", "1", 1.0, "1 when this sample carries a new fix, else 0"),
        out("fix_age", "s", 0.0, "time since the last valid fix"),
        out("fix_quality", "1", float(RTK_FIXED), "GGA fix quality: 4 (RTK fixed) with a fix, 0 in an outage"),
    )
    feedthrough = {k: ("x_true", "y_true", "vel_east_true", "vel_north_true")
                   for k in ("x", "y", "vel_east", "vel_north")}

    def initialize(self, t0: float, dt: float) -> None:
        p = self.p
        lag = p["latency"] / dt
        self.require(p["latency"] >= 0 and math.isclose(lag, round(lag), abs_tol=1e-9),
                     f"latency {p['latency']} s must be a non-negative multiple of the step {dt} s")
        self.require(0 <= p["dropout_probability"] <= 1, "dropout_probability must be in [0, 1]")
        self.lag = int(round(lag))
        self.history: deque = deque(maxlen=self.lag + 1)
        self.outage_left = 0
        self.last_fix_time = t0
        self.require(p["bias_std"] >= 0 and p["bias_time_constant"] > 0,
                     "bias_std must be >= 0 and bias_time_constant > 0")
        # b_k+1 = phi b_k + sqrt(1 - phi^2) sigma_b w_k, phi = exp(-dt / T): stationary std sigma_b
        self.bias_phi = math.exp(-dt / p["bias_time_constant"])
        self.bias = self.rng.standard_normal(2) * p["bias_std"] if p["bias_std"] > 0 else (0.0, 0.0)

    def step(self, t: float, dt: float) -> None:
        u, p, y = self.u, self.p, self.y
        self.history.append((u["x_true"], u["y_true"], u["vel_east_true"], u["vel_north_true"]))
        if self.outage_left == 0 and p["dropout_probability"] > 0 and self.rng.random() < p["dropout_probability"]:
            self.outage_left = max(1, int(round(p["dropout_duration"] / dt)))
        noise = self.rng.standard_normal(4)
        if p["bias_std"] > 0:
            phi = self.bias_phi
            self.bias = phi * self.bias + math.sqrt(1 - phi * phi) * p["bias_std"] * self.rng.standard_normal(2)
        if self.outage_left > 0:
            self.outage_left -= 1
            y["fix_valid"] = y["fix_quality"] = 0.0
            y["fix_age"] = t - self.last_fix_time
            return
        x, yy, ve, vn = self.history[0]
        sp, sv = p["position_noise_std"], p["velocity_noise_std"]
        bx, by = self.bias
        y["x"], y["y"] = x + sp * noise[0] + bx, yy + sp * noise[1] + by
        y["vel_east"], y["vel_north"] = ve + sv * noise[2], vn + sv * noise[3]
        y["fix_valid"], y["fix_quality"] = 1.0, float(RTK_FIXED)
        self.last_fix_time = t
        y["fix_age"] = p["latency"]


COMPONENT = GPSSensor
