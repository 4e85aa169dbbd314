"""The linear models of the guidance loop's components on a straight (analysis.loop_models), each
derived from the component's own step equations and parameters, without the nonlinearities a small
signal beyond the dead bands does not see (dead bands, quantisation, saturations).

A component names its model next to itself: ``LINEAR_MODEL = "agrobot.analysis.component_models:yaw_plant"``
in its class (any ``module:function`` taking (component, step, speed) and returning a loop_blocks.Block),
or a method ``lateral_linearisation`` (analysis.loop_models.block_of); ``OFF_THE_LATERAL_LOOP = True``
for one that moves nothing of the lateral channel.
"""
from __future__ import annotations

import math

import numpy as np

from .loop_blocks import LEVEL, Block, Ground, delay_line, lifted, passthrough


def _yaw_dynamics(comp, speed: float):
    """(A, B, C, v_y row, parameters) of the plant's yaw dynamics at v (models.yaw_dynamics; v_y =
    l_r gamma for a transfer-function model), as its step uses them."""
    from agrobot.components.models.yaw_dynamics import (TractorParameters, controllable_canonical, cornering_scale,
                                                state_space, with_cornering_scale)

    p = comp.p
    params = TractorParameters.of(p)
    if p["model"] == "transfer_function":
        Ay, By, Cy = controllable_canonical(p["tf_num"], p["tf_den"])
        return Ay, By, Cy, params.l_r * Cy, params
    if float(p["cornering_speed_slope"]):
        params = with_cornering_scale(params, cornering_scale(speed, p["cornering_speed_slope"],
                                                              p["cornering_reference_speed"]))
    Ay, By, Cy = state_space(p["model"], params, speed)
    return Ay, By, Cy, np.eye(len(By))[0], params


def _on_the_plane(p, heading: float) -> dict[str, float]:
    """Roll, pitch, the pull across the heading and the antenna's lever (east, north) of a plant
    heading ``heading`` on its plane (models.terrain, as the plant's step computes them)."""
    from agrobot.components.models.terrain import attitude, ground_of, lever_offset, slope_pull

    gx, gy = ground_of(p["slope_angle"], p["slope_downhill_heading"]).gradient(0.0, 0.0)
    pe, pn = slope_pull(gx, gy)
    roll, pitch = attitude(gx, gy, heading)
    ox, oy = lever_offset(roll, pitch, heading, p["antenna_forward"], p["antenna_left"], p["antenna_height"])
    return {"roll": roll, "pitch": pitch, "pull": -pe * math.sin(heading) + pn * math.cos(heading),
            "lever_east": ox, "lever_north": oy}


def _per_heading(p, eps: float = 1e-6) -> dict[str, float]:
    """d/d psi at psi = 0 of _on_the_plane's values (central differences)."""
    up, down = _on_the_plane(p, eps), _on_the_plane(p, -eps)
    return {k: (up[k] - down[k]) / (2 * eps) for k in up}


def plant_ground(comp, speed: float) -> Ground | None:
    """The ground under the yaw plant ``comp`` driving straight east at ``speed`` on its plane
    (``slope_angle``, ``slope_downhill_heading``), None on level ground: roll, pitch and the pull across
    the heading a_lat and their change with psi (models.terrain), the left specific force the IMU reads
    there, f_y = g sin(roll) cos(pitch) (models.terrain.body_of with no acceleration), and the rear
    axle's crab: the yaw dynamics' steady state holding the line against the pull, gamma = 0,

        A z + B delta + E a_lat = 0,   C z = 0        (n + 1 equations in z, delta)

    whose v_y (state 0) is R's sideways velocity (gamma = 0: every point of the body moves alike).
    A height grid (``terrain_file``) is not linearised here: None (the caller says so)."""
    from agrobot.components.models.terrain import GRAVITY
    from agrobot.components.models.yaw_dynamics import lateral_disturbance_column

    p = comp.p
    if not float(p.get("slope_angle", 0.0) or 0.0) or p.get("terrain_file") or p.get("model") == "transfer_function":
        return None
    here, slope = _on_the_plane(p, 0.0), _per_heading(p)
    A, B, C, _, _ = _yaw_dynamics(comp, speed)
    n = len(B)
    M = np.zeros((n + 1, n + 1))
    M[:n, :n], M[:n, n], M[n, :n] = A, B, C
    rhs = np.concatenate([-lateral_disturbance_column(n) * here["pull"], [0.0]])
    z = np.linalg.solve(M, rhs)
    return Ground(roll=here["roll"], pitch=here["pitch"], roll_per_heading=slope["roll"],
                  pitch_per_heading=slope["pitch"], pull=here["pull"], pull_per_heading=slope["pull"],
                  specific_force=GRAVITY * math.sin(here["roll"]) * math.cos(here["pitch"]), crab=float(z[0]))


def yaw_plant(comp, step: float, speed: float) -> Block:
    """Yaw dynamics at v (models.yaw_dynamics; v_y = l_r gamma for a transfer-function model)
    with the pose on the straight: psi' = gamma, y_cg' = v psi + v_y; R = CG - l_r psi, the
    antenna a lever arm f ahead of R: y_ant = y_R + f psi, its velocity + f gamma.

    On a plane (``slope_angle``) the deviations are about the steady state that holds the line
    against the pull (plant_ground); the pull across the heading turns with it, dv_y/dt gains
    (d a_lat / d psi) psi, roll and pitch follow the heading (d roll / d psi psi, ...), and the antenna's
    lever, leaning with them, moves by (d lever / d psi) psi east and north; the line runs along the
    velocity, the body turned by the crab angle psi_0 = -v_y0 / v off it, so a change of the crab
    moves R along the line, x' = (v_y0 / v) v_y (outputs x_antenna, roll and pitch, the lateral
    channel's share of them, only on a plane). The crab angle (0.5 deg on 10 deg) is left out elsewhere."""
    from agrobot.components.models.yaw_dynamics import lateral_disturbance_column, zoh_discretize

    p = comp.p
    Ay, By, Cy, vy, params = _yaw_dynamics(comp, speed)
    ground = plant_ground(comp, speed)
    tilted = ground is not None
    slope = _per_heading(p) if tilted else {"lever_north": float(p["antenna_forward"])}
    n = len(By)
    m = n + 3 if tilted else n + 2                   # on a plane also x: the crab's share of the along-track motion
    A = np.zeros((m, m))
    A[:n, :n] = Ay
    A[n, :n] = Cy                                    # psi' = gamma
    A[n + 1, :n], A[n + 1, n] = vy, speed            # y' = v psi + v_y
    if tilted:
        A[:n, n] += lateral_disturbance_column(n) * slope["pull"]      # the pull turning with psi
        A[n + 2, :n] = vy * ground.crab / speed      # x' = v cos psi - v_y sin psi, sin psi_0 = -v_y0 / v
    B = np.concatenate([By, np.zeros(m - n)]).reshape(-1, 1)
    e = np.eye(m)
    gamma, psi, y, lr = np.concatenate([Cy, np.zeros(m - n)]), e[n], e[n + 1], params.l_r
    f = slope["lever_north"]
    turning = _on_the_plane(p, 0.0)["lever_east"] if tilted else f     # the plant's antenna velocity: the lever
    lateral = np.concatenate([vy, np.zeros(m - n)])                   # turned by gamma, its lean held
    vel_rear = speed * psi + lateral - lr * gamma
    rows = {"yaw_rate": gamma, "lateral_velocity": lateral, "heading": psi, "y_cg": y, "y_rear": y - lr * psi,
            "vel_north_rear": vel_rear, "y_antenna": y - lr * psi + f * psi,
            "vel_north_antenna": vel_rear + turning * gamma}
    if tilted:                                       # the lateral channel's share of these: nil on level ground
        rows |= {"x_antenna": e[n + 2] + slope["lever_east"] * psi, "roll": slope["roll"] * psi,
                 "pitch": slope["pitch"] * psi}
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


def gps_sensor(comp, step: float, speed: float, ground: Ground = LEVEL) -> Block:
    """The true antenna position and velocity ``latency`` / step samples late (noise, bias and
    dropouts left out); on a slope the east position too (its lateral-channel share: the leaning
    antenna turning with the heading)."""
    ports = ["y", "vel_north"] + ([] if ground.level else ["x"])
    return delay_line(comp.name, [f"{p}_true" for p in ports], ports, int(round(comp.p["latency"] / step)))


def pose_ekf(comp, step: float, speed: float) -> Block:
    """The EKF (components.pose_ekf) on the straight with its steady-state gain: the covariance
    recursion run with the component's own predict and update until it settles, then

        y- = y + T v psi,  psi- = psi + T v delta_{k-1} / L,  (y, psi) = (y-, psi-) + K (z - y-)

    outputs the updated R, heading and CG = R + l_r psi."""
    from agrobot.components.pose_ekf import PoseEKF

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


INS_INPUTS = ["gps_x", "gps_y", "yaw_rate", "roll", "accel_left", "pitch"]
INS_OUTPUTS = ["y_rear", "heading", "y_cg", "lateral_velocity"]


def ins_ekf(comp, step: float, speed: float, fix_every: int = 1, fix_phase: int = 0, ground: Ground = LEVEL) -> Block:
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
    key = (repr(sorted(comp.p.items())), step, speed, fix_every, fix_phase, ground)
    if key not in _INS_BLOCKS:
        _INS_BLOCKS[key] = _ins_ekf(comp, step, speed, fix_every, fix_phase, ground)
    block = _INS_BLOCKS[key]
    return Block(comp.name, block.inputs, block.outputs, block.A, block.B, block.C, block.D, block.ratio,
                 block.sampled, block.phases)


_INS_BLOCKS: dict[tuple, Block] = {}        # the settled gains, per parameters and operating point (seconds each)


def _lean(p, roll: float, pitch: float, eps: float = 1e-7) -> np.ndarray:
    """d (antenna east, north) / d (roll, pitch) at psi = 0 as the filter models the antenna
    (nil without terrain compensation): a 2 x 2 matrix, central differences of models.terrain."""
    from agrobot.components.models.terrain import lever_offset

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
    from agrobot.components.ins_ekf import INSEKF

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


def imu_sensor(comp, step: float, speed: float, ground: Ground = LEVEL) -> Block:
    """The IMU (components.imu_sensor) heading east without bias and noise, on the ground's roll phi
    and pitch theta: the gyro reads the heading rate about its up axis, cos(phi) cos(theta) gamma; roll
    and pitch read roll and pitch; the left specific force (models.terrain.body_of, the east
    acceleration 0 on the operating point) is the north acceleration by a difference over one sample
    and the gravity of the attitude,

        f_y = cos(phi) (v_n - v_n') / dt + g (cos(phi) cos(theta) d phi - sin(phi) sin(theta) d theta)

    (level ground: f_y = (v_n - v_n') / dt + g phi)."""
    from agrobot.components.models.terrain import GRAVITY

    cr, sr = math.cos(ground.roll), math.sin(ground.roll)
    cp, sp = math.cos(ground.pitch), math.sin(ground.pitch)
    return Block.of(comp.name, ["yaw_rate", "vel_north", "roll", "pitch"], ["yaw_rate", "accel_left", "roll", "pitch"],
                    A=[[0.0]], B=[[0.0, 1.0, 0.0, 0.0]], C=[[0.0], [-cr / step], [0.0], [0.0]],
                    D=[[cr * cp, 0.0, 0.0, 0.0], [0.0, cr / step, GRAVITY * cr * cp, -GRAVITY * sr * sp],
                       [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


def yaw_rate_mpc(comp, step: float, speed: float) -> Block:
    """The MPC while no constraint is active (components.models.condensed_mpc): the first move
    du = K [x_k; u_{k-1}; gamma - gamma_d], K = -(H^-1 G)[0], with its model advanced by the measured
    wheel angle (x_k = A x_{k-1} + B delta_m) or by its last command (x_k = A x_{k-1} + B u_{k-1});
    state [x_{k-1}; u_{k-1}], inputs (steer_angle, yaw_rate, yaw_rate_ref)."""
    from agrobot.components.models.condensed_mpc import CondensedTrackingMPC

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

    from agrobot.components.yaw_rate_notch import notch_coefficients

    p = comp.p
    if float(p["frequency"]) == 0.0:
        return passthrough(comp.name, {"yaw_rate": "yaw_rate_filtered"})
    b, a = notch_coefficients(float(p["frequency"]), float(p["notch_damping"]), float(p["pole_damping"]), step)
    A, B, C, D = tf2ss(b, a)
    return Block.of(comp.name, ["yaw_rate"], ["yaw_rate_filtered"], A, B, C, D)


def computation_delay(comp, step: float, speed: float) -> Block:
    return delay_line(comp.name, ["steer_angle_cmd"], ["steer_angle_cmd_out"], int(comp.p["samples"]))


def gyro_sensor(comp, step: float, speed: float) -> Block:
    """The gyro without bias and noise: it reads the yaw rate."""
    return passthrough(comp.name, {"yaw_rate": "yaw_rate_measured"})


def safety_watchdog(comp, step: float, speed: float) -> Block:
    """The watchdog while nothing trips it: the command passes."""
    return passthrough(comp.name, {"steer_angle_cmd": "steer_angle_cmd_out"})


def linear_model_of(comp):
    """f(component, step, speed) -> Block that the component's class names in ``LINEAR_MODEL``
    (``"module:function"``), None when it names none."""
    from agrobot.orchestrator.errors import InputError
    from agrobot.orchestrator.registry import import_study_module

    name = getattr(type(comp), "LINEAR_MODEL", None)
    if not name:
        return None
    module, _, function = name.partition(":")
    try:
        return getattr(import_study_module(module), function)
    except (ImportError, AttributeError) as exc:
        raise InputError(f"component {comp.name!r} ({type(comp).__module__}.{type(comp).__qualname__}): "
                         f"LINEAR_MODEL = {name!r} cannot be loaded ({exc}); expected 'module:function'") from None


def off_the_lateral_loop(comp) -> bool:
    """The component's class says ``OFF_THE_LATERAL_LOOP = True``: its outputs do not move the
    lateral channel at first order on a straight (the speed loop and its estimator set v; an
    implement reads the tractor and nothing reads it back; status and recording)."""
    return bool(getattr(type(comp), "OFF_THE_LATERAL_LOOP", False))
