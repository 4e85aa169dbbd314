"""Guidance on real ground: terrain (roll, pitch, the antenna's height, the slope's pull), the IMU,
the GNSS/INS estimator through outages and quality drops, the crab feed-forward, and the figures
vendors and ISO 12188-2 quote (line acquisition, pass-to-pass at an interval), on real fields
(copies in tests/data). Expected values come from closed forms derived here, or a second method."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from agrobot.components.gps_sensor import GPSSensor, gga_qualities
from agrobot.components.imu_sensor import IMUSensor
from agrobot.components.ins_ekf import INSEKF
from agrobot.components.models import terrain
from agrobot.components.tractor_yaw_plant import TractorYawPlant
from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.study import Study
from tests.commands import cli as _cli

ROOT = Path(__file__).resolve().parents[1]
REAL = ROOT / "tests" / "data"
PARCEL = REAL / "fields2cover_data" / "test.json"                 # Fields2Cover's 3.6 ha test parcel
PARTFIELDS = REAL / "isoxml_dev4ag_timelogs" / "PARTFIELDS_TASKDATA.XML"
NMEA_RTK = REAL / "nmea_gpsd_testlogs" / "nmea-rtk.log"            # a Trimble log: DGPS, a pause, RTK fixed
DEG = math.pi / 180.0
SIDE_SLOPE = ("tractor.slope_angle=10 deg", "tractor.slope_downhill_heading=-90 deg")   # swaths run east-west
SECTION = ("--set", "field.max_swaths=1", "--set", "field.headland_work=0")     # a bad input is found after planning


def _run(study: str, *overrides: str):
    return run_study(Study.load(ROOT / "studies" / study, list(overrides)), None, plots=False)


# --- the ground's geometry -------------------------------------------------------------------------------
@pytest.mark.parametrize("gx,gy,heading", [(0.0, -0.176, 0.0), (0.12, -0.05, 1.1), (-0.3, 0.2, -2.5)])
def test_attitude_on_the_ground_is_the_rotation_of_its_tangent_and_normal(gx, gy, heading):
    """A body on ground of gradient (gx, gy): forward along the tangent above its heading, up along
    the normal (-gx, -gy, 1). Its rotation matrix from those axes equals terrain.rotation of the
    roll and pitch terrain.attitude gives, and scipy's ZYX Euler angles of it are (heading, -pitch, roll)."""
    from scipy.spatial.transform import Rotation

    c, s = math.cos(heading), math.sin(heading)
    forward = np.array([c, s, gx * c + gy * s])
    up = np.array([-gx, -gy, 1.0])
    forward, up = forward / np.linalg.norm(forward), up / np.linalg.norm(up)
    axes = np.column_stack([forward, np.cross(up, forward), up])
    roll, pitch = terrain.attitude(gx, gy, heading)
    assert np.allclose(terrain.rotation(roll, pitch, heading), axes, atol=1e-12)
    yaw_, minus_pitch, roll_ = Rotation.from_matrix(axes).as_euler("ZYX")
    assert (yaw_, -minus_pitch, roll_) == pytest.approx((math.remainder(heading, 2 * math.pi), pitch, roll), abs=1e-12)
    lever = np.array([0.3, -0.2, 2.7])
    assert terrain.lever_offset(roll, pitch, heading, *lever) == pytest.approx(tuple((axes @ lever)[:2]), abs=1e-12)
    assert terrain.body_of(roll, pitch, heading, 0.4, -1.0, 9.81) == pytest.approx(tuple(axes.T @ (0.4, -1.0, 9.81)),
                                                                                     abs=1e-12)


def test_the_antenna_hangs_h_sin_roll_downhill_and_the_pull_is_g_sin_phi():
    """Heading east on a 10 deg slope falling south: roll 10 deg (left side up), pitch 0, the
    antenna h sin(10 deg) south of R, the pull g sin(10 deg) south; on flat ground it stands over R."""
    h = 3.0
    plant = TractorYawPlant("tractor", {"slope_angle": 10 * DEG, "slope_downhill_heading": -90 * DEG,
                                        "antenna_height": h})
    plant.initialize(0.0, 0.01)
    y = plant.y
    assert (y["roll"], y["pitch"]) == pytest.approx((10 * DEG, 0.0), abs=1e-12)
    assert y["x_antenna"] - y["x_rear"] == pytest.approx(0.0, abs=1e-12)
    assert y["y_antenna"] - y["y_rear"] == pytest.approx(-h * math.sin(10 * DEG), abs=1e-12)
    assert (y["slope_pull_east"], y["slope_pull_north"]) == pytest.approx((0.0, -9.81 * math.sin(10 * DEG)), abs=1e-12)
    flat = TractorYawPlant("tractor", {"antenna_height": h})
    flat.initialize(0.0, 0.01)
    assert (flat.y["x_antenna"], flat.y["y_antenna"]) == (flat.y["x_rear"], flat.y["y_rear"])


def test_a_height_grid_of_a_plane_drives_the_tractor_as_the_plane_does(tmp_path):
    """The plane written as a height grid (CSV x, y, z): the same gradient everywhere inside, and
    a tractor turning on it follows the same path, roll and pitch as on the analytic plane."""
    plane = terrain.Plane(8 * DEG, 30 * DEG)
    xs, ys = np.arange(-20.0, 41.0, 2.0), np.arange(-30.0, 31.0, 2.5)
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    rows = [(float(x), float(y), plane.height(x, y)) for x, y in zip(gx.ravel(), gy.ravel())]
    path = tmp_path / "heights.csv"
    path.write_text("x,y,z\n" + "".join(f"{x:.17g},{y:.17g},{z:.17g}\n" for x, y, z in rows))
    grid = terrain.HeightGrid.read_csv(path)
    for x, y in ((0.0, 0.0), (13.3, -7.1), (-19.0, 28.0)):
        assert grid.gradient(x, y) == pytest.approx(plane.gradient(x, y), abs=1e-9)
    runs = []
    for params in ({"slope_angle": 8 * DEG, "slope_downhill_heading": 30 * DEG}, {"terrain_file": str(path)}):
        plant = TractorYawPlant("tractor", {**params, "antenna_height": 2.5})
        plant.u.update(steer_angle=0.2, speed=2.0)
        plant.initialize(0.0, 0.01)
        for i in range(800):
            plant.step(i * 0.01, 0.01)
        runs.append([plant.y[k] for k in ("x_cg", "y_cg", "heading", "roll", "pitch", "x_antenna", "y_antenna")])
    assert runs[1] == pytest.approx(runs[0], abs=1e-8)


def test_a_bad_height_grid_is_named(tmp_path):
    bad = tmp_path / "heights.csv"
    bad.write_text("x,y,height\n0,0,1\n")
    with pytest.raises(ValueError, match="heights.csv: column.*'z'.*missing"):
        terrain.HeightGrid.read_csv(bad)
    res = _cli("run", str(ROOT / "studies" / "field_coverage.toml"), "--out", str(tmp_path / "out"), *SECTION,
               "--set", f"tractor.terrain_file={bad}")
    assert res.returncode == 2 and "terrain_file" in res.stderr and "heights.csv" in res.stderr
    assert "Traceback" not in res.stderr and not (tmp_path / "out").exists()


# --- the IMU and the crab ---------------------------------------------------------------------------------
def test_the_imu_measures_gravity_through_its_tilt_and_the_yaw_rate_through_its_up_axis():
    """Without noise or bias, at rest on a slope: the specific force is g times the body's view of
    up, (sin theta, cos theta sin phi, cos theta cos phi); turning at dpsi/dt the gyro reads
    cos(phi) cos(theta) dpsi/dt. With noise: the gyro's spread is sqrt(PSD / T_s)."""
    quiet = {k: 0.0 for k in ("gyro_noise_psd", "gyro_bias_std", "gyro_bias_instability", "accel_noise_psd",
                              "accel_bias_std", "attitude_bias_std", "attitude_noise_std")}
    imu = IMUSensor("imu", quiet)
    roll, pitch = 9 * DEG, -4 * DEG
    imu.u.update(roll=roll, pitch=pitch, heading=0.7, yaw_rate=0.3, vel_east=0.0, vel_north=0.0)
    imu.initialize(0.0, 0.01)
    imu.step(0.0, 0.01)
    g = 9.81
    assert (imu.y["accel_forward"], imu.y["accel_left"], imu.y["accel_up"]) == pytest.approx(
        (g * math.sin(pitch), g * math.cos(pitch) * math.sin(roll), g * math.cos(pitch) * math.cos(roll)), abs=1e-12)
    assert imu.y["yaw_rate"] == pytest.approx(math.cos(roll) * math.cos(pitch) * 0.3, abs=1e-15)
    noisy = IMUSensor("imu", {**quiet, "gyro_noise_psd": 1e-6}, rng=np.random.default_rng(3))
    noisy.initialize(0.0, 0.01)
    reads = []
    for i in range(20000):
        noisy.step(i * 0.01, 0.01)
        reads.append(noisy.y["yaw_rate"])
    assert np.std(reads) == pytest.approx(math.sqrt(1e-6 / 0.01), rel=0.03)


def test_on_a_side_slope_the_rear_axle_crabs_at_k_f_y_v():
    """Straight across a 10 deg slope (heading east, downhill south) the plant's steady state (the
    wheel angle that holds gamma = 0, solved from its state space) moves the rear axle sideways at
    -k f_y v with k = m l_f / (L C_r): the rear tyres carry l_f / L of the side force m f_y at the
    slip angle force / C_r (the crab model the estimator uses); the plant holds that state."""
    from agrobot.components.models.yaw_dynamics import lateral_disturbance_column, state_space

    plant = TractorYawPlant("tractor", {"slope_angle": 10 * DEG, "slope_downhill_heading": -90 * DEG})
    v, dt = 2.0, 0.01
    plant.u.update(speed=v, steer_angle=0.0)
    plant.initialize(0.0, dt)
    A, B, _ = state_space("rlf", plant.params, v)
    a_lat = -9.81 * math.sin(10 * DEG)                          # gravity along the body's left axis
    n = A.shape[0]
    M = np.zeros((n + 1, n + 1))                                # A z + B delta = -E a_lat, gamma = z[1] = 0
    M[:n, :n], M[:n, n], M[n, 1] = A, B, 1.0
    rhs = np.concatenate([-lateral_disturbance_column(n) * a_lat, [0.0]])
    sol = np.linalg.solve(M, rhs)
    plant.z, plant.u["steer_angle"] = sol[:n].copy(), sol[n]
    for i in range(500):
        plant.step(i * dt, dt)
    p = plant.params
    k = p.m * p.l_f / ((p.l_f + p.l_r) * p.C_r)
    f_y = 9.81 * math.sin(10 * DEG)                             # what the tyres carry: the slope's pull
    crab = -math.sin(plant.y["heading"]) * plant.y["vel_east_rear"] + math.cos(plant.y["heading"]) * plant.y["vel_north_rear"]
    assert abs(plant.y["yaw_rate"]) < 1e-9 and abs(plant.y["heading"]) < 1e-9
    assert crab == pytest.approx(-k * f_y * v, rel=1e-6)


# --- the estimator -----------------------------------------------------------------------------------------
def _quiet_ekf(**params) -> INSEKF:
    ekf = INSEKF("ekf", params)
    ekf.initialize(0.0, 0.01)
    return ekf


def test_the_estimator_propagates_its_covariance_as_the_dense_jacobian_does():
    """predict's row and column operations against F P F' + Q, F by central differences of the
    motion model (a second method) and Q written from the noise model: the wheel speed's noise along
    the heading, the white velocity, the gyro's noise through the tilt, the random walks."""
    ekf = _quiet_ekf(crab_estimate=1)
    rng = np.random.default_rng(5)
    ekf.error_std = 0.3                                         # an RTK float fix's wandering error
    A = rng.standard_normal((8, 8)) * np.array([1e-3, 1e-3, 1e-3, 1e-5, 1e-3, 1e-4, 1e-2, 1e-2])
    s0, P0 = np.array([3.0, -2.0, 0.8, 1e-3, 0.04, 5e-3, 0.1, -0.2]), A @ A.T
    u = (0.05, 4 * DEG, -2 * DEG, 1.3, 2.1, 0.01)
    F = np.zeros((8, 8))
    for j in range(6):
        e = np.zeros(8)
        e[j] = 1e-6
        ekf.s = s0 + e
        plus = ekf.jacobian(*u)[0]
        ekf.s = s0 - e
        F[:, j] = (plus - ekf.jacobian(*u)[0]) / 2e-6              # (the error states do not move R)
    p, dt = ekf.p, u[-1]
    phi = math.exp(-dt / p["degraded_time_constant"])
    F[6, 6] = F[7, 7] = phi                                     # the receiver's error: a Gauss-Markov decay
    c, s = math.cos(s0[2]), math.sin(s0[2])
    Q = np.zeros((8, 8))
    Q[:2, :2] = (p["odometry_noise_std"] * dt) ** 2 * np.outer((c, s), (c, s)) + p["velocity_noise_psd"] * dt * np.eye(2)
    Q[2, 2] = p["gyro_noise_psd"] * dt / (math.cos(u[1]) * math.cos(u[2])) ** 2
    Q[3, 3] = 2 * p["gyro_bias_instability"] ** 2 / p["gyro_bias_time_constant"] * dt
    Q[4, 4] = 2 * p["odometry_scale_wander"] ** 2 / p["odometry_scale_time_constant"] * dt
    Q[5, 5] = p["slip_compliance_rate_std"] ** 2 * dt
    Q[6, 6] = Q[7, 7] = (1 - phi * phi) * 0.3 ** 2
    ekf.s, ekf.P = s0.copy(), P0.copy()
    ekf.predict(*u)
    assert np.allclose(ekf.P, F @ P0 @ F.T + Q, rtol=1e-6, atol=1e-16)


def test_dead_reckoning_uncertainty_grows_as_the_closed_form_of_the_sensor_model():
    """Straight east at v without fixes: the CG's cross-track error is e = y + l_r psi with
    dy/dt = v psi, dpsi/dt = -b + n_g, db/dt = w_b (and a white velocity), whose variance is, in
    closed form, P_yy + (v t + l_r)^2 P_pp + (v t^2/2 + l_r t)^2 P_bb + q_g (v^2 t^3/3 + v l_r t^2
    + l_r^2 t) + q_b (v^2 t^5/20 + v l_r t^4/4 + l_r^2 t^3/3) + q_v t (diagonal start)."""
    ekf = _quiet_ekf(crab_estimate=0, odometry_scale_std=0.0, odometry_scale_wander=0.0)
    P_yy, P_pp, P_bb = 0.01 ** 2, 0.002 ** 2, 2e-5 ** 2
    v, dt, l_r = 2.0, 0.01, ekf.p["l_r"]
    q_g, q_v = ekf.p["gyro_noise_psd"], ekf.p["velocity_noise_psd"]
    q_b = 2 * ekf.p["gyro_bias_instability"] ** 2 / ekf.p["gyro_bias_time_constant"]
    for n in (1000, 6000, 30000):               # 10 s, 1 min, 5 min
        ekf.P = np.diag([P_yy, P_yy, P_pp, P_bb, 0.0, 0.0, 0.0, 0.0])
        ekf.s = np.zeros(8)
        for _ in range(n):
            ekf.predict(0.0, 0.0, 0.0, 0.0, v, dt)
        ekf._publish(0.0, v, n * dt)
        t = n * dt
        var = (P_yy + (v * t + l_r) ** 2 * P_pp + (v * t * t / 2 + l_r * t) ** 2 * P_bb
               + q_g * (v * v * t ** 3 / 3 + v * l_r * t * t + l_r * l_r * t)
               + q_b * (v * v * t ** 5 / 20 + v * l_r * t ** 4 / 4 + l_r * l_r * t ** 3 / 3) + q_v * t)
        assert ekf.y["cross_track_std"] == pytest.approx(math.sqrt(var), rel=0.01), t


# --- GNSS quality ------------------------------------------------------------------------------------------
def _gps_run(params: dict, seconds: float, dt: float = 0.05, seed: int = 1) -> dict[str, np.ndarray]:
    gps = GPSSensor("gps", {"position_noise_std": 0.0, **params}, rng=np.random.default_rng(seed))
    gps.initialize(0.0, dt)
    rows = []
    for i in range(int(round(seconds / dt))):
        gps.step(i * dt, dt)
        rows.append((i * dt, gps.y["x"], gps.y["fix_valid"], gps.y["fix_quality"], gps.y["fix_age"]))
    return dict(zip(("t", "x", "valid", "quality", "age"), np.array(rows).T))


def test_outage_windows_carry_their_quality_and_a_degraded_fix_its_error():
    r = _gps_run({"outages": [[10, 20], [30, 2030, 2]], "dgps_error_std": 0.5}, 2040.0)
    t, q = r["t"], r["quality"]
    none = (t >= 10) & (t < 20)
    assert np.all(r["valid"][none] == 0) and np.all(q[none] == 0)
    assert r["age"][np.flatnonzero(none)[-1]] == pytest.approx(10.0, abs=0.06)
    dgps = (t >= 30) & (t < 2030)
    assert np.all(q[dgps] == 2) and np.all(r["valid"][dgps] == 1)
    assert np.all(q[~none & ~dgps] == 4)
    assert np.std(r["x"][dgps]) == pytest.approx(0.5, rel=0.3)          # a 60 s Gauss-Markov over 2000 s
    assert np.all(r["x"][~none & ~dgps] == 0.0)                          # RTK fixed: no white noise set here


def test_a_recorded_nmea_log_replays_its_qualities():
    """nmea-rtk.log (Trimble): 10.3 s of DGPS, ten minutes without a GGA, then RTK fixed. The
    replayed qualities against the log read as text (time and quality fields of each GGA)."""
    stamps, qualities = [], []
    for line in NMEA_RTK.read_text().splitlines():
        if "GGA," in line:
            f = line.split(",")
            stamps.append(int(f[1][:2]) * 3600 + int(f[1][2:4]) * 60 + float(f[1][4:]))
            qualities.append(int(f[6]))
    stamps = np.array(stamps) - stamps[0]
    t, q = gga_qualities(str(NMEA_RTK))
    assert np.allclose(t, stamps) and list(q) == qualities
    r = _gps_run({"quality_log": str(NMEA_RTK), "quality_log_start": 5.0}, 700.0, dt=0.1)
    at = {round(tt, 1): qq for tt, qq in zip(r["t"], r["quality"])}
    assert at[2.0] == 4 and at[6.0] == 2 and at[15.0] == 2           # before the log: RTK fixed; then its DGPS
    assert at[100.0] == 0 and at[round(5.0 + stamps[-1] - 0.5, 1)] == 4    # the pause: no fix; its last second: RTK fixed
    assert at[690.0] == 4                                              # after the log: back to RTK fixed


@pytest.mark.parametrize("value,expect", [("[[5, 1]]", "end after it starts"), ("[[5, 8, 11]]", "not a GGA fix quality"),
                                          ("[5, 8]", "expected [start_s, end_s]")])
def test_bad_outage_windows_exit_2_naming_the_window(tmp_path, value, expect):
    res = _cli("run", str(ROOT / "studies" / "field_coverage.toml"), "--out", str(tmp_path / "out"), *SECTION,
               "--set", f"gps.outages={value}")
    assert res.returncode == 2 and "outages" in res.stderr and expect in res.stderr, res.stderr
    assert "Traceback" not in res.stderr and not (tmp_path / "out").exists()


def test_a_log_without_gga_is_named(tmp_path):
    log = tmp_path / "empty.nmea"
    log.write_text("$GPRMC,000000,V,,,,,,,,,,N*53\n")
    res = _cli("run", str(ROOT / "studies" / "field_coverage.toml"), "--out", str(tmp_path / "out"), *SECTION,
               "--set", f"gps.quality_log={log}")
    assert res.returncode == 2 and "quality_log" in res.stderr and "no GGA" in res.stderr, res.stderr


# --- closed loop on real fields ---------------------------------------------------------------------------
@pytest.mark.slow
def test_on_a_10_degree_side_slope_tractor_and_implement_hold_2_5_cm():
    """Two swaths of a real parcel across a 10 deg side slope, RTK noise, the antenna 2.5 m up: with
    terrain compensation and the crab estimate (the field studies' default) the tractor's and the
    implement's P95 stay within 2.5 cm; without them the tractor runs h sin(10 deg) = 43 cm downhill."""
    common = (f"field.path={PARCEL}", "field.max_swaths=2", "field.headland_work=0", *SIDE_SLOPE)
    on = _run("field_coverage.toml", *common).metrics
    assert on["tractor_xte_p95_m"] <= 0.025 and on["implement_xte_p95_m"] <= 0.025, on
    off = _run("field_coverage.toml", *common, "ekf.terrain_compensation=0", "ekf.crab_estimate=0").metrics
    assert off["tractor_xte_rms_m"] == pytest.approx(2.5 * math.sin(10 * DEG), rel=0.15)


@pytest.mark.slow
def test_through_a_gnss_outage_the_estimator_drifts_within_its_own_uncertainty_and_the_watchdog_stops_on_it(tmp_path):
    """A 40 s outage on the second swath of a real parcel (the estimator has learnt its gyro's bias on
    the first and in the turn): the estimate rides through on the IMU and the
    odometry (no fix used, no stop without a bound), its drift at the end within 3 sigma of its own
    cross-track std; with a 5 cm bound the watchdog stops the tractor when that std passes 5 cm,
    saying why, and drives on when the fix returns."""
    common = (f"field.path={PARCEL}", "field.max_swaths=2", "field.headland_work=0", "gps.outages=[[140, 180]]")
    free = _run("field_coverage.toml", *common, "watchdog.max_position_std=inf")
    m, f = free.metrics, free.frame
    assert m["outages"] == 1 and m["guidance_stops"] == 0 and m["route_done_share"] > 0.99
    assert m["outage_1_duration_s"] == pytest.approx(40.0, abs=0.11)
    window = (f["t"] >= 140) & (f["t"] < 180)
    assert (f.loc[window, "ekf.fix_used"] == 0).all()
    std_end = float(f.loc[window, "ekf.cross_track_std"].iloc[-1])
    assert 0.02 < std_end < 0.3 and m["outage_1_drift_across_m"] < 3 * std_end, (m["outage_1_drift_across_m"], std_end)
    bounded = run_study(Study.load(ROOT / "studies" / "field_coverage.toml", [*common, "watchdog.max_position_std=5 cm"]),
                        tmp_path / "bounded", plots=False)
    b = bounded.metrics
    g = pd.DataFrame({c: bounded.frame[c].to_numpy() for c in ("t", "ekf.cross_track_std", "watchdog.safe_state")})
    crossing = float(g.loc[g["ekf.cross_track_std"] > 0.05, "t"].iloc[0])
    stop = float(g.loc[g["watchdog.safe_state"] > 0.5, "t"].iloc[0])
    assert 140 < crossing < 180 and 0 <= stop - crossing <= 0.05 + 1e-9
    assert b["guidance_stops"] == 1 and b["outage_1_stopped_after_s"] == pytest.approx(stop - 140, abs=0.1)
    assert b["route_done_share"] > 0.99                                # the fix came back: on it went
    events = (tmp_path / "bounded" / "events.log").read_text()
    assert "SAFE STATE: position estimate too uncertain" in events and "bound 0.05 m" in events, events


@pytest.mark.slow
def test_line_acquisition_after_each_turn_against_a_second_computation():
    """Three swaths of a real partfield: acquisition from the end of each turn (where the route
    straightens) until the CG is within 5 cm of the swath's line for 2 s, recomputed here from the
    signals with shapely (the distance to the swath's line as a LineString) and the route's own
    curvature, and ISO-style cross-track error along the whole route by interpolation."""
    from shapely.geometry import LineString, Point

    from agrobot.analysis.field_tracks import mission
    from agrobot.fields.planner import SWATH, TURN

    overrides = [f"field.path={PARTFIELDS}", "field.name=SW_Curitiba_Simple", "field.max_swaths=3",
                 "field.headland_work=0"]
    res = run_study(Study.load(ROOT / "studies" / "field_coverage.toml", overrides), None, plots=False)
    m = res.metrics
    study = Study.load(ROOT / "studies" / "field_coverage.toml", overrides)
    _, plan, conv, _ = mission(study)
    f = res.frame.iloc[::10].reset_index(drop=True)                   # 0.1 s, as the analysis samples
    t, x, y, s_est = (f[c].to_numpy() for c in ("t", "tractor.x_cg", "tractor.y_cg", "field.path_length"))
    r = plan.path.evaluate(np.arange(0.0, s_est.max() + 20.0, 0.1))     # the route on the trackers' grid
    got = []
    order = [seg.index for seg in plan.path.segments if seg.kind == SWATH]
    for k in order[1:]:
        first = int(np.flatnonzero((r["kind"] == SWATH) & (r["index"] == k))[0])
        i = first
        while r["kind"][i - 1] == TURN and abs(r["curvature"][i - 1]) < 1e-3:
            i -= 1
        seg = next(sg for sg in plan.path.segments if sg.kind == SWATH and sg.index == k)
        a, b = conv(seg.points[[0, -1], :2])
        d = (b - a) / np.hypot(*(b - a))
        line = LineString([a - 100 * d, b + 100 * d])
        j0 = int(np.flatnonzero(s_est >= r["s"][i])[0])
        for j in range(j0, len(t)):
            if line.distance(Point(x[j], y[j])) < 0.05:
                ahead = (t >= t[j]) & (t < t[j] + 2.0)
                if all(line.distance(Point(px, py)) < 0.05 for px, py in zip(x[ahead], y[ahead])):
                    got.append(((x[j] - x[j0]) * d[0] + (y[j] - y[j0]) * d[1], t[j] - t[j0]))
                    break
    assert len(got) == m["line_acquisitions"] == 2 and m["line_acquisition_failures"] == 0
    dist, secs = np.array(got).T
    assert m["line_acquisition_p95_m"] == pytest.approx(np.percentile(dist, 95), abs=1e-6)
    assert m["line_acquisition_p95_s"] == pytest.approx(np.percentile(secs, 95), abs=1e-6)
    assert 0 < m["line_acquisition_p95_m"] < 10.0 and m["route_xte_max_m"] < 0.5


def test_route_cross_track_interpolates_between_route_points():
    """On an arc of radius 20 m sampled every 2 m, the distance of points to the route by
    interpolation is within the chord's sagitta (2^2 / (8 R) = 2.5 cm) of the exact distance to the
    circle, and exact on a straight route; the nearest route point can be a metre off along it."""
    from agrobot.analysis.field_ground import route_cross_track

    theta = np.arange(0, 1.5, 0.1)
    rx, ry = 20 * np.sin(theta), 20 * (1 - np.cos(theta))
    rng = np.random.default_rng(2)
    a = np.sort(rng.uniform(0.05, 1.35, 40))
    off = rng.uniform(-1, 1, 40)
    px, py = (20 - off) * np.sin(a), 20 - (20 - off) * np.cos(a)
    d, _ = route_cross_track(px, py, rx, ry)
    assert np.allclose(d, off, atol=2.0 ** 2 / (8 * 20) + 1e-9)
    d_line, arc = route_cross_track(np.array([3.3, 7.7]), np.array([0.4, -0.25]), np.array([0.0, 5.0, 10.0]),
                                    np.zeros(3))
    assert d_line == pytest.approx([0.4, -0.25]) and arc == pytest.approx([3.3, 7.7])


@pytest.mark.slow
def test_pass_to_pass_at_an_interval_by_interpolation_against_shapely():
    """The ISO-style line test on a real parcel, its pause cut to 60 s: the second pass starts the
    pass, the turn and the pause after the first; pass-to-pass (the spacing of the implement's two
    tracks minus the planned one, 1 m apart along them) against shapely: each track as a line cut
    by the perpendicular to the swath every metre of their common part (the nearest-point distance
    would not do: the tracks jitter by the receiver's noise, and the nearest of the jittering
    vertices is nearer than the track at the same place)."""
    from shapely.geometry import LineString, Point

    from agrobot.analysis.field_tracks import _samples, _swath_frames, mission
    from agrobot.fields.planner import SWATH

    overrides = [f"field.path={PARCEL}", "operator.pauses=[[1, 60.0]]"]
    res = run_study(Study.load(ROOT / "studies" / "field_line_test.toml", overrides), None, plots=False)
    m = res.metrics
    study = Study.load(ROOT / "studies" / "field_line_test.toml", overrides)
    _, plan, conv, _ = mission(study)
    s = _samples(res.frame, study)
    tracks, starts = [], []
    for k in (0, 1):
        on = (s["impl_segment"] == SWATH) & (s["swath"] == k)
        tracks.append(np.column_stack([s.loc[on, "ix"], s.loc[on, "iy"]]))
        starts.append(float(s.loc[on, "t"].iloc[0]))
    paused = res.frame.loc[res.frame["operator.paused"] > 0.5, "t"]
    assert paused.iloc[-1] - paused.iloc[0] == pytest.approx(60.0, abs=0.11)
    assert m["pass_to_pass_interval_s"] == pytest.approx(starts[1] - starts[0], abs=1e-9)
    assert 60.0 < m["pass_to_pass_interval_s"] < 60.0 + 166 / 2.0 + 60.0
    spacing = plan.settings.working_width - plan.settings.overlap
    line = _swath_frames(plan, conv)[0]
    a, d = line[0], (line[-1] - line[0]) / np.hypot(*(line[-1] - line[0]))
    n = np.array([-d[1], d[0]])
    along = [(tr - a) @ d for tr in tracks]
    lines = [LineString(tr) for tr in tracks]
    gaps = []
    for g in np.arange(max(x.min() for x in along), min(x.max() for x in along), 1.0):
        cut = LineString([a + g * d - 20 * n, a + g * d + 20 * n])
        hits = [line.intersection(cut) for line in lines]
        if all(isinstance(h, Point) for h in hits):                   # a track that doubles back here is left out
            gaps.append(abs((np.array(hits[1].coords[0]) - np.array(hits[0].coords[0])) @ n) - spacing)
    assert len(gaps) > 50
    assert m["pass_to_pass_p95_m"] == pytest.approx(np.percentile(np.abs(gaps), 95), abs=1e-3)


def test_a_standing_implement_jittering_gives_a_strip_of_few_points():
    """An implement that stands (a pause, a watchdog stop) while its position jitters by a few
    millimetres: its swept strip is buffered from points at least 5 cm apart (L1), so the strip of
    2,000 standing samples and a 10 m drive is the drive's 200 points or so, and covers the same
    area as the straight 10 m strip (10 m x 3 m plus the round join: at most pi 1.5^2 more)."""
    import pandas as pd

    from agrobot.analysis.field_tracks import _strips

    rng = np.random.default_rng(1)
    n_drive, n_stand = 1001, 2000
    x = np.concatenate([np.linspace(0.0, 10.0, n_drive), 10.0 + 0.003 * rng.standard_normal(n_stand)])
    y = np.concatenate([np.zeros(n_drive), 0.003 * rng.standard_normal(n_stand)])
    s = pd.DataFrame({"ix": x, "iy": y, "working": np.ones(len(x))})
    (strip,) = _strips(s, 3.0)
    assert len(strip.exterior.coords) < 600
    assert 30.0 - 0.05 <= strip.area <= 30.0 + math.pi * 1.5 ** 2
