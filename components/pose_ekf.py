"""Pose EKF (paper section VI-A.3, eq. for the discrete kinematic model at R).

    x_{k+1}   = x_k + T_s v_k cos(psi_k)
    y_{k+1}   = y_k + T_s v_k sin(psi_k)
    psi_{k+1} = psi_k + T_s v_k tan(delta_k) / L

measurement h(x) = [x, y] (GPS antenna at R), w ~ N(0, Q), v ~ N(0, R). At sample k the filter
predicts with (v, delta) of sample k-1 and updates with the fix of sample k. Outputs: the pose at R
and, for the tracker, the CG = R + l_r (cos psi, sin psi). A non-finite fix or input is not used;
a state that goes non-finite anyway is reset to the last finite pose with the initial covariance
(logged with its reason).
"""
from __future__ import annotations

from pathlib import Path
import math

import numpy as np

from agrobot.orchestrator.compiled.cores import CoreDescription
from agrobot.orchestrator.component import Component, inp, out, par

from .models.loop_blocks import Block


# what every pose estimator starts from and gives (this EKF, the GNSS/INS one): swappable in a study
POSE_START = (
    par("x0", "m", 0.0, "initial east position of R"),
    par("y0", "m", 0.0, "initial north position of R"),
    par("psi0", "rad", 0.0, "initial heading estimate"),
    par("heading0_std", "rad", math.radians(30.0), "initial heading uncertainty"),
    par("position0_std", "m", 0.5, "initial position uncertainty"),
)
POSE_OUTPUTS = (
    out("x_rear", "m", 0.0, "estimated east position of R"),
    out("y_rear", "m", 0.0, "estimated north position of R"),
    out("heading", "rad", 0.0, "estimated yaw angle"),
    out("x_cg", "m", 0.0, "estimated east position of the CG"),
    out("y_cg", "m", 0.0, "estimated north position of the CG"),
    out("heading_std", "rad", 0.0, "heading standard deviation"),
)


class PoseEKF(Component):
    sampled = True
    roles = ("pose_estimator",)
    c_core = CoreDescription(Path(__file__).with_suffix(".c"))   # its C model core, beside this file
    variables = (
        inp("gps_x", "m", 0.0, "GPS east position of R"),
        inp("gps_y", "m", 0.0, "GPS north position of R"),
        inp("fix_valid", "1", 1.0, "1 when the GPS sample is a new fix (unconnected: every sample is)", optional=True),
        inp("speed", "m/s", 0.0, "longitudinal speed (speed KF)"),
        inp("steer_angle", "rad", 0.0, "measured front wheel angle"),
        par("wheelbase", "m", 1.4, "L = l_f + l_r"),
        par("l_r", "m", 0.4, "rear axle to CG"),
        par("position_process_std", "m", 0.003, "process noise per step, position"),
        par("heading_process_std", "rad", 0.003, "process noise per step, heading"),
        par("position_noise_std", "m", 0.02, "GPS position noise"),
    ) + POSE_START + POSE_OUTPUTS
    feedthrough = {k: ("gps_x", "gps_y", "fix_valid")
                   for k in ("x_rear", "y_rear", "heading", "x_cg", "y_cg", "heading_std")}

    def initialize(self, t0: float, dt: float) -> None:
        """State and the six entries of the symmetric covariance are kept as floats; predict and
        update are the matrix equations written out (tests: equal to the matrix form)."""
        p = self.p
        self.s = [float(p["x0"]), float(p["y0"]), float(p["psi0"])]
        p0, h0 = p["position0_std"] ** 2, p["heading0_std"] ** 2
        self.P = [p0, 0.0, 0.0, p0, 0.0, h0]             # P11 P12 P13 P22 P23 P33
        self.Q = (p["position_process_std"] ** 2, p["heading_process_std"] ** 2)
        self.r = p["position_noise_std"] ** 2
        self.prev_input: tuple[float, float] | None = None
        self.good = list(self.s)
        self._publish()

    def predict(self, v: float, delta: float, dt: float) -> None:
        """s <- f(s, v, delta);  P <- F P F' + Q with F = [[1, 0, f13], [0, 1, f23], [0, 0, 1]]."""
        x, y, psi = self.s
        c, s = math.cos(psi), math.sin(psi)
        self.s = [x + dt * v * c, y + dt * v * s, psi + dt * v * math.tan(delta) / self.p["wheelbase"]]
        f13, f23 = -dt * v * s, dt * v * c
        p11, p12, p13, p22, p23, p33 = self.P
        qp, qh = self.Q
        self.P = [p11 + 2 * f13 * p13 + f13 * f13 * p33 + qp,
                  p12 + f13 * p23 + f23 * p13 + f13 * f23 * p33,
                  p13 + f13 * p33,
                  p22 + 2 * f23 * p23 + f23 * f23 * p33 + qp,
                  p23 + f23 * p33,
                  p33 + qh]

    def update(self, zx: float, zy: float) -> None:
        """K = P H' (H P H' + R)^-1 with H = [I 0];  s <- s + K (z - H s);  P <- P - K H P."""
        p11, p12, p13, p22, p23, p33 = self.P
        s11, s22 = p11 + self.r, p22 + self.r
        det = s11 * s22 - p12 * p12
        ex, ey = zx - self.s[0], zy - self.s[1]
        k = [((pi1 * s22 - pi2 * p12) / det, (pi2 * s11 - pi1 * p12) / det)
             for pi1, pi2 in ((p11, p12), (p12, p22), (p13, p23))]
        self.s = [si + ki1 * ex + ki2 * ey for si, (ki1, ki2) in zip(self.s, k)]
        (k11, k12), (k21, k22), (k31, k32) = k
        self.P = [p11 - (k11 * p11 + k12 * p12), p12 - (k11 * p12 + k12 * p22),
                  p13 - (k11 * p13 + k12 * p23), p22 - (k21 * p12 + k22 * p22),
                  p23 - (k21 * p13 + k22 * p23), p33 - (k31 * p13 + k32 * p23)]

    def step(self, t: float, dt: float) -> None:
        u = self.u
        if self.prev_input is not None:
            self.predict(*self.prev_input, dt)
        isfinite = math.isfinite
        zx, zy = float(u["gps_x"]), float(u["gps_y"])
        if u["fix_valid"] > 0.5 and isfinite(zx) and isfinite(zy):
            self.update(zx, zy)
        v, delta = float(u["speed"]), float(u["steer_angle"])
        self.prev_input = (v, delta) if isfinite(v) and isfinite(delta) else None
        if not all(map(math.isfinite, self.s + self.P)):
            self.event(t, f"pose estimate went non-finite: reset to the last finite pose ({self.good[0]:.3f} m, "
                          f"{self.good[1]:.3f} m, {self.good[2]:.4f} rad) with the initial uncertainty")
            self.s = list(self.good)
            p0, h0 = self.p["position0_std"] ** 2, self.p["heading0_std"] ** 2
            self.P = [p0, 0.0, 0.0, p0, 0.0, h0]
        self.good = list(self.s)
        self._publish()

    def _publish(self) -> None:
        x, y, psi = self.s
        psi = math.atan2(math.sin(psi), math.cos(psi))
        self.s[2] = psi
        lr = self.p["l_r"]
        out_ = self.y
        out_["x_rear"], out_["y_rear"], out_["heading"] = x, y, psi
        out_["x_cg"], out_["y_cg"] = x + lr * math.cos(psi), y + lr * math.sin(psi)
        out_["heading_std"] = math.sqrt(self.P[5])

    def linear_model(self, step: float, speed: float) -> Block:
        """The EKF (components.pose_ekf) on the straight with its steady-state gain: the covariance
        recursion run with the component's own predict and update until it settles, then

            y- = y + T v psi,  psi- = psi + T v delta_{k-1} / L,  (y, psi) = (y-, psi-) + K (z - y-)

        outputs the updated R, heading and CG = R + l_r psi."""
        ekf = PoseEKF(self.name, {**self.p, "x0": 0.0, "y0": 0.0, "psi0": 0.0})
        ekf.initialize(0.0, step)
        P = None
        for _ in range(100000):
            ekf.predict(speed, 0.0, step)
            previous, P = P, list(ekf.P)
            ekf.update(0.0, 0.0)
            if previous is not None and np.allclose(previous, P, rtol=1e-12, atol=0.0):
                break
        p11, p12, p13, p22, p23, p33 = P
        Pm = np.array([[p11, p12, p13], [p12, p22, p23], [p13, p23, p33]])
        S = Pm[:2, :2] + ekf.r * np.eye(2)
        K = Pm[:, :2] @ np.linalg.inv(S)                  # columns: gps_x, gps_y
        ky, kpsi = K[1, 1], K[2, 1]
        T, L, lr = step, self.p["wheelbase"], self.p["l_r"]
        M = np.array([[1.0, T * speed, 0.0], [0.0, 1.0, T * speed / L]])      # (y-, psi-) from (y, psi, delta_prev)
        U = np.array([[1.0 - ky, 0.0], [-kpsi, 1.0]])                          # update, innovation z - y-
        Kz = np.array([ky, kpsi])
        A = np.vstack([U @ M, [0.0, 0.0, 0.0]])
        B = np.array([[ky, 0.0], [kpsi, 0.0], [0.0, 1.0]])                      # inputs (gps_y, steer_angle)
        out = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, lr]])                    # y_rear, heading, y_cg
        C = out @ U @ M
        D = np.column_stack([out @ Kz, np.zeros(3)])
        return Block.of(self.name, ["gps_y", "steer_angle"], ["y_rear", "heading", "y_cg"], A, B, C, D)


COMPONENT = PoseEKF
