"""The linear models the margins rest on, each checked against its component's own step function
(finite differences, or the component driven with small signals beside the linear block)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from agrobot.components.models.loop_blocks import Block, OperatingPoint
from agrobot.analysis.loop_models import network_of
from agrobot.components.kinematic_tracker import TRACKER_INPUTS, KinematicTracker
from agrobot.components.pure_pursuit import PurePursuit
from agrobot.components.stanley import Stanley
from agrobot.orchestrator.study import Study

ROOT = Path(__file__).resolve().parents[1]
FIGURE8 = ROOT / "studies" / "figure8.toml"


def run_block(block: Block, inputs: np.ndarray) -> np.ndarray:
    """Outputs of a sampled block (y = C x + D u, x <- A x + B u) or a continuous one (its output
    after each step) for a sequence of input vectors, from rest."""
    x = np.zeros(block.n)
    out = []
    for u in inputs:
        if block.sampled:
            out.append(block.C @ x + block.D @ u)
            x = block.A @ x + block.B @ u
        else:
            x = block.A @ x + block.B @ u
            out.append(block.C @ x)
    return np.array(out)


# --- trackers: the declared linearisation against finite differences of step() ---------------

TRACKERS = [(KinematicTracker, {"lookahead": 1.6}), (KinematicTracker, {}), (KinematicTracker, {"lookahead": 3.0, "k_c": 2.5}),
            (PurePursuit, {"lookahead_min": 2.0, "lookahead_time": 1.5}), (PurePursuit, {"lookahead_min": 4.0, "lookahead_time": 0.5}),
            (Stanley, {"k": 1.0, "v_soft": 1.0}), (Stanley, {"k": 2.5, "v_soft": 0.5, "l_f": 1.2})]


@pytest.mark.parametrize("cls, params", TRACKERS, ids=[f"{c.__name__}-{i}" for i, (c, _) in enumerate(TRACKERS)])
@pytest.mark.parametrize("speed, along", [(2.0, 0.0), (1.0, 0.0), (2.0, 0.25), (3.0, -0.1)])
def test_tracker_linearisation_is_the_jacobian_of_its_step(cls, params, speed, along):
    """Every input port (lateral and longitudinal) perturbed by +-1e-6 about a straight east-bound
    reference with the CG ``along`` behind it: the central difference of yaw_rate_desired equals
    the declared gain (0 for the ports the linearisation leaves out)."""
    tracker = cls("t", params)
    tracker.initialize(0.0, 0.05)
    lin = tracker.lateral_linearisation(speed, 0.05, along)
    trim = {"x_ref": 10.0 + along, "y_ref": 0.0, "xdot_ref": speed, "ydot_ref": 0.0, "x": 10.0, "y": 0.0,
            "heading": 0.0, "yaw_rate_ref": 0.0, "lateral_velocity": 0.0}

    def gamma_d(port, eps):
        tracker.u.update(trim)
        tracker.u[port] += eps
        tracker.step(0.0, 0.05)
        return tracker.y["yaw_rate_desired"]

    for port in (v.name for v in TRACKER_INPUTS):
        fd = (gamma_d(port, 1e-6) - gamma_d(port, -1e-6)) / 2e-6
        declared = lin.D[lin.output_labels.index("yaw_rate_desired"), lin.input_labels.index(port)] \
            if port in lin.input_labels else 0.0
        assert fd == pytest.approx(declared, abs=2e-6, rel=1e-5), port


def test_paper_law_and_look_ahead_gains_by_hand():
    """The kinematic tracker's heading gain is v/l_r for the paper's law and v/a with look-ahead
    (5 and 1.25 rad/s at 2 m/s, the numbers the figure-8 study's comment gives)."""
    paper = KinematicTracker("t", {}).lateral_linearisation(2.0, 0.05)
    ahead = KinematicTracker("t", {"lookahead": 1.6}).lateral_linearisation(2.0, 0.05)
    heading = paper.input_labels.index("heading")
    assert paper.D[0, heading] == pytest.approx(-5.0) and ahead.D[0, heading] == pytest.approx(-1.25)


def test_field_route_linearisation_against_its_projection(tmp_path):
    """On the route's first (straight, east-bound) leg the CG moved north by +-1 mm changes
    cross_track by as much and leaves the reference the tracker reads unmoved."""
    from agrobot.components.field_route import FieldRoute

    field = tmp_path / "plot.wkt"
    field.write_text("POLYGON ((0 0, 100 0, 100 60, 0 60, 0 0))")
    route = FieldRoute("field", {"path": str(field), "working_width": 3.0, "turn_radius": 4.0, "drawbar": 0.0, "max_swaths": 1,
                                 "settle": 2.0})
    route.u.update(x=0.0, y=0.0, implement_x=-1.0, implement_y=0.0)
    route.initialize(0.0, 0.05)
    lin = route.lateral_linearisation(2.0, 0.05)

    def outputs(dy):
        route.i_cg = route.i_impl = 0
        route.u.update(x=3.0, y=dy)
        route.step(0.0, 0.05)
        return dict(route.y)

    up, down = outputs(1e-3), outputs(-1e-3)
    for port in lin.output_labels:
        fd = (up[port] - down[port]) / 2e-3
        assert fd == pytest.approx(lin.D[lin.output_labels.index(port), 0], abs=1e-9), port
    assert route.operating_points()["work"] == {"speed": 2.0, "along_track_error": 0.0}
    assert route.operating_points()["turn"]["turn_radius"] == 4.0


# --- plant, steering, sensors, estimator, controller -----------------------------------------

def test_steering_block_is_the_hydraulics_step_without_its_dead_bands():
    """With the dead bands, the quantisation and the bounds out of the way the hydraulics are
    linear: the block (substeps lifted, 30 ms command delay) reproduces them to round-off."""
    from agrobot.components.steering_hydraulics import SteeringHydraulics

    params = {"deadband": 0.0, "potentiometer_resolution": 0.0, "quantization_guard": 0, "command_delay": 0.03}
    comp = SteeringHydraulics("steering", params)
    comp.initialize(0.0, 0.01)
    block = comp.linear_model(0.01, 2.0)
    cmd = 0.02 * np.sin(np.arange(300) * 0.01 * 3.0) + 0.01 * (np.arange(300) > 40)
    sim = []
    for c in cmd:
        comp.u["steer_angle_cmd"] = c
        comp.step(0.0, 0.01)
        sim.append(comp.y["steer_angle"])
    lin = run_block(block, cmd.reshape(-1, 1))[:, 0]
    np.testing.assert_allclose(lin, sim, atol=1e-12)


@pytest.mark.parametrize("model", ["rlf", "bicycle", "rlfr", "transfer_function"])
def test_yaw_plant_block_against_the_plant_on_a_straight(model):
    """Small wheel angles about a straight at 2 m/s: yaw rate, heading, CG and antenna north
    positions of the plant (exact ZOH yaw dynamics, midpoint pose) against the block."""
    from agrobot.components.tractor_yaw_plant import TractorYawPlant

    plant = TractorYawPlant("tractor", {"model": model, "antenna_forward": 0.5})
    plant.initialize(0.0, 0.01)
    block = plant.linear_model(0.01, 2.0)
    delta = 0.01 * np.sin(np.arange(600) * 0.01 * 2.0)
    sim = []
    for d in delta:
        plant.u.update(steer_angle=d, speed=2.0)
        plant.step(0.0, 0.01)
        sim.append([plant.y[k] for k in block.outputs])
    sim = np.array(sim)
    lin = run_block(block, delta.reshape(-1, 1))
    for i, name in enumerate(block.outputs):
        if name.startswith("vel_") or name.startswith("y") or name == "heading":
            scale = np.abs(sim[:, i]).max()
            np.testing.assert_allclose(lin[:, i], sim[:, i], atol=2e-3 * scale, err_msg=name)
        else:
            np.testing.assert_allclose(lin[:, i], sim[:, i], atol=1e-9 * np.abs(sim[:, i]).max() + 1e-15, err_msg=name)


def test_ekf_block_against_the_filter_after_it_settles():
    """The EKF run on a straight until its covariance settles, then fed small random GPS north
    offsets and wheel angles: its R, heading and CG match the steady-state block."""
    from agrobot.components.pose_ekf import PoseEKF

    ekf = PoseEKF("ekf", {"x0": 0.0, "y0": 0.0, "psi0": 0.0})
    ekf.initialize(0.0, 0.05)
    v = 2.0
    for k in range(4000):                                 # settle on the straight
        ekf.u.update(gps_x=v * 0.05 * k, gps_y=0.0, fix_valid=1.0, speed=v, steer_angle=0.0)
        ekf.step(k * 0.05, 0.05)
    block = ekf.linear_model(0.05, v)
    rng = np.random.default_rng(1)
    z, d = 1e-3 * rng.standard_normal(200), 1e-3 * rng.standard_normal(200)
    sim = []
    for i in range(200):
        k = 4000 + i
        ekf.u.update(gps_x=v * 0.05 * k, gps_y=z[i], steer_angle=d[i])
        ekf.step(k * 0.05, 0.05)
        sim.append([ekf.y["y_rear"], ekf.y["heading"], ekf.y["y_cg"]])
    lin = run_block(block, np.column_stack([z, d]))
    np.testing.assert_allclose(lin, np.array(sim), atol=1e-8)


@pytest.mark.parametrize("model_input", ["measured", "command"])
def test_mpc_block_equals_the_qp_mpc_while_no_constraint_is_active(model_input):
    """Small signals (no bound active): the block gives the QP controller's commands."""
    from agrobot.components.yaw_rate_mpc import YawRateMPC

    mpc = YawRateMPC("mpc", {"model_input": model_input})
    mpc.initialize(0.0, 0.05)
    block = mpc.linear_model(0.05, 2.0)
    rng = np.random.default_rng(0)
    u = 1e-3 * rng.standard_normal((200, 3))            # (steer_angle, yaw_rate, yaw_rate_ref)
    qp = []
    for k in range(200):
        mpc.u.update(steer_angle=u[k, 0], yaw_rate=u[k, 1], yaw_rate_ref=u[k, 2])
        mpc.step(k * 0.05, 0.05)
        qp.append(mpc.y["steer_angle_cmd"])
    u[0, 0] = 0.0                                         # the QP controller ignores the first measured angle
    np.testing.assert_allclose(run_block(block, u)[:, 0], qp, rtol=1e-8, atol=1e-12)


def test_notch_and_gps_latency_blocks_against_their_components():
    from agrobot.components.gps_sensor import GPSSensor
    from agrobot.components.yaw_rate_notch import YawRateNotch

    notch = YawRateNotch("n", {"frequency": 10.0, "notch_damping": 0.05, "pole_damping": 0.5})
    notch.initialize(0.0, 0.05)
    x = np.sin(np.arange(100) * 0.05 * 7.0)
    x[0] = 0.0                                            # the notch starts at rest on its first value
    sim = []
    for value in x:
        notch.u["yaw_rate"] = value
        notch.step(0.0, 0.05)
        sim.append(notch.y["yaw_rate_filtered"])
    np.testing.assert_allclose(run_block(notch.linear_model(0.05, 2.0), x.reshape(-1, 1))[:, 0], sim, atol=1e-12)

    gps = GPSSensor("gps", {"position_noise_std": 0.0, "velocity_noise_std": 0.0, "latency": 0.15})
    gps.initialize(0.0, 0.05)
    sim = []
    for value in x:
        gps.u.update(y_true=value, vel_north_true=-value)
        gps.step(0.0, 0.05)
        sim.append([gps.y["y"], gps.y["vel_north"]])
    np.testing.assert_allclose(run_block(gps.linear_model(0.05, 2.0), np.column_stack([x, -x])), sim, atol=1e-15)


# --- the network ----------------------------------------------------------------------------

def test_the_opened_loop_closed_again_is_the_network():
    """The figure-8's network opened at the steering command and closed again (w = z) evolves as
    the network never opened, from a random state, for 40 periods."""
    net = network_of(Study.load(FIGURE8), OperatingPoint(2.0))
    brk = [("steering", "steer_angle_cmd")]
    loop = net.opened_at(brk)
    rng = np.random.default_rng(3)
    X0 = rng.standard_normal(net.n) * 1e-3
    X, Xp = X0.copy(), X0.copy()
    for _ in range(40):
        Z = loop.H @ Xp                                  # w = z: closed
        Xp = loop.Phi @ Xp + loop.Gamma @ np.linalg.solve(np.eye(1) - loop.J, Z)
        full, _, _, _ = net.run({}, 0)                    # one period of the closed network on numbers
        X = full @ X
    np.testing.assert_allclose(Xp, X, atol=1e-12)


# --- the GNSS/INS estimator and the IMU: their blocks against finite differences of step() ----------

def run_phased(block: Block, inputs: np.ndarray) -> np.ndarray:
    """Outputs of a sampled block whose matrices change with its own step (Block.at), from rest."""
    x = np.zeros(block.n)
    out = []
    for j, u in enumerate(inputs):
        A, B, C, D = block.at(j)
        out.append(C @ x + D @ u)
        x = A @ x + B @ u
    return np.array(out)


def ins_differences(ekf, inputs, start: int, block, steps: int = 25, eps: float = 1e-6, dt: float = 0.01) -> dict:
    """{port: (measured, declared)} for each lateral input of the settled INS EKF ``ekf`` (at step
    ``start`` of ``inputs(k)``) stepped by +-eps for ``steps`` steps: the central differences of its
    outputs, and the block's response to the unit step."""
    import copy

    from agrobot.components.ins_ekf import INS_INPUTS, INS_OUTPUTS

    def run(port, delta):
        fresh = copy.deepcopy(ekf)
        rows = []
        for i in range(steps):
            u = inputs(start + i)
            u[port] += delta
            fresh.u.update(u)
            fresh.step((start + i) * dt, dt)
            rows.append([fresh.y[o] for o in INS_OUTPUTS])
        return np.array(rows)

    out = {}
    for port in INS_INPUTS:
        u = np.zeros((steps, len(INS_INPUTS)))
        u[:, INS_INPUTS.index(port)] = 1.0
        out[port] = ((run(port, eps) - run(port, -eps)) / (2 * eps), run_phased(block, u))
    return out


@pytest.mark.parametrize("params, speed", [({"antenna_height": 2.5}, 2.0),
                                           pytest.param({"antenna_height": 2.5}, 1.0, marks=pytest.mark.slow),
                                           pytest.param({"antenna_height": 1.0, "antenna_forward": 0.8,
                                                         "slip_compliance0": 0.006, "l_r": 0.6}, 2.0,
                                                        marks=pytest.mark.slow),
                                           pytest.param({"antenna_height": 2.5, "terrain_compensation": 0,
                                                         "crab_estimate": 0}, 2.0, marks=pytest.mark.slow)])
def test_ins_ekf_block_is_the_jacobian_of_its_step(params, speed):
    """The INS EKF settled on a straight (a fix every 5th step at the true antenna, wheel speed v, level),
    then each lateral input stepped by +-eps for 25 steps (a receiver's
    value held between its fixes): the central differences of its outputs
    follow the block with the periodic gains (the fix steps first), to 1e-3 relative (the filter
    after 200 s is that close to its settled gains)."""
    from agrobot.components.ins_ekf import INSEKF

    dt, every = 0.01, 5
    ekf = INSEKF("ekf", {"x0": 0.0, "y0": 0.0, "psi0": 0.0, **params})
    ekf.initialize(0.0, dt)
    f = float(params.get("antenna_forward", 0.0))

    def inputs(k):
        x = speed * dt * (k // every * every)              # the fix moves at the receiver's steps only
        return {"gps_x": x + f, "gps_y": 0.0, "fix_valid": 1.0, "fix_quality": 4.0, "yaw_rate": 0.0, "roll": 0.0,
                "pitch": 0.0, "accel_left": 0.0, "speed": speed}

    start = 20000                                          # 200 s: the gyro bias and scale settled
    for k in range(start):
        ekf.u.update(inputs(k))
        ekf.step(k * dt, dt)
    block = ekf.linear_model(dt, speed, every, 0)
    for port, (measured, declared) in ins_differences(ekf, inputs, start, block).items():
        assert np.allclose(measured, declared, rtol=1e-3, atol=1e-6), (port, measured[:6], declared[:6])
        assert np.abs(declared).max() > 1e-3 or port in ("gps_x", "roll", "accel_left", "pitch")   # pitch: east only, level


def impulse_differences(component, trim: dict, port: str, outputs, dt: float, eps: float = 1e-6,
                        steps: int = 3) -> np.ndarray:
    """(steps, outputs): central differences of a component's outputs over ``steps`` steps after an
    impulse of +-eps on input ``port`` at the first, each from a copy at the trim ``trim``."""
    import copy

    def run(delta):
        fresh = copy.deepcopy(component)
        rows = []
        for k in range(steps):
            fresh.u.update(trim)
            fresh.u[port] += delta if k == 0 else 0.0
            fresh.step((k + 1) * dt, dt)
            rows.append([fresh.y[o] for o in outputs])
        return np.array(rows)
    return (run(eps) - run(-eps)) / (2 * eps)


def test_imu_block_is_the_jacobian_of_its_step():
    """The IMU without bias or noise, level, heading east at 2 m/s: central differences of its gyro,
    left specific force and roll over 3 steps for each input against the block."""

    from agrobot.components.imu_sensor import IMUSensor

    zero = {k: 0.0 for k in ("gyro_noise_psd", "gyro_bias_std", "gyro_bias_instability", "accel_noise_psd",
                             "accel_bias_std", "attitude_bias_std", "attitude_noise_std")}
    imu = IMUSensor("imu", zero)
    imu.rng = np.random.default_rng(0)
    imu.initialize(0.0, 0.01)
    trim = {"roll": 0.0, "pitch": 0.0, "heading": 0.0, "yaw_rate": 0.0, "vel_east": 2.0, "vel_north": 0.0}
    imu.u.update(trim)
    imu.step(0.0, 0.01)
    block = imu.linear_model(0.01, 2.0)
    for port in trim:
        measured = impulse_differences(imu, trim, port, block.outputs, 0.01)
        u = np.zeros((3, len(block.inputs)))
        if port in block.inputs:
            u[0, block.inputs.index(port)] = 1.0
        assert np.allclose(measured, run_block(block, u), rtol=1e-5, atol=1e-5), port
