"""The guidance loop of a study as a linear network: its own components, linearised about a
straight line, wired by its own connections, run on the orchestrator's schedule.

Operating point: the tractor drives a straight line heading east (psi = 0) at speed v, on its
reference, wheels centred. First-order deviations split into a longitudinal channel (east positions,
speeds) and a lateral channel (north positions and velocities, heading, yaw rate, wheel angles); on a
straight the two do not couple, so the steering loop is the lateral channel alone and the speed loop
(speed PID, drivetrain, speed KF) only sets the operating point.

Each component on the loop becomes a discrete block at its own step, inputs and outputs named by port:

- trackers and routes declare theirs (``lateral_linearisation(speed, dt, along_track_error)``: a python-control
  StateSpace whose labels are port names);
- the yaw plant, steering, GPS, gyro, IMU, pose EKF, GNSS/INS EKF, yaw-rate MPC, notch, computation
  delay and watchdog are linearised here, each from its own step equations and parameters without the nonlinearities a
  small signal beyond the dead bands does not see (dead bands, quantisation, saturations);
- a composite subsystem is its inner network lifted over its step.

A block may change from step to step with a period of its own (``Block.phases``: the INS EKF takes
a fix on every n-th of its steps); the network's period then covers that cycle too.

Schedule (orchestrator.engine): at each base instant continuous blocks publish the state they
reached, sampled blocks step in the study's evaluation order (y = C x + D u, then x <- A x + B u),
then continuous blocks integrate with the inputs of the instant held (their A, B: the exact
zero-order-hold step). Over one period (the least common multiple of the steps) the network is
time-invariant: running the schedule once on matrices instead of numbers gives its period map

    X+ = Phi X + Gamma w,    z = H X + J w

with w injected at chosen inputs (a loop opened there) and z what their sources delivered: exact
for the linear blocks, the multirate sampling included.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from orchestrator.errors import InputError


class NoLinearModel(InputError):
    """The study's loop holds a component this module cannot linearise, or has no loop."""


@dataclass(frozen=True)
class OperatingPoint:
    """A straight line heading east at ``speed``, the CG on the reference's line
    ``along_track_error`` behind its point (a time-based reference: what the speed loop leaves)."""

    speed: float
    along_track_error: float = 0.0
    label: str = ""


@dataclass
class Block:
    """A discrete linear block at ``ratio`` base steps: sampled y = C x + D u, x <- A x + B u;
    continuous (D = 0) x <- A x + B u, published y = C x at its next instant."""

    name: str
    inputs: list[str]
    outputs: list[str]
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    ratio: int = 1
    sampled: bool = True
    phases: list | None = None

    @classmethod
    def of(cls, name: str, inputs, outputs, A=None, B=None, C=None, D=None, ratio: int = 1,
           sampled: bool = True) -> "Block":
        """Missing matrices are empty (no state) or zero (no feedthrough)."""
        n = 0 if A is None else np.atleast_2d(A).shape[0]
        A = np.zeros((n, n)) if A is None else np.atleast_2d(np.asarray(A, float))
        B = np.zeros((n, len(inputs))) if B is None else np.asarray(B, float).reshape(n, len(inputs))
        C = np.zeros((len(outputs), n)) if C is None else np.asarray(C, float).reshape(len(outputs), n)
        D = np.zeros((len(outputs), len(inputs))) if D is None else np.asarray(D, float).reshape(len(outputs), len(inputs))
        return cls(name, list(inputs), list(outputs), A, B, C, D, ratio, sampled)

    @property
    def n(self) -> int:
        return self.A.shape[0]

    @property
    def cycle(self) -> int:
        """Its own steps per period: 1, or the length of ``phases``."""
        return len(self.phases) if self.phases else 1

    def at(self, j: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(A, B, C, D) of its ``j``-th own step: the same each step, or ``phases[j mod cycle]`` for a
        periodically time-varying block (an estimator that takes a fix every n-th of its steps)."""
        return self.phases[j % len(self.phases)] if self.phases else (self.A, self.B, self.C, self.D)


def delay_line(name: str, inputs: list[str], outputs: list[str], samples: int) -> Block:
    """out_k = in_{k - n} per channel (a deque of n + 1 read at its oldest end)."""
    m = len(inputs)
    if samples == 0:
        return Block.of(name, inputs, outputs, D=np.eye(m))
    n = samples * m
    A = np.zeros((n, n))
    A[m:, :-m] = np.eye(n - m)                       # registers [u_{k-1}; ...; u_{k-n}]
    B = np.zeros((n, m))
    B[:m] = np.eye(m)
    C = np.zeros((m, n))
    C[:, -m:] = np.eye(m)
    return Block.of(name, inputs, outputs, A, B, C)


def passthrough(name: str, pairs: dict[str, str]) -> Block:
    """A memoryless unit gain from each input to the output it names."""
    return Block.of(name, list(pairs), list(pairs.values()), D=np.eye(len(pairs)))


def lifted(A: np.ndarray, B: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """m steps of x <- A x + B u with u held: (A^m, sum_i A^i B)."""
    Am, Bm = np.eye(A.shape[0]), np.zeros_like(B)
    for _ in range(m):
        Bm = A @ Bm + B
        Am = A @ Am
    return Am, Bm


# --- the components' linear models -------------------------------------------------------------

def yaw_plant(comp, step: float, speed: float) -> Block:
    """Yaw dynamics at v (models.yaw_dynamics; v_y = l_r gamma for a transfer-function model)
    with the pose on the straight: psi' = gamma, y_cg' = v psi + v_y; R = CG - l_r psi, the
    antenna a lever arm f ahead of R: y_ant = y_R + f psi, its velocity + f gamma."""
    from components.models.yaw_dynamics import (TractorParameters, controllable_canonical, cornering_scale,
                                                state_space, with_cornering_scale, zoh_discretize)

    p = comp.p
    params = TractorParameters.of(p)
    if p["model"] == "transfer_function":
        Ay, By, Cy = controllable_canonical(p["tf_num"], p["tf_den"])
        vy = params.l_r * Cy
    else:
        if float(p["cornering_speed_slope"]):
            params = with_cornering_scale(params, cornering_scale(speed, p["cornering_speed_slope"],
                                                                  p["cornering_reference_speed"]))
        Ay, By, Cy = state_space(p["model"], params, speed)
        vy = np.eye(len(By))[0]
    n = len(By)
    A = np.zeros((n + 2, n + 2))
    A[:n, :n] = Ay
    A[n, :n] = Cy                                    # psi' = gamma
    A[n + 1, :n], A[n + 1, n] = vy, speed            # y' = v psi + v_y
    B = np.concatenate([By, [0.0, 0.0]]).reshape(-1, 1)
    e = np.eye(n + 2)
    gamma, psi, y, lr, f = np.concatenate([Cy, [0, 0]]), e[n], e[n + 1], params.l_r, float(p["antenna_forward"])
    lateral = np.concatenate([vy, [0, 0]])
    vel_rear = speed * psi + lateral - lr * gamma
    rows = {"yaw_rate": gamma, "lateral_velocity": lateral, "heading": psi, "y_cg": y, "y_rear": y - lr * psi,
            "vel_north_rear": vel_rear, "y_antenna": y - lr * psi + f * psi, "vel_north_antenna": vel_rear + f * gamma}
    Ad, Bd = zoh_discretize(A, B, step)
    return Block.of(comp.name, ["steer_angle"], list(rows), Ad, Bd, np.array(list(rows.values())), sampled=False)


def steering_hydraulics(comp, step: float, speed: float) -> Block:
    """The hydraulics' substep (components.steering_hydraulics) beyond its dead bands, lifted over
    the substeps of one step, with the command delay in whole steps:

        e = c - delta;  I <- I + k_i h e;  o <- o + alpha (s_o (k_p e + I) - o);  delta <- delta + r_s o

    s_o = 1 / (V_max - V_n - V_db) the valve's slope above its dead band, alpha = 1 - exp(-h / tau_valve),
    r_s = h Q_max / V_rad. The potentiometer reads delta."""
    p = comp.p
    m = max(1, int(round(step / p["internal_step"])))
    h = step / m
    s_o = 1.0 / (p["voltage_max"] - p["neutral_voltage"] - p["deadband"])
    alpha = 1.0 - math.exp(-h / p["valve_time_constant"])
    rs = h * p["max_flow"] / p["volume_per_rad"]
    kp, kih = p["kp"], p["ki"] * h
    A1 = np.array([[1.0, 0.0, -kih], [alpha * s_o, 1.0 - alpha, -alpha * s_o * kp], [0.0, 0.0, 1.0]])
    B1 = np.array([kih, alpha * s_o * kp, 0.0])
    A1[2] += rs * A1[1]                               # delta uses the new opening
    B1[2] += rs * B1[1]
    As, Bs = lifted(A1, B1.reshape(3, 1), m)
    d = int(round(float(p["command_delay"]) / step))
    line = delay_line("", ["c"], ["c"], d)
    # state [I, o, delta; registers]; the hydraulics act on the delayed command
    n = 3 + line.n
    A = np.zeros((n, n))
    A[:3, :3] = As
    A[:3, 3:] = Bs @ line.C
    A[3:, 3:] = line.A
    B = np.vstack([Bs @ line.D, line.B])
    C = np.zeros((2, n))
    C[:, 2] = 1.0
    return Block.of(comp.name, ["steer_angle_cmd"], ["steer_angle", "steer_angle_measured"], A, B, C, sampled=False)


def gps_sensor(comp, step: float, speed: float) -> Block:
    """The true antenna position and velocity ``latency`` / step samples late (noise, bias and
    dropouts left out)."""
    return delay_line(comp.name, ["y_true", "vel_north_true"], ["y", "vel_north"], int(round(comp.p["latency"] / step)))


def pose_ekf(comp, step: float, speed: float) -> Block:
    """The EKF (components.pose_ekf) on the straight with its steady-state gain: the covariance
    recursion run with the component's own predict and update until it settles, then

        y- = y + T v psi,  psi- = psi + T v delta_{k-1} / L,  (y, psi) = (y-, psi-) + K (z - y-)

    outputs the updated R, heading and CG = R + l_r psi."""
    from components.pose_ekf import PoseEKF

    ekf = PoseEKF(comp.name, {**comp.p, "x0": 0.0, "y0": 0.0, "psi0": 0.0})
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
    T, L, lr = step, comp.p["wheelbase"], comp.p["l_r"]
    M = np.array([[1.0, T * speed, 0.0], [0.0, 1.0, T * speed / L]])      # (y-, psi-) from (y, psi, delta_prev)
    U = np.array([[1.0 - ky, 0.0], [-kpsi, 1.0]])                          # update, innovation z - y-
    Kz = np.array([ky, kpsi])
    A = np.vstack([U @ M, [0.0, 0.0, 0.0]])
    B = np.array([[ky, 0.0], [kpsi, 0.0], [0.0, 1.0]])                      # inputs (gps_y, steer_angle)
    out = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, lr]])                    # y_rear, heading, y_cg
    C = out @ U @ M
    D = np.column_stack([out @ Kz, np.zeros(3)])
    return Block.of(comp.name, ["gps_y", "steer_angle"], ["y_rear", "heading", "y_cg"], A, B, C, D)


INS_INPUTS = ["gps_x", "gps_y", "yaw_rate", "roll", "accel_left"]
INS_OUTPUTS = ["y_rear", "heading", "y_cg", "lateral_velocity"]


def ins_ekf(comp, step: float, speed: float, fix_every: int = 1, fix_phase: int = 0) -> Block:
    """The GNSS/INS EKF (components.ins_ekf) on the straight, level ground, k at its initial value
    k0 (f_y = 0 leaves k unobservable and uncoupled), its gains periodic: a fix every ``fix_every``-th
    of its steps, at the steps j = ``fix_phase`` (mod fix_every). The covariance recursion is run with
    the component's own predict and update until the gains of a whole cycle settle; then, all eight
    states s = [x, y, psi, b_g, e_v, k, b_x, b_y] and the inputs of the previous step (the component
    predicts with them):

        s- = F s + dt (0, -k0 v f_y', omega', 0, ...)   F = I + the component's own Jacobian entries,
                                                         b_x, b_y decaying by exp(-dt / T)
        s  = s- + K_j (z - H s- + (0, h roll))         on a fix step (H: the component's antenna Jacobian;
                                                         the antenna's lean -h roll with terrain compensation)

    outputs the updated R (north), heading, CG = R + l_r psi and the crab -k0 v f_y of this step."""
    key = (repr(sorted(comp.p.items())), step, speed, fix_every, fix_phase)
    if key not in _INS_BLOCKS:
        _INS_BLOCKS[key] = _ins_ekf(comp, step, speed, fix_every, fix_phase)
    block = _INS_BLOCKS[key]
    return Block(comp.name, block.inputs, block.outputs, block.A, block.B, block.C, block.D, block.ratio,
                 block.sampled, block.phases)


_INS_BLOCKS: dict[tuple, Block] = {}        # the settled gains, per parameters and operating point (seconds each)


def _ins_ekf(comp, step: float, speed: float, fix_every: int, fix_phase: int) -> Block:
    from components.ins_ekf import INSEKF

    p = comp.p
    ekf = INSEKF(comp.name, {**p, "x0": 0.0, "y0": 0.0, "psi0": 0.0, "slip_compliance0": 0.0})
    ekf.initialize(0.0, step)
    n, R = 8, (p["fix_noise_std"] ** 2 + (p["antenna_height"] * p["attitude_noise_std"]) ** 2) * np.eye(2)
    gains, previous = [None] * fix_every, None
    for cycle in range(20000):
        for j in range(fix_every):
            ekf.predict(0.0, 0.0, 0.0, 0.0, speed, step)
            if j == fix_phase % fix_every:
                h, H = ekf.antenna(0.0, 0.0)
                gains[j] = np.linalg.solve(H @ ekf.P @ H.T + R, H @ ekf.P).T
                ekf.update(h, h, H, R)
        K = gains[fix_phase % fix_every]
        if previous is not None and np.allclose(previous, K, rtol=1e-10, atol=1e-14):
            break
        previous = K.copy()
    k0 = float(p["slip_compliance0"]) if p["crab_estimate"] else 0.0
    ekf.s = np.array([0.0, 0.0, 0.0, 0.0, 0.0, k0, 0.0, 0.0])
    _, entries, _ = ekf.jacobian(0.0, 0.0, 0.0, 0.0, speed, step)
    F = np.eye(n)
    for (i, j), f in entries.items():
        F[i, j] += f
    F[6, 6] = F[7, 7] = math.exp(-step / p["degraded_time_constant"])
    _, H = ekf.antenna(0.0, 0.0)
    lean = -float(p["antenna_height"]) if p["terrain_compensation"] else 0.0     # d(antenna north) / d roll
    # X = [s; omega'; f_y'], u = (gps_x, gps_y, yaw_rate, roll, accel_left)
    G = np.zeros((n, 2))
    G[1, 1], G[2, 0] = -step * k0 * speed, step                  # from f_y' and omega'
    M = np.hstack([F, G])                                        # s- from X
    lr = float(p["l_r"])
    out = np.zeros((4, n))
    out[0, 1], out[1, 2], out[2, 1], out[2, 2] = 1.0, 1.0, 1.0, lr
    crab = np.array([0.0, 0.0, 0.0, 0.0, -k0 * speed])           # lateral_velocity from this step's f_y
    hold = np.zeros((2, 5))
    hold[0, 2] = hold[1, 4] = 1.0                                # omega', f_y' <- this step's inputs
    phases = []
    for j in range(fix_every):
        if gains[j] is None:
            Ms, Ns = M, np.zeros((n, 5))
        else:
            K = gains[j]
            Ms = M - K @ H @ M
            Ns = np.zeros((n, 5))
            Ns[:, 0:2] = K
            Ns[:, 3] = K[:, 1] * -lean
        A = np.vstack([Ms, np.zeros((2, n + 2))])
        B = np.vstack([Ns, hold])
        C = out @ Ms
        D = out @ Ns
        D[3] += crab
        phases.append((A, B, C, D))
    block = Block.of(comp.name, INS_INPUTS, INS_OUTPUTS, *phases[0])
    block.phases = phases if fix_every > 1 else None
    return block


def imu_sensor(comp, step: float, speed: float) -> Block:
    """The IMU (components.imu_sensor) level and heading east without bias and noise: the gyro reads
    the heading rate (cos(phi) cos(theta) = 1 to first order), roll reads roll, and the left specific
    force is the north acceleration by a difference over one sample plus the gravity of the roll,
    f_y = (v_n - v_n') / dt + g phi (the east acceleration is 0 on the operating point)."""
    from components.models.terrain import GRAVITY

    return Block.of(comp.name, ["yaw_rate", "vel_north", "roll"], ["yaw_rate", "accel_left", "roll"],
                    A=[[0.0]], B=[[0.0, 1.0, 0.0]], C=[[0.0], [-1.0 / step], [0.0]],
                    D=[[1.0, 0.0, 0.0], [0.0, 1.0 / step, GRAVITY], [0.0, 0.0, 1.0]])


def yaw_rate_mpc(comp, step: float, speed: float) -> Block:
    """The MPC while no constraint is active (components.models.condensed_mpc): the first move
    du = K [x_k; u_{k-1}; gamma - gamma_d], K = -(H^-1 G)[0], with its model advanced by the measured
    wheel angle (x_k = A x_{k-1} + B delta_m) or by its last command (x_k = A x_{k-1} + B u_{k-1});
    state [x_{k-1}; u_{k-1}], inputs (steer_angle, yaw_rate, yaw_rate_ref)."""
    from components.models.condensed_mpc import CondensedTrackingMPC

    p = comp.p
    mpc = CondensedTrackingMPC(p["num"], p["den"], step, int(p["prediction_horizon"]), int(p["control_horizon"]),
                               float(p["Q"]), float(p["R"]), float(p["steer_limit"]), float(p["steer_rate_limit"]) * step)
    n = mpc.A.shape[0]
    K = -np.linalg.solve(mpc.H, mpc.G)[0]
    Kx, Ku, Ke = K[:n], K[n], K[n + 1]
    Am, Bm = mpc.A, mpc.B.reshape(-1)
    if p["model_input"] == "measured":
        Ax = np.hstack([Am, np.zeros((n, 1))])               # x_k from (x_{k-1}, u_{k-1})
        Bx = np.column_stack([Bm, np.zeros(n), np.zeros(n)])
    else:
        Ax = np.hstack([Am, Bm.reshape(-1, 1)])
        Bx = np.zeros((n, 3))
    urow = np.concatenate([Kx @ Ax[:, :n], [Kx @ Ax[:, n] + 1.0 + Ku]])
    ucol = Kx @ Bx + np.array([0.0, Ke, -Ke])
    A = np.vstack([Ax, urow])
    B = np.vstack([Bx, ucol])
    return Block.of(comp.name, ["steer_angle", "yaw_rate", "yaw_rate_ref"], ["steer_angle_cmd"], A, B, urow, ucol)


def yaw_rate_notch(comp, step: float, speed: float) -> Block:
    """The notch's difference equation (components.yaw_rate_notch), or a unit gain at frequency 0."""
    from scipy.signal import tf2ss

    from components.yaw_rate_notch import notch_coefficients

    p = comp.p
    if float(p["frequency"]) == 0.0:
        return passthrough(comp.name, {"yaw_rate": "yaw_rate_filtered"})
    b, a = notch_coefficients(float(p["frequency"]), float(p["notch_damping"]), float(p["pole_damping"]), step)
    A, B, C, D = tf2ss(b, a)
    return Block.of(comp.name, ["yaw_rate"], ["yaw_rate_filtered"], A, B, C, D)


def computation_delay(comp, step: float, speed: float) -> Block:
    return delay_line(comp.name, ["steer_angle_cmd"], ["steer_angle_cmd_out"], int(comp.p["samples"]))


def linear_models() -> dict[type, object]:
    """Component class -> f(component, step, speed) -> Block."""
    from components.computation_delay import ComputationDelay
    from components.gps_sensor import GPSSensor
    from components.gyro_sensor import GyroSensor
    from components.imu_sensor import IMUSensor
    from components.ins_ekf import INSEKF
    from components.pose_ekf import PoseEKF
    from components.safety_watchdog import SafetyWatchdog
    from components.steering_hydraulics import SteeringHydraulics
    from components.tractor_yaw_plant import TractorYawPlant
    from components.yaw_rate_mpc import YawRateMPC
    from components.yaw_rate_notch import YawRateNotch

    return {TractorYawPlant: yaw_plant, SteeringHydraulics: steering_hydraulics, GPSSensor: gps_sensor,
            PoseEKF: pose_ekf, YawRateMPC: yaw_rate_mpc, YawRateNotch: yaw_rate_notch,
            ComputationDelay: computation_delay, INSEKF: ins_ekf, IMUSensor: imu_sensor,
            GyroSensor: lambda c, step, v: passthrough(c.name, {"yaw_rate": "yaw_rate_measured"}),
            SafetyWatchdog: lambda c, step, v: passthrough(c.name, {"steer_angle_cmd": "steer_angle_cmd_out"})}


def off_the_lateral_loop() -> tuple[type, ...]:
    """Components whose outputs do not move the lateral channel at first order on a straight:
    the speed loop and its estimator (they set v), the implement and its side-shift (it reads the
    tractor, nothing reads it back), status and recording."""
    from components.bus_recorder import BusRecorder
    from components.speed_drivetrain import SpeedDrivetrain
    from components.speed_kf import SpeedKF
    from components.speed_pid import SpeedPID
    from components.steering_status import SteeringStatus
    from components.trailed_implement import TrailedImplement

    return SpeedPID, SpeedDrivetrain, SpeedKF, TrailedImplement, SteeringStatus, BusRecorder


# --- the network -----------------------------------------------------------------------------------

@dataclass
class Network:
    """Blocks on the orchestrator's schedule. ``sources[(block, input)] = (block, output)``;
    ``order``: the sampled blocks' evaluation order; ``period`` in base steps."""

    blocks: dict[str, Block]
    order: list[str]
    sources: dict[tuple[str, str], tuple[str, str]]
    base_step: float
    period: int = field(init=False)

    def __post_init__(self) -> None:
        self.period = math.lcm(*(b.ratio * b.cycle for b in self.blocks.values())) if self.blocks else 1
        self._layout: dict[str, tuple[slice, slice]] = {}
        i = 0
        for name, b in self.blocks.items():
            self._layout[name] = (slice(i, i + b.n), slice(i + b.n, i + b.n + len(b.outputs)))
            i += b.n + len(b.outputs)
        self.n = i                                    # block states, then each block's published outputs

    @property
    def step(self) -> float:
        return self.period * self.base_step

    def run(self, injected: dict[tuple[str, str], int], n_w: int, zeroed=(), instants: int | None = None):
        """The schedule over ``instants`` base steps (default one period) on matrices over
        [X; w]: returns (X+, captured, S, Y) with ``captured[(block, input)]`` the value the source of
        an injected input delivered when it was first read, S and Y each block's state and
        published outputs at the end."""
        N = self.n + n_w
        E = np.eye(N)
        S = {b: E[self._layout[b][0]] for b in self.blocks}
        Y = {b: E[self._layout[b][1]] for b in self.blocks}
        captured: dict[tuple[str, str], np.ndarray] = {}
        zero = np.zeros(N)
        zeroed = set(zeroed)

        def read(name: str, port: str) -> np.ndarray:
            src = self.sources.get((name, port))
            if src is None or src[0] not in self.blocks or src[1] not in self.blocks[src[0]].outputs:
                return zero
            return Y[src[0]][self.blocks[src[0]].outputs.index(src[1])]

        def gather(name: str) -> np.ndarray:
            rows = []
            for port in self.blocks[name].inputs:
                key = (name, port)
                if key in injected:
                    captured.setdefault(key, read(name, port))
                    rows.append(E[self.n + injected[key]])
                elif key in zeroed:
                    rows.append(zero)
                else:
                    rows.append(read(name, port))
            return np.array(rows).reshape(len(rows), N)

        continuous = [b for b in self.blocks.values() if not b.sampled]
        sampled = [self.blocks[name] for name in self.order if name in self.blocks]
        for k in range(self.period if instants is None else instants):
            for b in continuous:
                if k % b.ratio == 0:
                    Y[b.name] = b.at(k // b.ratio)[2] @ S[b.name]
            for b in sampled:
                if k % b.ratio == 0:
                    U = gather(b.name)
                    A, B, C, D = b.at(k // b.ratio)
                    Y[b.name] = C @ S[b.name] + D @ U
                    S[b.name] = A @ S[b.name] + B @ U
            for b in continuous:
                if k % b.ratio == 0:
                    A, B, _, _ = b.at(k // b.ratio)
                    S[b.name] = A @ S[b.name] + B @ gather(b.name)
        X = np.vstack([np.vstack([S[b], Y[b]]) for b in self.blocks]).reshape(self.n, N)
        return X, captured, S, Y

    def opened_at(self, breaks: list[tuple[str, str]], zeroed=()) -> "OpenLoop":
        """The network opened at the inputs ``breaks``: w injected there, z what their sources
        deliver; ``zeroed`` inputs held at the operating point."""
        X, captured, _, _ = self.run({key: i for i, key in enumerate(breaks)}, len(breaks), zeroed)
        Z = np.array([captured.get(key, np.zeros(self.n + len(breaks))) for key in breaks])
        return OpenLoop(X[:, :self.n], X[:, self.n:], Z[:, :self.n], Z[:, self.n:], self.step)


@dataclass
class OpenLoop:
    """z = G(q) w over one period: X+ = Phi X + Gamma w, z = H X + J w; closing it sets w = z."""

    Phi: np.ndarray
    Gamma: np.ndarray
    H: np.ndarray
    J: np.ndarray
    dt: float

    def response(self, w: np.ndarray) -> np.ndarray:
        """G(e^{j w dt}) for a SISO opening, at the angular frequencies ``w`` [rad/s]."""
        z = np.exp(1j * np.asarray(w, float) * self.dt)
        n = self.Phi.shape[0]
        out = np.empty(len(z), complex)
        for i in range(0, len(z), 256):
            zz = z[i:i + 256]
            M = zz[:, None, None] * np.eye(n) - self.Phi
            x = np.linalg.solve(M, np.broadcast_to(self.Gamma[:, :1], (len(zz), n, 1)))
            out[i:i + 256] = (self.H[:1] @ x)[:, 0, 0] + self.J[0, 0]
        return out

    def closed_loop_poles(self) -> np.ndarray:
        """Eigenvalues of the period map with the loop closed (w = z)."""
        m = self.J.shape[0]
        Acl = self.Phi + self.Gamma @ np.linalg.solve(np.eye(m) - self.J, self.H)
        return np.linalg.eigvals(Acl)

    def spectral_radius(self) -> float:
        poles = self.closed_loop_poles()
        return float(np.max(np.abs(poles))) if len(poles) else 0.0


# --- from a study --------------------------------------------------------------------------------

def _type_name(comp) -> str:
    return getattr(comp, "type_name", None) or type(comp).__name__


def check_tracker(comp, lin, step: float, op: OperatingPoint, steps: int = 4, eps: float = 1e-6) -> None:
    """The tracker's declared linearisation against its own step function: a fresh copy at the
    operating point (east-bound reference, the CG ``along_track_error`` behind it) with each input
    port moved by +-eps for ``steps`` steps; the central differences of its outputs must follow the
    declared system (inputs it leaves out: no effect). A law changed without its linearisation is
    refused here rather than analysed wrongly."""
    trim = {"x_ref": 10.0 + op.along_track_error, "y_ref": 0.0, "xdot_ref": op.speed, "ydot_ref": 0.0, "x": 10.0,
            "y": 0.0, "heading": 0.0, "yaw_rate_ref": 0.0, "lateral_velocity": 0.0}
    ports = [p for p in comp.declared("input") if p in trim]
    outputs = list(lin.output_labels)

    def run(port: str, delta: float) -> np.ndarray:
        fresh = type(comp)(comp.name, comp.p)
        fresh.initialize(0.0, step)
        rows = []
        for k in range(steps):
            fresh.u.update(trim)
            fresh.u[port] += delta
            fresh.step(k * step, step)
            rows.append([fresh.y[o] for o in outputs])
        return np.array(rows)

    A, B, C, D = (np.atleast_2d(np.asarray(m, float)) for m in (lin.A, lin.B, lin.C, lin.D))
    for port in ports:
        measured = (run(port, eps) - run(port, -eps)) / (2 * eps)
        u = np.zeros(len(lin.input_labels))
        if port in lin.input_labels:
            u[lin.input_labels.index(port)] = 1.0
        x = np.zeros(A.shape[0])
        for k in range(steps):
            declared = (C @ x if A.size else np.zeros(len(outputs))) + D @ u
            x = A @ x + B @ u if A.size else x
            bad = np.abs(measured[k] - declared) > 1e-4 * (1.0 + np.abs(declared))
            if bad.any():
                j = int(np.argmax(bad))
                raise NoLinearModel(f"component {comp.name!r} ({_type_name(comp)}): its declared linearisation "
                                    f"disagrees with its step function at {op.speed:g} m/s: d {outputs[j]} / d {port} "
                                    f"after {k + 1} step(s) is declared {declared[j]:.6g}, its step gives "
                                    f"{measured[k][j]:.6g} (finite differences); update lateral_linearisation")


def block_of(comp, step: float, ratio: int, op: OperatingPoint, models: dict, off_loop: tuple) -> Block | None:
    """The component's block, or None when it has none (network_of then checks that it is off the
    loop: off the lateral channel, reading nothing, or driving nothing the loop reads)."""
    from orchestrator.composite import CompositeComponent

    if hasattr(comp, "lateral_linearisation"):
        sys_ = comp.lateral_linearisation(op.speed, step, op.along_track_error)
        if "tracker" in comp.roles:
            check_tracker(comp, sys_, step, op)
        return Block.of(comp.name, list(sys_.input_labels), list(sys_.output_labels), sys_.A, sys_.B, sys_.C, sys_.D,
                        ratio, comp.sampled)
    for cls, model in models.items():
        if isinstance(comp, cls):
            block = model(comp, step, op.speed)
            block.ratio = ratio
            return block
    if isinstance(comp, CompositeComponent):
        return composite(comp, step, ratio, op)
    return None


def composite(comp, step: float, ratio: int, op: OperatingPoint) -> Block:
    """A subsystem as one block: its inner network run over its step (the inputs held), its
    outputs what its inner components hold after it (orchestrator.composite)."""
    sub = comp.subsystem.with_values({k: v for k, v in comp.p.items() if v is not None})
    inner = network_of(sub, op, purpose=f"the subsystem {comp.name!r}", resolver=comp.resolver)
    substeps = int(round(step / inner.base_step))
    if comp.sampled or substeps % inner.period:
        raise NoLinearModel(f"component {comp.name!r}: a subsystem whose step ({step} s) is not a whole number of "
                            f"its periods ({inner.step} s) or with only sampled components has no linear model here")
    ex = sub.exports
    inputs = list(ex.inputs)
    injected = {}
    for i, port in enumerate(inputs):
        for target in ex.input_targets(port):
            injected[tuple(target)] = i
    X, _, S, Y = inner.run(injected, len(inputs), instants=substeps)
    N = inner.n + len(inputs)
    # outputs read after the step: a continuous block's state through C (published at the next instant
    # in the host's time), a sampled block's last published value; both are rows of the new state
    outputs, rows = [], []
    for port in ex.outputs:
        name, out = ex.output_source(port)
        b = inner.blocks.get(name)
        if b is None or out not in b.outputs:
            continue
        j = b.outputs.index(out)
        select = np.zeros(inner.n)
        state, published = inner._layout[name]
        if b.sampled:
            select[published.start + j] = 1.0
        else:
            select[state] = b.C[j]
        outputs.append(port)
        rows.append(select)
    C = np.array(rows).reshape(len(rows), inner.n)
    return Block.of(comp.name, inputs, outputs, X[:, :inner.n], X[:, inner.n:N], C, ratio=ratio, sampled=False)


def network_of(study, op: OperatingPoint, purpose: str = "the margins", resolver=None) -> Network:
    """The study's lateral loop at the operating point (see the module docstring); its components'
    classes found by ``resolver`` (orchestrator.resolver; default: the default resolver)."""
    from orchestrator.build import build_system
    from orchestrator.resolver import resolve

    system = build_system(resolve(study, resolver))
    models, off_loop = linear_models(), off_the_lateral_loop()
    blocks: dict[str, Block] = {}
    for name, node in system.nodes.items():
        block = block_of(node.component, node.step, node.ratio, op, models, off_loop)
        if block is not None:
            blocks[name] = block
    sources = {(c.target, c.input): (c.source, c.output) for c in system.connections}
    order = [n.name for n in system.sampled_order]
    for name, block in blocks.items():
        comp = system.nodes[name].component
        source = sources.get((name, "gps_y"), (None,))[0]
        if models.get(type(comp)) is ins_ekf and source in system.nodes:
            # a new fix every n-th of its steps: at the receiver's instants when the receiver steps first
            node = system.nodes[name]
            every = max(1, system.nodes[source].ratio // node.ratio)
            first = source in order and order.index(source) < order.index(name)
            blocks[name] = ins_ekf(comp, node.step, op.speed, every, 0 if first else 1)
            blocks[name].ratio = node.ratio
    for (target, port), (source, output) in sources.items():
        if target in blocks and port in blocks[target].inputs and source not in blocks:
            comp = system.nodes[source].component
            if comp.declared("input") and not isinstance(comp, off_loop):
                raise NoLinearModel(f"{study.where}: {purpose}: component {source!r} ({_type_name(comp)}) drives "
                                    f"{target}.{port} in the guidance loop and has no linear model (a method "
                                    f"lateral_linearisation, or one in analysis.loop_models)")
    return Network(blocks, order, sources, study.study.base_step)
