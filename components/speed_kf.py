"""Speed Kalman filter (paper eq. 1): position-velocity model, velocity a random walk.

State [x, v_x, y, v_y] (east/north), x_{k+1} = Phi(T_s) x_k + w_k with Phi = blockdiag([[1, T_s],
[0, 1]]) twice; measurement z = [x, v_x, y, v_y] from the GPS. Process noise of a white
acceleration of spectral density q per axis: Q = q [[T^3/3, T^2/2], [T^2/2, T]].
Output speed = |v|, the speed of the antenna point R (= v_x of the tractor, no rear slip).
"""
from __future__ import annotations

import math

import numpy as np

from orchestrator.component import Component, inp, out, par


class SpeedKF(Component):
    sampled = True
    variables = (
        inp("x", "m", 0.0, "GPS east position"),
        inp("y", "m", 0.0, "GPS north position"),
        inp("vel_east", "m/s", 0.0, "GPS east velocity"),
        inp("vel_north", "m/s", 0.0, "GPS north velocity"),
        inp("fix_valid", "1", 1.0, "1 when the GPS sample is a new fix"),
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
        p = self.p
        one = np.array([[1.0, dt], [0.0, 1.0]])
        self.Phi = np.kron(np.eye(2), one)
        q = p["acceleration_psd"]
        self.Q = np.kron(np.eye(2), q * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]]))
        self.R = np.diag([p["position_noise_std"] ** 2, p["velocity_noise_std"] ** 2] * 2)
        self.x: np.ndarray | None = None
        self.P = np.diag([1.0, 1.0, 1.0, 1.0])

    def step(self, t: float, dt: float) -> None:
        u = self.u
        z = np.array([u["x"], u["vel_east"], u["y"], u["vel_north"]], dtype=float)
        if self.x is None:
            self.x = z.copy()
            self.P = self.R.copy()
        else:
            self.x = self.Phi @ self.x
            self.P = self.Phi @ self.P @ self.Phi.T + self.Q
            if u["fix_valid"] > 0.5:
                S = self.P + self.R
                K = np.linalg.solve(S, self.P).T          # P S^-1 (P, S symmetric)
                self.x = self.x + K @ (z - self.x)
                self.P = (np.eye(4) - K) @ self.P
        ve, vn = float(self.x[1]), float(self.x[3])
        self.y["vel_east"], self.y["vel_north"], self.y["speed"] = ve, vn, math.hypot(ve, vn)


COMPONENT = SpeedKF
