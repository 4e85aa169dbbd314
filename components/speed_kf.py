"""Speed Kalman filter (paper eq. 1): position-velocity model, velocity a random walk.

State [x, v_x, y, v_y] (east/north), x_{k+1} = Phi(T_s) x_k + w_k with Phi = blockdiag([[1, T_s],
[0, 1]]) twice; measurement z = [x, v_x, y, v_y] from the GPS. Process noise of a white
acceleration of spectral density q per axis: Q = q [[T^3/3, T^2/2], [T^2/2, T]].
Output speed = |v|, the speed of the antenna point R (= v_x of the tractor, no rear slip).
"""
from __future__ import annotations

from pathlib import Path
import math

from agrobot.orchestrator.compiled.cores import CoreDescription
from agrobot.orchestrator.component import Component, inp, out, par


class SpeedKF(Component):
    sampled = True
    roles = ("speed_estimator",)
    c_core = CoreDescription(Path(__file__).with_suffix(".c"))   # its C model core, beside this file
    OFF_THE_LATERAL_LOOP = True   # moves nothing of the lateral channel at first order (margins)
    variables = (
        inp("x", "m", 0.0, "GPS east position"),
        inp("y", "m", 0.0, "GPS north position"),
        inp("vel_east", "m/s", 0.0, "GPS east velocity"),
        inp("vel_north", "m/s", 0.0, "GPS north velocity"),
        inp("fix_valid", "1", 1.0, "1 when the GPS sample is a new fix (unconnected: every sample is)", optional=True),
        par("acceleration_psd", "m2/s3", 0.005, "white-acceleration spectral density q"),
        par("position_noise_std", "m", 0.02, "GPS position noise"),
        par("velocity_noise_std", "m/s", 0.02, "GPS velocity noise"),
        out("speed", "m/s", 0.0, "filtered speed |v|"),
        out("vel_east", "m/s", 0.0, "filtered east velocity"),
        out("vel_north", "m/s", 0.0, "filtered north velocity"),
    )
    feedthrough = {k: ("x", "y", "vel_east", "vel_north", "fix_valid")
                   for k in ("speed", "vel_east", "vel_north")}

    def initialize(self, t0: float, dt: float) -> None:
        """Both axes have the same Phi, Q, R and initial P, so they share one 2x2 covariance
        [[a, b], [b, c]]; the filter is written out in scalars (tests: equal to the 4-state
        matrix form)."""
        p = self.p
        q = p["acceleration_psd"]
        self.T = dt
        self.Q = (q * dt**3 / 3, q * dt**2 / 2, q * dt)
        self.R = (p["position_noise_std"] ** 2, p["velocity_noise_std"] ** 2)
        self.state: list[float] | None = None          # [x, v_east, y, v_north]
        self.P = (self.R[0], 0.0, self.R[1])

    def step(self, t: float, dt: float) -> None:
        u = self.u
        z = (float(u["x"]), float(u["vel_east"]), float(u["y"]), float(u["vel_north"]))
        if self.state is None:
            self.state = list(z)
        else:
            T, (q11, q12, q22), (rp, rv) = self.T, self.Q, self.R
            a, b, c = self.P
            st = self.state
            st[0] += T * st[1]
            st[2] += T * st[3]
            a, b, c = a + 2 * T * b + T * T * c + q11, b + T * c + q12, c + q22
            if u["fix_valid"] > 0.5:
                det = (a + rp) * (c + rv) - b * b      # K = P (P + R)^-1
                k11, k12 = (a * (c + rv) - b * b) / det, b * rp / det
                k21, k22 = b * rv / det, (c * (a + rp) - b * b) / det
                for i in (0, 2):
                    ep, ev = z[i] - st[i], z[i + 1] - st[i + 1]
                    st[i] += k11 * ep + k12 * ev
                    st[i + 1] += k21 * ep + k22 * ev
                a, b, c = a - (k11 * a + k12 * b), b - (k11 * b + k12 * c), c - (k21 * b + k22 * c)
            self.P = (a, b, c)
        ve, vn = self.state[1], self.state[3]
        self.y["vel_east"], self.y["vel_north"], self.y["speed"] = ve, vn, math.hypot(ve, vn)


COMPONENT = SpeedKF
