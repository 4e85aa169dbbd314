"""A notch filter on the measured yaw rate: removes a lightly damped yaw mode
(the RLFR tractor's, -0.62 +- 9.95j at 2 m/s) from what the yaw-rate controller sees, so that the
controller does not chase it with the steering.

Continuous prototype, centre w0, notch damping zeta_z (depth: |H(j w0)| = zeta_z / zeta_p), pole
damping zeta_p (width)::

    H(s) = (s^2 + 2 zeta_z w0 s + w0^2) / (s^2 + 2 zeta_p w0 s + w0^2)

discretised at the component's step by the bilinear (Tustin) transform with the frequency
pre-warped to w0 (scipy.signal.bilinear), so the notch sits exactly at w0; unit gain at DC.
``frequency = 0`` passes the signal through unchanged.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.signal import bilinear, tf2ss

from agrobot.orchestrator.component import Component, inp, out, par

from .models.loop_blocks import Block, passthrough


def notch_coefficients(w0: float, zeta_z: float, zeta_p: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """(b, a) of the discrete notch, a[0] = 1."""
    warped = 2.0 / dt * math.tan(w0 * dt / 2.0)          # the analogue centre that maps onto w0
    b = [1.0, 2.0 * zeta_z * warped, warped ** 2]
    a = [1.0, 2.0 * zeta_p * warped, warped ** 2]
    bd, ad = bilinear(b, a, fs=1.0 / dt)
    return np.asarray(bd) / ad[0], np.asarray(ad) / ad[0]


class YawRateNotch(Component):
    sampled = True
    roles = ("yaw_rate_filter",)
    variables = (
        inp("yaw_rate", "rad/s", 0.0, "measured yaw rate"),
        par("frequency", "rad/s", 0.0, "notch centre w0 (0: pass through)"),
        par("notch_damping", "1", 0.05, "zeta_z: the notch's depth zeta_z / zeta_p at w0"),
        par("pole_damping", "1", 0.7, "zeta_p: the notch's width"),
        out("yaw_rate_filtered", "rad/s", 0.0, "the yaw rate without its component near w0"),
    )
    feedthrough = {"yaw_rate_filtered": ("yaw_rate",)}

    def initialize(self, t0: float, dt: float) -> None:
        p = self.p
        w0 = float(p["frequency"])
        self.require(w0 >= 0, f"frequency must be >= 0 rad/s, got {w0}")
        self.require(w0 * dt < math.pi, f"frequency {w0} rad/s is above the Nyquist frequency {math.pi / dt:.3g} rad/s "
                     f"of the step {dt} s")
        self.require(0 <= p["notch_damping"] < p["pole_damping"], "need 0 <= notch_damping < pole_damping")
        self.passthrough = w0 == 0.0
        if not self.passthrough:
            self.b, self.a = notch_coefficients(w0, float(p["notch_damping"]), float(p["pole_damping"]), dt)
        self.x = self.y_prev = None

    def step(self, t: float, dt: float) -> None:
        u = float(self.u["yaw_rate"])
        if self.passthrough:
            self.y["yaw_rate_filtered"] = u
            return
        if self.x is None:                 # start at rest on the first value (no transient from zero)
            self.x, self.y_prev = [u, u], [u, u]
        b, a = self.b, self.a
        y = b[0] * u + b[1] * self.x[0] + b[2] * self.x[1] - a[1] * self.y_prev[0] - a[2] * self.y_prev[1]
        self.x = [u, self.x[0]]
        self.y_prev = [y, self.y_prev[0]]
        self.y["yaw_rate_filtered"] = y

    def linear_model(self, step: float, speed: float) -> Block:
        """The notch's difference equation (components.yaw_rate_notch), or a unit gain at frequency 0."""
        p = self.p
        if float(p["frequency"]) == 0.0:
            return passthrough(self.name, {"yaw_rate": "yaw_rate_filtered"})
        b, a = notch_coefficients(float(p["frequency"]), float(p["notch_damping"]), float(p["pole_damping"]), step)
        A, B, C, D = tf2ss(b, a)
        return Block.of(self.name, ["yaw_rate"], ["yaw_rate_filtered"], A, B, C, D)


COMPONENT = YawRateNotch
