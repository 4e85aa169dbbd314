"""The guidance loop's linear model on a side slope (the components' linear_model with a Ground): the
operating point against the closed form of the tyres holding the line, and the yaw plant's, the
IMU's and the INS's blocks against short nonlinear runs of the components themselves on the slope
(deviations from the trimmed run; central differences of the settled filter). Each check also
shows that the level-ground block misses what the slope adds."""
from __future__ import annotations

import math

import numpy as np
import pytest

from agrobot.components.ins_ekf import INS_OUTPUTS
from agrobot.components.models.terrain import GRAVITY, attitude, ground_of, lever_offset
from agrobot.components.models.yaw_dynamics import TractorParameters
from agrobot.components.tractor_yaw_plant import TractorYawPlant
from tests.test_margins_models import impulse_differences, ins_differences

DEG = math.pi / 180.0
SLOPE = 10 * DEG
DT = 0.01


def _plant(downhill: float, **extra) -> TractorYawPlant:
    plant = TractorYawPlant("tractor", {"model": "rlf", "slope_angle": SLOPE, "slope_downhill_heading": downhill,
                                        "antenna_height": 2.5, "antenna_forward": 0.5, **extra})
    plant.initialize(0.0, DT)
    return plant


def _run_block(block, inputs: np.ndarray) -> np.ndarray:
    """Outputs of a block after each step from rest (continuous: published after the step)."""
    x = np.zeros(block.n)
    out = []
    for j, u in enumerate(inputs):
        A, B, C, D = block.at(j)
        if block.sampled:
            out.append(C @ x + D @ u)
            x = A @ x + B @ u
        else:
            x = A @ x + B @ u
            out.append(C @ x)
    return np.array(out)


@pytest.mark.parametrize("downhill", [-90 * DEG, -60 * DEG])
def test_the_operating_point_on_a_slope_is_the_tyres_holding_the_line(downhill):
    """Heading east on a plane of slope phi falling towards psi_d: the pull across the heading is
    g sin(phi) sin(psi_d) and turns with the heading as -g sin(phi) cos(psi_d); the tyres hold it,
    the rear's share l_f / L at the slip angle F_r / C_r, so R crabs at -k f_y v, k = m l_f / (L C_r),
    f_y = g sin(roll) cos(pitch) the IMU's reading (the rear axle's steady slip, by hand)."""
    plant = _plant(downhill)
    g = plant.linear_ground(2.0)
    p = TractorParameters.of(plant.p)
    assert g.pull == pytest.approx(GRAVITY * math.sin(SLOPE) * math.sin(downhill), rel=1e-9)
    assert g.pull_per_heading == pytest.approx(-GRAVITY * math.sin(SLOPE) * math.cos(downhill), abs=1e-6)
    roll, pitch = attitude(*ground_of(SLOPE, downhill).gradient(0.0, 0.0), 0.0)
    assert g.specific_force == pytest.approx(GRAVITY * math.sin(roll) * math.cos(pitch), rel=1e-12)
    k = p.m * p.l_f / ((p.l_f + p.l_r) * p.C_r)
    assert g.crab == pytest.approx(-k * -g.pull * 2.0, rel=1e-6)          # the tyres push -pull uphill
    assert g.slip_compliance(2.0) * g.specific_force == pytest.approx(-g.crab / 2.0, rel=1e-12)
    assert TractorYawPlant("flat", {"model": "rlf"}).linear_ground(2.0) is None


def trimmed(plant_of, speed: float, seconds: float = 12.0):
    """(wheel angle, initial heading) holding the tractor on a line east on the slope, found on the
    nonlinear plant itself: a secant on the heading's drift over the run's last half, then the start
    heading turned so that the CG's north velocity ends nil (the body crabbed off the line)."""
    def run(delta, psi0=0.0):
        plant = plant_of()
        plant.psi = psi0
        psi, y = [], []
        for _ in range(int(seconds / DT)):
            plant.u.update(steer_angle=delta, speed=speed)
            plant.step(0.0, DT)
            psi.append(plant.psi)
            y.append(plant.y_pos)
        return psi[-1] - psi[len(psi) // 2], (y[-1] - y[-101]) / (100 * DT)
    a, b = 0.0, 0.02
    fa, fb = run(a)[0], run(b)[0]
    for _ in range(8):
        a, b, fa = b, b - fb * (b - a) / (fb - fa), fb
        fb = run(b)[0]
        if abs(fb) < 1e-10:
            break
    psi0 = 0.0
    for _ in range(3):
        psi0 -= run(b, psi0)[1] / speed
    return b, psi0


def test_yaw_plant_block_on_a_slope_against_the_plant():
    """An oblique 10 deg slope (fall line 60 deg off the heading, so the pull turns with the heading):
    the plant trimmed on it, then small wheel angles about the trim; the deviations of yaw rate,
    heading, CG, antenna (east and north), roll and pitch from the trimmed run follow the block; the
    level block (no pull turning with the heading, no tilt) does not."""
    speed, downhill = 2.0, -60 * DEG
    trim, psi0 = trimmed(lambda: _plant(downhill), speed)
    block = _plant(downhill).linear_model(DT, speed)
    level = TractorYawPlant("tractor", {"model": "rlf", "antenna_height": 2.5, "antenna_forward": 0.5}).linear_model(
        DT, speed)
    settle = int(12.0 / DT)
    delta = 0.005 * np.sin(np.arange(600) * DT * 2.0)

    def run(extra):
        plant = _plant(downhill)
        plant.psi = psi0
        rows = []
        for k in range(settle + len(delta)):
            plant.u.update(steer_angle=trim + (extra[k - settle] if k >= settle else 0.0), speed=speed)
            plant.step(0.0, DT)
            if k >= settle:
                rows.append([plant.y[o] for o in block.outputs])
        return np.array(rows)

    sim = run(delta) - run(np.zeros_like(delta))
    lin = _run_block(block, delta.reshape(-1, 1))
    # east (x_antenna), the lateral channel's share is within the crab angle's neglect (0.5 deg): the
    # crab's share of the along-track speed and a lever of mm per radian, below the second-order v psi^2 / 2
    names = [o for o in block.outputs if o != "x_antenna"]
    heading = lin[:, block.outputs.index("heading")]
    for name in names:
        i = block.outputs.index(name)
        scale = np.abs(sim[:, i]).max()
        assert scale > 1e-9, name
        assert np.abs(lin[:, i] - sim[:, i]).max() < 0.02 * scale, name
    assert np.abs(heading).max() > 1e-3
    j, i = level.outputs.index("y_cg"), block.outputs.index("y_cg")
    flat = _run_block(level, delta.reshape(-1, 1))[:, j]
    assert np.abs(flat - sim[:, i]).max() > 0.05 * np.abs(sim[:, i]).max()     # 7 %: the pull turning with psi


def test_imu_block_on_a_slope_is_the_jacobian_of_its_step():
    """The IMU without bias or noise on an oblique 10 deg slope (roll and pitch both), heading east
    at 2 m/s: central differences of its gyro, left specific force, roll and pitch against the block
    with the ground; the level block misses the tilt's share."""
    from agrobot.components.imu_sensor import IMUSensor

    g = _plant(-60 * DEG).linear_ground(2.0)
    zero = {k: 0.0 for k in ("gyro_noise_psd", "gyro_bias_std", "gyro_bias_instability", "accel_noise_psd",
                             "accel_bias_std", "attitude_bias_std", "attitude_noise_std")}
    imu = IMUSensor("imu", zero)
    imu.rng = np.random.default_rng(0)
    imu.initialize(0.0, DT)
    trim = {"roll": g.roll, "pitch": g.pitch, "heading": 0.0, "yaw_rate": 0.0, "vel_east": 2.0, "vel_north": 0.0}
    imu.u.update(trim)
    imu.step(0.0, DT)
    block, level = imu.linear_model(DT, 2.0, g), imu.linear_model(DT, 2.0)
    differs = False
    for port in ("roll", "pitch", "yaw_rate", "vel_north"):
        measured = impulse_differences(imu, trim, port, block.outputs, DT)
        u = np.zeros((3, len(block.inputs)))
        u[0, block.inputs.index(port)] = 1.0
        assert np.allclose(measured, _run_block(block, u), rtol=1e-5, atol=1e-5), port
        differs |= not np.allclose(measured, _run_block(level, u), rtol=1e-3, atol=1e-3)
    assert differs


@pytest.mark.slow
def test_ins_ekf_block_on_a_slope_is_the_jacobian_of_its_step(downhill=-60 * DEG):
    """The INS EKF on a 10 deg slope whose fall line is 60 deg off the heading (roll and pitch both),
    settled on the true motion there (R east at v, crabbing
    sideways at the plant's steady crab, the antenna leaning with roll and pitch, the IMU reading the
    slope's f_y, k learnt): each input stepped by +-eps for 25 steps, the central differences of its
    outputs follow the block with the ground (the learnt k coupled through f_y, the tilted antenna)
    to 1 % (after 200 s the variance of k is still settling; after 800 s they agree to 1e-3, too long
    a run for the suite); a fix moves the crab, which it cannot on level ground."""
    from agrobot.components.ins_ekf import INSEKF

    speed, every = 2.0, 5
    g = _plant(downhill).linear_ground(speed)
    k = g.slip_compliance(speed)
    params = {"antenna_height": 2.5, "antenna_forward": 0.5, "slip_compliance0": k}
    ekf = INSEKF("ekf", {"x0": 0.0, "y0": 0.0, "psi0": 0.0, **params})
    ekf.initialize(0.0, DT)
    ox, oy = lever_offset(g.roll, g.pitch, 0.0, 0.5, 0.0, 2.5)

    def inputs(i):
        t = DT * (i // every * every)                      # the fix moves at the receiver's steps only
        return {"gps_x": speed * t + ox, "gps_y": g.crab * t + oy, "fix_valid": 1.0, "fix_quality": 4.0,
                "yaw_rate": 0.0, "roll": g.roll, "pitch": g.pitch, "accel_left": g.specific_force, "speed": speed}

    start = 20000                                          # 200 s: the gyro bias, scale and k settled
    for i in range(start):
        ekf.u.update(inputs(i))
        ekf.step(i * DT, DT)
    assert ekf.s[5] == pytest.approx(k, rel=1e-3)          # the filter keeps the crab it was given
    block = ekf.linear_model(DT, speed, every, 0, g)
    differences = ins_differences(ekf, inputs, start, block)
    for port, (measured, declared) in differences.items():
        assert np.allclose(measured, declared, rtol=1e-2, atol=2e-6), (port, measured[:6], declared[:6])
    # on level ground a fix moves no crab (k uncoupled, f_y = 0); here it does, through the learnt k
    crab = differences["gps_y"][0][:, INS_OUTPUTS.index("lateral_velocity")]
    assert np.abs(crab).max() > 1e-5                       # 1.7e-5 (m/s) / m here, 0 on level ground
