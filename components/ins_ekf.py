"""GNSS/INS pose estimator: the tractor's ground point R dead-reckoned from the yaw gyro and the
wheel odometry at the IMU rate, corrected by the GNSS antenna's fixes weighted by their quality,
the antenna brought down to the ground through the IMU's roll and pitch (terrain compensation).

State s = [x, y, psi, b_g, e_v, k, b_x, b_y]: R (east, north), heading, gyro bias, odometry scale
error, the rear axle's slip compliance and the receiver's slowly wandering error. Inputs each step: gyro omega, roll phi, pitch theta and the
lateral specific force f_y (IMU), wheel speed v_o. Kinematics (no wheel lifts; the attitude
changes slowly):

    dpsi/dt = (omega - b_g) / (cos(phi) cos(theta)),      v = v_o (1 + e_v)
    v_lat   = -k f_y v                                     (crab of R, left positive)
    dx/dt   = v cos(psi) - v_lat sin(psi),   dy/dt = v sin(psi) + v_lat cos(psi)

The crab: in steady cornering or on a side slope the tyres carry m f_y (f_y the lateral specific
force: what the accelerometer measures), the rear's share l_f/L of it at the slip angle
alpha_r = F_r / C_r, so R moves sideways at v alpha_r = -(m l_f / (L C_r)) f_y v: k = m l_f / (L C_r),
about 5.6e-3 s2/m for the paper's tractor, estimated here (the soil sets C_r). b_g, e_v and k
are random walks (process noise from the sensor grades, models.sensor_grades). A tractor at rest
does not turn: with v_o = 0 the heading holds and the gyro reading measures b_g (a zero-rate update).

Fix update (each new fix: fix_valid and a new position; GGA quality 4 RTK fixed, 5 float, 2/3/9
DGPS, 1 single; 0, 6-8 carry none), antenna at (forward, left, height) in the body frame:

    z = (x, y) + [Rz(psi) Ry(-theta) Rx(phi) (forward, left, height)]_east,north + (b_x, b_y) + v,
    v ~ N(0, (sigma_w^2 + (height sigma_att)^2) I)

A degraded fix's error is not white: it wanders over a minute or more (models.sensor_grades), and
a filter that took it as white would average it away and trust itself far too much. So (b_x, b_y)
is a first-order Gauss-Markov error of the quality's std sigma_q and ``degraded_time_constant``;
when the quality changes it starts afresh (0, variance sigma_q^2); with RTK fixed sigma_q = 0 (the
2 cm are white, sigma_w). Each quality is thus weighed by its accuracy, over time too.

With ``terrain_compensation = 0`` the antenna is taken as standing on flat ground (phi = theta = 0
in h). Outputs: the pose (R and CG = R + l_r (cos psi, sin psi)), the crab for the tracker's
feed-forward, and the CG's cross-track standard deviation sqrt(n' P n), n the body's left axis,
for a watchdog to stop on. The speed output (for the speed controller) is v_o (1 + e_v) through a
first-order low-pass of ``speed_time_constant`` (the wheel speed's sample noise). A non-finite fix
or IMU/odometry input is not used; a state that goes non-finite anyway is reset to the last finite
one with the initial covariance (logged with its reason).
"""
from __future__ import annotations

import math

import numpy as np

from agrobot.orchestrator.component import Component, inp, out, par

from .hardware.nmea import FIX_RANK
from .models import sensor_grades as grade
from .models.terrain import lever_offset
from .pose_ekf import POSE_OUTPUTS, POSE_START
from .models.loop_blocks import Block, Ground, LEVEL

# the wandering error's std by GGA quality (models.sensor_grades.FIX_ERROR_STD: the defaults)
QUALITY_PARAMETER = {4: "rtk_fixed_bias_std", 5: "rtk_float_std", 2: "dgps_std", 3: "dgps_std", 9: "dgps_std",
                     1: "single_std"}
N = 8                                  # states


_INS_BLOCKS: dict[tuple, Block] = {}        # the settled gains, per parameters and operating point (seconds each)

INS_INPUTS = ["gps_x", "gps_y", "yaw_rate", "roll", "accel_left", "pitch"]


INS_OUTPUTS = ["y_rear", "heading", "y_cg", "lateral_velocity"]


def _lean(p, roll: float, pitch: float, eps: float = 1e-7) -> np.ndarray:
    """d (antenna east, north) / d (roll, pitch) at psi = 0 as the filter models the antenna
    (nil without terrain compensation): a 2 x 2 matrix, central differences of models.terrain."""
    if not p["terrain_compensation"]:
        return np.zeros((2, 2))
    lever = (p["antenna_forward"], p["antenna_left"], p["antenna_height"])
    out = np.zeros((2, 2))
    for j, (dr, dp) in enumerate(((eps, 0.0), (0.0, eps))):
        up = lever_offset(roll + dr, pitch + dp, 0.0, *lever)
        down = lever_offset(roll - dr, pitch - dp, 0.0, *lever)
        out[:, j] = (np.array(up) - np.array(down)) / (2 * eps)
    return out


def _ins_ekf(comp, step: float, speed: float, fix_every: int, fix_phase: int, ground: Ground) -> Block:
    p = comp.p
    k0 = (ground.slip_compliance(speed) if not ground.level else float(p["slip_compliance0"])) \
        if p["crab_estimate"] else 0.0
    roll, pitch, f0 = ground.roll, ground.pitch, ground.specific_force
    ekf = INSEKF(comp.name, {**p, "x0": 0.0, "y0": 0.0, "psi0": 0.0, "slip_compliance0": k0})
    ekf.initialize(0.0, step)
    n, R = 8, (p["fix_noise_std"] ** 2 + (p["antenna_height"] * p["attitude_noise_std"]) ** 2) * np.eye(2)
    gains, previous = [None] * fix_every, None
    for cycle in range(20000):
        for j in range(fix_every):
            ekf.predict(0.0, roll, pitch, f0, speed, step)
            ekf.s[:3] = 0.0                                      # stay at the operating point (psi = 0)
            if j == fix_phase % fix_every:
                h, H = ekf.antenna(roll, pitch)
                gains[j] = np.linalg.solve(H @ ekf.P @ H.T + R, H @ ekf.P).T
                ekf.update(h, h, H, R)
        K = gains[fix_phase % fix_every]
        if previous is not None and np.allclose(previous, K, rtol=1e-10, atol=1e-14):
            break
        previous = K.copy()
    ekf.s = np.array([0.0, 0.0, 0.0, 0.0, 0.0, k0, 0.0, 0.0])
    _, entries, tilt = ekf.jacobian(0.0, roll, pitch, f0, speed, step)
    F = np.eye(n)
    for (i, j), f in entries.items():
        F[i, j] += f
    F[6, 6] = F[7, 7] = math.exp(-step / p["degraded_time_constant"])
    _, H = ekf.antenna(roll, pitch)
    lean = _lean(p, roll, pitch)                                 # d(antenna) / d(roll, pitch)
    # X = [s; omega'; f_y'], u = (gps_x, gps_y, yaw_rate, roll, accel_left, pitch)
    G = np.zeros((n, 2))
    G[1, 1], G[2, 0] = -step * k0 * speed, step / tilt           # from f_y' and omega'
    M = np.hstack([F, G])                                        # s- from X
    lr = float(p["l_r"])
    out = np.zeros((4, n))
    out[0, 1], out[1, 2], out[2, 1], out[2, 2] = 1.0, 1.0, 1.0, lr
    out[3, 4], out[3, 5] = -k0 * f0 * speed, -f0 * speed         # the crab -k f_y v(1 + e_v) about k0, f0
    crab = np.array([0.0, 0.0, 0.0, 0.0, -k0 * speed, 0.0])      # lateral_velocity from this step's f_y
    hold = np.zeros((2, 6))
    hold[0, 2] = hold[1, 4] = 1.0                                # omega', f_y' <- this step's inputs
    phases = []
    for j in range(fix_every):
        if gains[j] is None:
            Ms, Ns = M, np.zeros((n, 6))
        else:
            K = gains[j]
            Ms = M - K @ H @ M
            Ns = np.zeros((n, 6))
            Ns[:, 0:2] = K
            Ns[:, 3] = -K @ lean[:, 0]
            Ns[:, 5] = -K @ lean[:, 1]
        A = np.vstack([Ms, np.zeros((2, n + 2))])
        B = np.vstack([Ns, hold])
        C = out @ Ms
        D = out @ Ns
        D[3] += crab
        phases.append((A, B, C, D))
    block = Block.of(comp.name, INS_INPUTS, INS_OUTPUTS, *phases[0])
    block.phases = phases if fix_every > 1 else None
    return block


class INSEKF(Component):
    sampled = True
    roles = ("pose_estimator",)
    FIX_INPUT = "gps_y"   # the input whose cadence sets its linear model's periodic gains
    variables = (
        inp("gps_x", "m", 0.0, "GNSS antenna east position"),
        inp("gps_y", "m", 0.0, "GNSS antenna north position"),
        inp("fix_valid", "1", 1.0, "1 while the receiver gives a position"),
        inp("fix_quality", "1", 4.0, "GGA fix quality of that position"),
        inp("yaw_rate", "rad/s", 0.0, "gyro about the body's up axis"),
        inp("roll", "rad", 0.0, "IMU roll (left side up positive)"),
        inp("pitch", "rad", 0.0, "IMU pitch (nose up positive)"),
        inp("accel_left", "m/s2", 0.0, "IMU lateral specific force f_y"),
        inp("speed", "m/s", 0.0, "wheel odometry speed v_o"),
        par("l_r", "m", 0.4, "rear axle to CG"),
        par("antenna_forward", "m", 0.0, "GNSS antenna ahead of R"),
        par("antenna_left", "m", 0.0, "GNSS antenna left of R"),
        par("antenna_height", "m", 0.0, "GNSS antenna above the ground at R"),
        par("terrain_compensation", "1", 1, "1: the antenna brought to the ground through roll and pitch; 0: not"),
        par("crab_estimate", "1", 1, "1: estimate the slip compliance k (the crab on slopes and in turns); 0: k = 0"),
        par("fix_noise_std", "m", grade.FIX_ERROR_STD[4], "white error of every fix, 1 sigma per axis (the paper's RTK noise)"),
        par("rtk_fixed_bias_std", "m", 0.0, "wandering error of an RTK fixed fix (quality 4), per axis"),
        par("rtk_float_std", "m", grade.FIX_ERROR_STD[5], "... of an RTK float fix (quality 5)"),
        par("dgps_std", "m", grade.FIX_ERROR_STD[2], "... of a DGPS fix (qualities 2, 3, 9)"),
        par("single_std", "m", grade.FIX_ERROR_STD[1], "... of a single-point fix (quality 1)"),
        par("degraded_time_constant", "s", grade.DEGRADED_ERROR_TIME_CONSTANT, "the wandering error's correlation time"),
        par("gyro_noise_psd", "rad2/s", grade.GYRO_NOISE_DENSITY ** 2, "gyro rate noise PSD"),
        par("gyro_bias_std", "rad/s", grade.GYRO_TURN_ON_BIAS, "initial gyro bias uncertainty"),
        par("gyro_bias_instability", "rad/s", grade.GYRO_BIAS_INSTABILITY, "in-run bias std (with its time constant: "
            "the bias's random walk 2 sigma^2 / T)"),
        par("gyro_bias_time_constant", "s", grade.GYRO_BIAS_TIME_CONSTANT, "in-run bias correlation time"),
        par("attitude_noise_std", "rad", grade.ATTITUDE_NOISE, "IMU roll and pitch noise (on the antenna's height)"),
        par("odometry_noise_std", "m/s", grade.ODOMETRY_NOISE, "wheel speed white noise per sample"),
        par("odometry_scale_std", "1", grade.ODOMETRY_SCALE_ERROR, "initial odometry scale uncertainty"),
        par("odometry_scale_wander", "1", grade.ODOMETRY_SLIP_WANDER, "scale wander std (random walk 2 sigma^2 / T)"),
        par("odometry_scale_time_constant", "s", grade.ODOMETRY_SLIP_TIME_CONSTANT, "its correlation time"),
        par("slip_compliance0", "s2/m", 0.0, "initial slip compliance k"),
        par("slip_compliance_std", "s2/m", 0.01, "its initial uncertainty"),
        par("slip_compliance_rate_std", "s2/m/s", 1e-4, "its random walk, per sqrt(s)"),
        par("velocity_noise_psd", "m2/s", 1e-5, "unmodelled velocity of R, per axis (transient slip)"),
        par("speed_time_constant", "s", 0.2, "low-pass of the speed output"),
    ) + POSE_START + POSE_OUTPUTS + (
        out("cross_track_std", "m", 0.0, "standard deviation of the CG's position across the heading"),
        out("lateral_velocity", "m/s", 0.0, "estimated crab of R, left positive (for the tracker)"),
        out("speed", "m/s", 0.0, "estimated speed v_o (1 + e_v), low-passed"),
        out("gyro_bias", "rad/s", 0.0, "estimated gyro bias"),
        out("odometry_scale_error", "1", 0.0, "estimated e_v"),
        out("slip_compliance", "s2/m", 0.0, "estimated k"),
        out("fix_used", "1", 0.0, "GGA quality of the fix used in this step (0: dead reckoning)"),
        out("time_since_fix", "s", 0.0, "time since the last fix was used"),
    )
    feedthrough = {o.name: ("gps_x", "gps_y", "fix_valid", "fix_quality", "yaw_rate", "roll", "pitch", "accel_left",
                            "speed")
                   for o in variables if o.causality == "output"}

    def initialize(self, t0: float, dt: float) -> None:
        p = self.p
        self.require(p["fix_noise_std"] > 0, f"parameter fix_noise_std must be > 0, got {p['fix_noise_std']}")
        for key in ("rtk_fixed_bias_std", "rtk_float_std", "dgps_std", "single_std"):
            self.require(p[key] >= 0, f"parameter {key} must be >= 0, got {p[key]}")
        for key in ("gyro_bias_time_constant", "odometry_scale_time_constant", "degraded_time_constant"):
            self.require(p[key] > 0, f"parameter {key} must be > 0, got {p[key]}")
        self.s = np.array([p["x0"], p["y0"], p["psi0"], 0.0, 0.0, p["slip_compliance0"], 0.0, 0.0], float)
        k0 = p["slip_compliance_std"] if p["crab_estimate"] else 0.0
        self.P = np.diag([p["position0_std"] ** 2, p["position0_std"] ** 2, p["heading0_std"] ** 2,
                          p["gyro_bias_std"] ** 2, p["odometry_scale_std"] ** 2, k0 ** 2, 0.0, 0.0])
        self.error_quality, self.error_std = 4, p["rtk_fixed_bias_std"]
        self.start_error(4)
        if not p["crab_estimate"]:
            self.s[5] = 0.0
        self.q_bias = 2 * p["gyro_bias_instability"] ** 2 / p["gyro_bias_time_constant"]
        self.q_scale = 2 * p["odometry_scale_wander"] ** 2 / p["odometry_scale_time_constant"]
        self.q_k = p["slip_compliance_rate_std"] ** 2 if p["crab_estimate"] else 0.0
        self.previous: tuple[float, ...] | None = None
        self.last_fix: tuple[float, float] | None = None
        self.last_fix_time = t0
        self.require(p["speed_time_constant"] >= 0, "parameter speed_time_constant must be >= 0")
        self.speed_gain = 1.0 - math.exp(-dt / p["speed_time_constant"]) if p["speed_time_constant"] > 0 else 1.0
        self.speed = 0.0
        self.good, self.P0 = self.s.copy(), self.P.copy()
        self._publish(0.0, 0.0, t0)

    # --- the filter ----------------------------------------------------------------------------
    def jacobian(self, omega: float, roll: float, pitch: float, f_y: float, v_o: float, dt: float):
        """(f(s, u), the non-zero entries {(i, j): F_ij - delta_ij} of its Jacobian, tilt)."""
        x, y, psi, b_g, e_v, k = self.s[:6]
        c, s = math.cos(psi), math.sin(psi)
        tilt = max(math.cos(roll) * math.cos(pitch), 0.5)
        v = v_o * (1.0 + e_v)
        v_lat = -k * f_y * v
        moved = np.array([x + dt * (v * c - v_lat * s), y + dt * (v * s + v_lat * c), psi + dt * (omega - b_g) / tilt,
                          b_g, e_v, k, *self.s[6:]])
        entries = {(0, 2): -dt * (v * s + v_lat * c), (1, 2): dt * (v * c - v_lat * s),
                   (0, 4): dt * v_o * (c + k * f_y * s), (1, 4): dt * v_o * (s - k * f_y * c),
                   (0, 5): dt * f_y * v * s, (1, 5): -dt * f_y * v * c, (2, 3): -dt / tilt}
        return moved, entries, tilt

    def predict(self, omega: float, roll: float, pitch: float, f_y: float, v_o: float, dt: float) -> None:
        """s <- f(s, u) over dt; P <- F P F' + Q, F = I + the Jacobian's few entries (applied as row
        and column operations; tests: equal to the dense product). The receiver's error decays by
        phi = exp(-dt / T) (its Gauss-Markov), at rest too."""
        p, P = self.p, self.P
        psi = self.s[2]
        phi = math.exp(-dt / p["degraded_time_constant"])
        q = np.array([0.0, 0.0, 0.0, self.q_bias * dt, self.q_scale * dt, self.q_k * dt,
                      *(2 * [(1.0 - phi * phi) * self.error_std ** 2])])
        entries = {(6, 6): phi - 1.0, (7, 7): phi - 1.0}
        self.s[6:] *= phi
        if abs(v_o) > 1e-3:
            self.s, moving, tilt = self.jacobian(omega, roll, pitch, f_y, v_o, dt)
            entries.update(moving)
        A = P.copy()                                               # A = F P: row operations
        for (i, j), f in entries.items():
            A[i] += f * P[j]
        P = A.copy()                                               # F P F' = A F': column operations
        for (i, j), f in entries.items():
            P[:, i] += f * A[:, j]
        if abs(v_o) > 1e-3:
            c, s = math.cos(psi), math.sin(psi)
            along = (p["odometry_noise_std"] * dt) ** 2            # the wheel speed's noise, along the heading
            qv = p["velocity_noise_psd"] * dt
            P[0, 0] += along * c * c + qv
            P[1, 1] += along * s * s + qv
            P[0, 1] += along * c * s
            P[1, 0] += along * c * s
            q[2] = p["gyro_noise_psd"] * dt / tilt ** 2
        P[np.diag_indices(N)] += q
        self.P = P

    def start_error(self, quality: int) -> None:
        """A new quality: its wandering error starts afresh, 0 with its variance, uncorrelated."""
        self.error_quality = quality
        self.error_std = float(self.p[QUALITY_PARAMETER[quality]])
        self.s[6:] = 0.0
        self.P[6:, :] = 0.0
        self.P[:, 6:] = 0.0
        self.P[6, 6] = self.P[7, 7] = self.error_std ** 2

    def update(self, z: np.ndarray, h: np.ndarray, H: np.ndarray, R: np.ndarray) -> None:
        """Joseph-form EKF update with innovation z - h."""
        S = H @ self.P @ H.T + R
        K = np.linalg.solve(S, H @ self.P).T
        self.s = self.s + K @ (z - h)
        A = np.eye(N) - K @ H
        self.P = A @ self.P @ A.T + K @ R @ K.T

    def antenna(self, roll: float, pitch: float) -> tuple[np.ndarray, np.ndarray]:
        """(h(s), H): the antenna's horizontal position and its Jacobian."""
        p = self.p
        if not p["terrain_compensation"]:
            roll = pitch = 0.0
        ox, oy = lever_offset(roll, pitch, float(self.s[2]), p["antenna_forward"], p["antenna_left"],
                              p["antenna_height"])
        H = np.zeros((2, N))
        H[0, 0] = H[1, 1] = H[0, 6] = H[1, 7] = 1.0
        H[0, 2], H[1, 2] = -oy, ox                                 # d/dpsi of the lever turned by psi
        return np.array([self.s[0] + ox + self.s[6], self.s[1] + oy + self.s[7]]), H

    def step(self, t: float, dt: float) -> None:
        with np.errstate(over="ignore", invalid="ignore"):      # a state blown up is caught and reset below
            self._step(t, dt)

    def _step(self, t: float, dt: float) -> None:
        u, p = self.u, self.p
        if self.previous is not None:
            self.predict(*self.previous, dt)
        omega, roll, pitch = float(u["yaw_rate"]), float(u["roll"]), float(u["pitch"])
        v_o = float(u["speed"])
        inputs = (omega, roll, pitch, float(u["accel_left"]), v_o)
        if not all(map(math.isfinite, inputs)):           # a bad sample: no dead reckoning over it
            self.previous = None
            self._publish(0.0, 0.0, t)
            return
        if abs(v_o) <= 1e-3:                                       # at rest: the gyro reads its bias
            H = np.zeros((1, N))
            H[0, 3] = 1.0
            self.update(np.array([omega]), np.array([self.s[3]]), H, np.array([[p["gyro_noise_psd"] / dt]]))
        used = 0.0
        fix = (float(u["gps_x"]), float(u["gps_y"]))
        quality = int(u["fix_quality"]) if math.isfinite(u["fix_quality"]) else 0
        if u["fix_valid"] > 0.5 and FIX_RANK.get(quality, 0) > 0 and fix != self.last_fix \
                and all(map(math.isfinite, fix)):
            self.last_fix, self.last_fix_time, used = fix, t, float(quality)
            if quality != self.error_quality:
                self.start_error(quality)
            r = p["fix_noise_std"] ** 2 + (p["antenna_height"] * p["attitude_noise_std"]) ** 2
            h, H = self.antenna(roll, pitch)
            self.update(np.array(fix), h, H, r * np.eye(2))
        self.previous = inputs
        if not (np.all(np.isfinite(self.s)) and np.all(np.isfinite(self.P))):
            self.event(t, f"pose estimate went non-finite: reset to the last finite state ({self.good[0]:.3f} m, "
                          f"{self.good[1]:.3f} m, {self.good[2]:.4f} rad) with the initial covariance")
            self.s, self.P = self.good.copy(), self.P0.copy()
        self.good = self.s.copy()
        self._publish(float(u["accel_left"]), v_o, t, used)

    def _publish(self, f_y: float, v_o: float, t: float, used: float = 0.0) -> None:
        x, y_, psi, b_g, e_v, k = self.s[:6]
        psi = math.atan2(math.sin(psi), math.cos(psi))
        self.s[2] = psi
        lr = self.p["l_r"]
        c, s = math.cos(psi), math.sin(psi)
        P = self.P
        y = self.y
        y["x_rear"], y["y_rear"], y["heading"] = float(x), float(y_), psi
        y["x_cg"], y["y_cg"] = float(x + lr * c), float(y_ + lr * s)
        y["heading_std"] = math.sqrt(max(P[2, 2], 0.0))
        # the CG across the heading moves by n . dR + l_r dpsi, n = (-sin psi, cos psi): n' P n with n = (-s, c, l_r)
        var = (s * s * P[0, 0] - 2 * s * c * P[0, 1] + c * c * P[1, 1] + 2 * lr * (c * P[1, 2] - s * P[0, 2])
               + lr * lr * P[2, 2])
        y["cross_track_std"] = math.sqrt(max(float(var), 0.0))
        v = v_o * (1.0 + e_v)
        self.speed += self.speed_gain * (v - self.speed)
        y["speed"], y["lateral_velocity"] = self.speed, -k * f_y * v
        y["gyro_bias"], y["odometry_scale_error"], y["slip_compliance"] = float(b_g), float(e_v), float(k)
        y["fix_used"], y["time_since_fix"] = used, t - self.last_fix_time

    def linear_model(self, step: float, speed: float, fix_every: int = 1, fix_phase: int = 0, ground: Ground = LEVEL) -> Block:
        """The GNSS/INS EKF (components.ins_ekf) on the straight, its gains periodic: a fix every
        ``fix_every``-th of its steps, at the steps j = ``fix_phase`` (mod fix_every). On level ground k
        stays at its initial value k0 (f_y = 0 leaves k unobservable and uncoupled); on a slope
        (``ground``: roll phi_0, pitch theta_0, the steady left specific force f_0 the IMU reads) the filter
        has learnt the crab, k0 = -crab / (f_0 v) (Ground.slip_compliance), and k is coupled and observable.
        The covariance recursion is run with the component's own predict and update at that operating
        point until the gains of a whole cycle settle; then, all eight states s = [x, y, psi, b_g, e_v, k,
        b_x, b_y] and the inputs of the previous step (the component predicts with them):

            s- = F s + dt (0, -k0 v f_y', omega' / (cos phi_0 cos theta_0), 0, ...)
                                              F = I + the component's own Jacobian entries at (phi_0, theta_0,
                                              f_0, k0): on a slope y' gains -f_0 v k and -k0 f_0 v e_v;
                                              b_x, b_y decaying by exp(-dt / T)
            s  = s- + K_j (z - H s- - (dh/dphi) phi - (dh/dtheta) theta)    on a fix step (H: the component's
                                              antenna Jacobian at phi_0, theta_0; dh/dphi, dh/dtheta the
                                              antenna's lean with terrain compensation, nil without)

        outputs the updated R (north), heading, CG = R + l_r psi and the crab's deviation
        -v (k0 f_y + f_0 k + k0 f_0 e_v) of this step."""
        key = (repr(sorted(self.p.items())), step, speed, fix_every, fix_phase, ground)
        if key not in _INS_BLOCKS:
            _INS_BLOCKS[key] = _ins_ekf(self, step, speed, fix_every, fix_phase, ground)
        block = _INS_BLOCKS[key]
        return Block(self.name, block.inputs, block.outputs, block.A, block.B, block.C, block.D, block.ratio,
                     block.sampled, block.phases)


COMPONENT = INSEKF
