"""Yaw plant against independently derived equations: symbolic Laplace-domain solution of the
equations of motion, the textbook bicycle transfer function, the steady-state (understeer) gain,
and a second integrator for the LPV plant."""
from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from agrobot.components.models.yaw_dynamics import TractorParameters, state_space
from agrobot.components.tractor_yaw_plant import TractorYawPlant, UnstableModelWarning

P = TractorParameters()
SPEEDS = [0.5, 1.0, 2.0, 3.0]


def tf_from_state_space(model, v):
    """Numerator/denominator of C (sI - A)^-1 B, monic denominator, via python-control."""
    import control

    A, B, C = state_space(model, P, v)
    g = control.ss2tf(A, B.reshape(-1, 1), C.reshape(1, -1), 0.0)
    num, den = np.array(g.num[0][0], float), np.array(g.den[0][0], float)
    return num / den[0], den / den[0]


def tf_symbolic(model, v):
    """Gamma/Delta solved from the equations of motion in the Laplace domain (sympy)."""
    s = sp.symbols("s")
    m, I, lf, lr, Cf, Cr, sf, sr = (sp.nsimplify(x) for x in
                                     (P.m, P.I, P.l_f, P.l_r, P.C_f, P.C_r, P.sigma_f, P.sigma_r))
    vx = sp.nsimplify(v)
    Vy, G, Af, Ar, D = sp.symbols("Vy G Af Ar D")
    eqs = [sp.Eq(m * s * Vy, -m * vx * G - Cf * Af - Cr * Ar), sp.Eq(I * s * G, -lf * Cf * Af + lr * Cr * Ar)]
    front_static = sp.Eq(Af, (Vy + lf * G) / vx - D)
    front_relax = sp.Eq(sf * s * Af, Vy + lf * G - vx * (D + Af))
    rear_static = sp.Eq(Ar, (Vy - lr * G) / vx)
    rear_relax = sp.Eq(sr * s * Ar, Vy - lr * G - vx * Ar)
    eqs += {"bicycle": [front_static, rear_static], "rlf": [front_relax, rear_static],
            "rlfr": [front_relax, rear_relax]}[model]
    sol = sp.solve(eqs, [Vy, G, Af, Ar], dict=True)[0]
    num, den = sp.fraction(sp.cancel(sp.together(sol[G] / D)))
    num_c = [float(c) for c in sp.Poly(num, s).all_coeffs()]
    den_c = [float(c) for c in sp.Poly(den, s).all_coeffs()]
    return np.array(num_c) / den_c[0], np.array(den_c) / den_c[0]


@pytest.mark.parametrize("model", ["bicycle", "rlf", "rlfr"])
@pytest.mark.parametrize("v", SPEEDS)
def test_state_space_matches_symbolic_equations_of_motion(model, v):
    num_ss, den_ss = tf_from_state_space(model, v)
    num_sym, den_sym = tf_symbolic(model, v)
    assert len(den_ss) == len(den_sym) == {"bicycle": 3, "rlf": 4, "rlfr": 5}[model]
    np.testing.assert_allclose(den_ss, den_sym, rtol=1e-9)
    np.testing.assert_allclose(np.trim_zeros(num_ss, "f") if abs(num_ss[0]) > 1e-9 * abs(num_ss).max()
                               else num_ss[np.abs(num_ss) > 1e-9 * abs(num_ss).max()], num_sym, rtol=1e-8)


@pytest.mark.parametrize("v", SPEEDS)
def test_bicycle_matches_textbook_coefficients(v):
    m, I, lf, lr, Cf, Cr = P.m, P.I, P.l_f, P.l_r, P.C_f, P.C_r
    L = lf + lr
    num = [Cf * lf / I, Cf * Cr * L / (m * I * v)]
    den = [1.0, (Cf + Cr) / (m * v) + (Cf * lf**2 + Cr * lr**2) / (I * v),
           Cf * Cr * L**2 / (m * I * v**2) + (Cr * lr - Cf * lf) / I]
    n, d = tf_from_state_space("bicycle", v)
    np.testing.assert_allclose(n[-2:], num, rtol=1e-10)
    np.testing.assert_allclose(d, den, rtol=1e-10)


def test_rlf_is_stable_and_rlfr_has_the_weak_growing_mode_with_table_values():
    for v in np.linspace(0.5, 3.0, 11):
        assert np.linalg.eigvals(state_space("rlf", P, v)[0]).real.max() < -1.0
        eig = np.linalg.eigvals(state_space("rlfr", P, v)[0])
        worst = eig[np.argmax(eig.real)]
        assert 0 < worst.real < 0.05 and abs(abs(worst.imag) / (2 * math.pi) - 1.65) < 0.02


def make_plant(model="rlf", **params):
    plant = TractorYawPlant("tractor", {"model": model, **params})
    plant.initialize(0.0, 0.01)
    return plant


def understeer_gain(v):
    """gamma/delta = v / (L + K v^2), K = m (l_r C_r - l_f C_f) / (L C_f C_r)."""
    L = P.l_f + P.l_r
    K = P.m * (P.l_r * P.C_r - P.l_f * P.C_f) / (L * P.C_f * P.C_r)
    return v / (L + K * v**2)


@pytest.mark.parametrize("model", ["bicycle", "rlf", "rlfr"])
@pytest.mark.parametrize("v", SPEEDS)
def test_dc_gain_is_the_understeer_formula(model, v):
    A, B, C = state_space(model, P, v)
    assert float(-C @ np.linalg.solve(A, B)) == pytest.approx(understeer_gain(v), rel=1e-10)


@pytest.mark.parametrize("model", ["bicycle", "rlf"])
def test_simulated_steady_state_yaw_rate_is_the_understeer_formula(model):
    v, delta = 1.5, math.radians(3.0)
    plant = make_plant(model)
    plant.u.update(speed=v, steer_angle=delta)
    for k in range(1500):
        plant.step(k * 0.01, 0.01)
    assert plant.y["yaw_rate"] == pytest.approx(delta * understeer_gain(v), rel=1e-6)


def test_plant_matches_a_second_integrator_with_varying_speed():
    """ZOH-exact LPV steps vs solve_ivp (RK45, tight tolerances) on the same piecewise-constant inputs."""
    dt, n = 0.01, 800
    t_grid = np.arange(n) * dt
    speed = 1.0 + 0.8 * np.sin(0.5 * t_grid)
    delta = 0.1 * np.sin(2 * np.pi * 0.7 * t_grid) + 0.05 * np.sign(np.sin(2 * np.pi * 0.2 * t_grid))
    plant = make_plant("rlf", speed_cache_resolution=1e-9)
    out = []
    for k in range(n):
        plant.u.update(speed=speed[k], steer_angle=delta[k])
        plant.step(t_grid[k], dt)
        out.append((plant.y["yaw_rate"], plant.y["x_cg"], plant.y["y_cg"], plant.y["heading"]))
    out = np.array(out)

    z = np.zeros(6)  # v_y, gamma, alpha_f, x, y, psi
    ref = []
    for k in range(n):
        A, B, _ = state_space("rlf", P, speed[k])

        def f(_t, s, A=A, B=B, v=speed[k], d=delta[k]):
            dz = A @ s[:3] + B * d
            c, si = math.cos(s[5]), math.sin(s[5])
            return np.concatenate([dz, [v * c - s[0] * si, v * si + s[0] * c, s[1]]])

        z = solve_ivp(f, (0, dt), z, rtol=1e-10, atol=1e-12).y[:, -1]
        ref.append((z[1], z[3], z[4], z[5]))
    ref = np.array(ref)
    np.testing.assert_allclose(out[:, 0], ref[:, 0], atol=1e-9)
    # pose by the midpoint rule: second order in dt
    np.testing.assert_allclose(out[:, 1:], ref[:, 1:], atol=2e-4)


def test_rear_axle_point_and_its_velocity_are_consistent():
    plant = make_plant("rlf", psi0=0.3)
    plant.u.update(speed=2.0, steer_angle=0.2)
    rows = []
    for k in range(400):
        plant.step(k * 0.01, 0.01)
        y = plant.y
        rows.append((y["x_rear"], y["y_rear"], y["vel_east_rear"], y["vel_north_rear"], y["heading"], y["x_cg"], y["y_cg"]))
    r = np.array(rows)
    np.testing.assert_allclose(np.hypot(r[:, 5] - r[:, 0], r[:, 6] - r[:, 1]), P.l_r, atol=1e-12)
    vel_num = np.gradient(r[:, :2], 0.01, axis=0)[5:-5]
    np.testing.assert_allclose(vel_num, r[5:-5, 2:4], atol=2e-3)


def test_default_plant_stays_bounded_for_ten_minutes():
    """10 min of random steering at each speed: yaw rate stays bounded by the DC gain bound."""
    rng = np.random.default_rng(0)
    for v in (0.5, 1.0, 2.0, 3.0):
        plant = make_plant()
        peak = 0.0
        for k in range(60000):
            if k % 50 == 0:
                d = rng.uniform(-0.3, 0.3)
            plant.u.update(speed=v, steer_angle=d)
            plant.step(k * 0.01, 0.01)
            peak = max(peak, abs(plant.y["yaw_rate"]))
        assert np.isfinite(peak) and peak < 3.0 * 0.3 * v / 1.4


def _free_response(**parameters) -> tuple[float, float]:
    """Peak |yaw rate| in 10-20 s and in the last 10 s of ten minutes after a small steering pulse."""
    plant = TractorYawPlant("plant", {"model": "rlfr", **parameters})
    plant.initialize(0.0, 0.01)
    plant.u.update(speed=2.0, steer_angle=0.01)
    plant.step(0.0, 0.01)
    plant.u["steer_angle"] = 0.0
    early = late = 0.0
    for k in range(1, 60000):
        plant.step(k * 0.01, 0.01)
        if 1000 <= k < 2000:
            early = max(early, abs(plant.y["yaw_rate"]))
        if k >= 59000:
            late = max(late, abs(plant.y["yaw_rate"]))
    return early, late


def test_rlfr_with_the_table_values_grows_over_ten_minutes_and_says_so():
    with pytest.warns(UnstableModelWarning, match=r"pole \+0\.0\d+ \+10\.\d+j 1/s"):
        early, late = _free_response(parameter_set="table")
    assert late > 100 * early


def test_rlfr_by_default_is_the_stable_set_with_the_identified_poles():
    """model = "rlfr" alone: the parameter set fitted to G_RLFR, whose poles at 2 m/s are the
    identified model's (-0.62 +- 9.95j, -5.13 +- 14.44j) and which decays at every speed."""
    import warnings

    from agrobot.components.models.paper_models import G_RLFR

    with warnings.catch_warnings():
        warnings.simplefilter("error", UnstableModelWarning)
        early, late = _free_response()
        params = TractorParameters.of({"model": "rlfr"})
    assert late < 1e-6 * early
    poles = np.sort_complex(np.linalg.eigvals(state_space("rlfr", params, 2.0)[0]))
    np.testing.assert_allclose(poles, np.sort_complex(np.roots(G_RLFR.den)), rtol=1e-4)
    for v in (0.3, 1.0, 2.5, 4.0):
        assert np.linalg.eigvals(state_space("rlfr", params, v)[0]).real.max() < 0
    # a value the study sets wins over the set
    assert TractorParameters.of({"model": "rlfr", "C_f": 8500.0}).C_f == 8500.0


def test_transfer_function_model_has_the_paper_g2nd_response():
    """Default TF model = 291/(s^2+10.9s+242): DC gain 291/242 and the step response's overshoot."""
    plant = make_plant("transfer_function")
    plant.u.update(speed=2.0, steer_angle=0.1)
    ys = []
    for k in range(300):
        plant.step(k * 0.01, 0.01)
        ys.append(plant.y["yaw_rate"])
    zeta = 10.9 / (2 * math.sqrt(242))
    overshoot = math.exp(-zeta * math.pi / math.sqrt(1 - zeta**2))
    assert ys[-1] == pytest.approx(0.1 * 291 / 242, rel=1e-6)
    assert max(ys) == pytest.approx(0.1 * 291 / 242 * (1 + overshoot), rel=2e-3)


def test_at_rest_the_tractor_does_not_turn():
    plant = make_plant()
    plant.u.update(speed=0.0, steer_angle=0.5)
    for k in range(200):
        plant.step(k * 0.01, 0.01)
    assert plant.y["heading"] == 0.0 and plant.y["x_cg"] == 0.0


# --- diagnosis-catalogue extensions -----------------------------------------------

def test_steer_angle_offset_turns_at_zero_reading_with_the_understeer_gain():
    v, offset = 2.0, math.radians(2.0)
    plant = make_plant("rlf", steer_angle_offset=offset)
    plant.u.update(speed=v, steer_angle=0.0)
    for k in range(1500):
        plant.step(k * 0.01, 0.01)
    assert plant.y["yaw_rate"] == pytest.approx(offset * understeer_gain(v), rel=1e-6)


def test_speed_dependent_cornering_equals_the_plant_with_scaled_stiffness():
    """Two routes: k = 0.25 at 3 m/s (scale 1.25) against C_f, C_r multiplied by 1.25 by hand."""
    a = make_plant("rlf", cornering_speed_slope=0.25, cornering_reference_speed=2.0)
    b = make_plant("rlf", C_f=P.C_f * 1.25, C_r=P.C_r * 1.25)
    for p in (a, b):
        p.u.update(speed=3.0, steer_angle=math.radians(5))
        for k in range(300):
            p.step(k * 0.01, 0.01)
    assert a.y["yaw_rate"] == pytest.approx(b.y["yaw_rate"], rel=1e-12)
    assert abs(a.y["yaw_rate"] - make_plant("rlf").discretized(3.0, 0.01)[0][1, 1]) > 0    # not the baseline


def test_side_slope_pushes_downhill_with_g_sin_phi():
    """Fall line to the tractor's left, at rest in yaw: dv_y/dt(0) = g sin(phi) (the equations'
    only lateral input), and the lateral force vanishes when the fall line is straight ahead."""
    phi, dt = math.radians(5), 1e-6
    left = make_plant("rlf", slope_angle=phi, slope_downhill_heading=math.pi / 2)
    left.u.update(speed=2.0, steer_angle=0.0)
    left.initialize(0.0, dt)
    left.step(0.0, dt)
    assert left.y["lateral_velocity"] / dt == pytest.approx(9.81 * math.sin(phi), rel=1e-3)
    ahead = make_plant("rlf", slope_angle=phi, slope_downhill_heading=0.0)
    ahead.u.update(speed=2.0, steer_angle=0.0)
    for k in range(100):
        ahead.step(k * 0.01, 0.01)
    assert ahead.y["lateral_velocity"] == 0.0 and ahead.y["yaw_rate"] == 0.0


def test_antenna_lever_arm_position_and_velocity_are_consistent():
    plant = make_plant("rlf", antenna_forward=0.8, antenna_left=-0.3, psi0=0.4)
    plant.u.update(speed=2.0, steer_angle=math.radians(8))
    rows = []
    for k in range(400):
        plant.step(k * 0.01, 0.01)
        y = plant.y
        rows.append((y["x_antenna"], y["y_antenna"], y["vel_east_antenna"], y["vel_north_antenna"],
                     y["x_rear"], y["y_rear"], y["heading"]))
    a = np.array(rows)
    c, s = np.cos(a[:, 6]), np.sin(a[:, 6])
    np.testing.assert_allclose(a[:, 0], a[:, 4] + 0.8 * c + 0.3 * s, atol=1e-12)
    np.testing.assert_allclose(a[:, 1], a[:, 5] + 0.8 * s - 0.3 * c, atol=1e-12)
    ve = np.gradient(a[:, 0], 0.01)[5:-5]
    vn = np.gradient(a[:, 1], 0.01)[5:-5]
    np.testing.assert_allclose(ve, a[5:-5, 2], atol=2e-3)
    np.testing.assert_allclose(vn, a[5:-5, 3], atol=2e-3)
