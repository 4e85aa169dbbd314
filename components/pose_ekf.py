"""Pose EKF (paper section VI-A.3, eq. for the discrete kinematic model at R).

    x_{k+1}   = x_k + T_s v_k cos(psi_k)
    y_{k+1}   = y_k + T_s v_k sin(psi_k)
    psi_{k+1} = psi_k + T_s v_k tan(delta_k) / L

measurement h(x) = [x, y] (GPS antenna at R), w ~ N(0, Q), v ~ N(0, R). At sample k the filter
predicts with (v, delta) of sample k-1 and updates with the fix of sample k. Outputs: the pose at R
and, for the tracker, the CG = R + l_r (cos psi, sin psi).
"""
from __future__ import annotations

import math

import numpy as np

from orchestrator.component import Component, inp, out, par


class PoseEKF(Component):
    sampled = True
    variables = (
        inp("gps_x", "m", 0.0, "GPS east position of R"),
        inp("gps_y", "m", 0.0, "GPS north position of R"),
        inp("fix_valid", "1", 1.0, "1 when the GPS sample is a new fix"),
        inp("speed", "m/s", 0.0, "longitudinal speed (speed KF)"),
        inp("steer_angle", "rad", 0.0, "measured front wheel angle"),
        par("wheelbase", "m", 1.4, "L = l_f + l_r"),
        par("l_r", "m", 0.4, "rear axle to CG"),
        par("position_process_std", "m", 0.003, "process noise per step, position"),
        par("heading_process_std", "rad", 0.003, "process noise per step, heading"),
        par("position_noise_std", "m", 0.02, "GPS position noise"),
        par("x0", "m", 0.0, "initial east position of R"),
        par("y0", "m", 0.0, "initial north position of R"),
        par("psi0", "rad", 0.0, "initial heading estimate"),
        par("heading0_std", "rad", math.radians(30.0), "initial heading uncertainty"),
        par("position0_std", "m", 0.5, "initial position uncertainty"),
        out("x_rear", "m", 0.0, "estimated east position of R"),
        out("y_rear", "m", 0.0, "estimated north position of R"),
        out("heading", "rad", 0.0, "estimated yaw angle"),
        out("x_cg", "m", 0.0, "estimated east position of the CG"),
        out("y_cg", "m", 0.0, "estimated north position of the CG"),
        out("heading_std", "rad", 0.0, "heading standard deviation"),
    )
    feedthrough = {k: ("gps_x", "gps_y", "fix_valid")
                   for k in ("x_rear", "y_rear", "heading", "x_cg", "y_cg", "heading_std")}

    def initialize(self, t0: float, dt: float) -> None:
        p = self.p
        self.s = np.array([p["x0"], p["y0"], p["psi0"]], dtype=float)
        self.P = np.diag([p["position0_std"] ** 2] * 2 + [p["heading0_std"] ** 2])
        self.Q = np.diag([p["position_process_std"] ** 2] * 2 + [p["heading_process_std"] ** 2])
        self.R = np.eye(2) * p["position_noise_std"] ** 2
        self.prev_input: tuple[float, float] | None = None
        self._publish()

    def predict(self, v: float, delta: float, dt: float) -> None:
        x, y, psi = self.s
        c, s = math.cos(psi), math.sin(psi)
        self.s = np.array([x + dt * v * c, y + dt * v * s, psi + dt * v * math.tan(delta) / self.p["wheelbase"]])
        F = np.array([[1.0, 0.0, -dt * v * s], [0.0, 1.0, dt * v * c], [0.0, 0.0, 1.0]])
        self.P = F @ self.P @ F.T + self.Q

    def update(self, zx: float, zy: float) -> None:
        innovation = np.array([zx, zy]) - self.s[:2]
        S = self.P[:2, :2] + self.R
        K = self.P[:, :2] @ np.linalg.inv(S)
        self.s = self.s + K @ innovation
        self.P = self.P - K @ self.P[:2, :]
        self.P = 0.5 * (self.P + self.P.T)

    def step(self, t: float, dt: float) -> None:
        u = self.u
        if self.prev_input is not None:
            self.predict(*self.prev_input, dt)
        if u["fix_valid"] > 0.5:
            self.update(float(u["gps_x"]), float(u["gps_y"]))
        self.prev_input = (float(u["speed"]), float(u["steer_angle"]))
        self._publish()

    def _publish(self) -> None:
        x, y, psi = (float(v) for v in self.s)
        psi = math.atan2(math.sin(psi), math.cos(psi))
        self.s[2] = psi
        lr = self.p["l_r"]
        out_ = self.y
        out_["x_rear"], out_["y_rear"], out_["heading"] = x, y, psi
        out_["x_cg"], out_["y_cg"] = x + lr * math.cos(psi), y + lr * math.sin(psi)
        out_["heading_std"] = math.sqrt(self.P[2, 2])


COMPONENT = PoseEKF
