"""Steering hydraulics and speed drivetrain against their stated equations."""
from __future__ import annotations

import math

import numpy as np
import pytest

from agrobot.components.models.pid import DiscretePID
from agrobot.components.speed_drivetrain import SpeedDrivetrain, steady_state_speed
from agrobot.components.speed_pid import SpeedPID
from agrobot.components.steering_hydraulics import SteeringHydraulics, valve_opening

DEG = math.pi / 180


def run_steering(cmd, seconds, dt=0.01, **params):
    s = SteeringHydraulics("steering", params)
    s.initialize(0.0, dt)
    s.u["steer_angle_cmd"] = cmd
    rows = []
    for k in range(int(round(seconds / dt))):
        s.step(k * dt, dt)
        rows.append((s.y["steer_angle"], s.y["steer_angle_measured"], s.y["valve_voltage"]))
    return np.array(rows)


def test_valve_opening_dead_band_and_saturation():
    assert valve_opening(6.0, 6.0, 0.5, 6.0) == 0.0
    assert valve_opening(6.49, 6.0, 0.5, 6.0) == 0.0
    assert valve_opening(5.51, 6.0, 0.5, 6.0) == 0.0
    assert valve_opening(6.5 + 2.75, 6.0, 0.5, 6.0) == pytest.approx(0.5)
    assert valve_opening(6.0 - 0.5 - 2.75, 6.0, 0.5, 6.0) == pytest.approx(-0.5)
    assert valve_opening(12.0, 6.0, 0.5, 6.0) == 1.0 and valve_opening(20.0, 6.0, 0.5, 6.0) == 1.0


def test_flow_limit_sets_the_fastest_steering_rate():
    """Full valve: rate = 12 L/min / (volume per rad) = 60 deg/s with the defaults."""
    r = run_steering(40 * DEG, 1.0, dt=0.001)
    rate = np.diff(r[:, 0]) / 0.001
    assert rate.max() <= math.radians(60.0) * (1 + 1e-9)
    assert rate.max() == pytest.approx(math.radians(60.0), rel=1e-3)


def test_angle_is_limited_to_45_degrees_and_measured_in_whole_degrees():
    r = run_steering(80 * DEG, 3.0)
    assert np.abs(r[:, 0]).max() <= 45 * DEG + 1e-12
    assert r[-1, 0] == pytest.approx(45 * DEG)
    steps = r[:, 1] / DEG
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-9)


def test_valve_voltage_stays_within_0_and_12_volts():
    for cmd in (-80 * DEG, 80 * DEG):
        r = run_steering(cmd, 2.0, kp=1e4)
        assert r[:, 2].min() >= 0.0 and r[:, 2].max() <= 12.0


def test_dead_band_stops_a_small_command_without_integral_action():
    """P only: 2 deg error x 10 V/rad = 0.35 V < 0.5 V dead-band: the wheels never move."""
    r = run_steering(2 * DEG, 2.0, kp=10.0, ki=0.0)
    assert np.all(r[:, 0] == 0.0)
    # the same command with integral action eventually pushes through the dead-band
    r = run_steering(2 * DEG, 5.0, kp=10.0, ki=20.0)
    assert r[-1, 1] == pytest.approx(2 * DEG, abs=1e-9)


def test_steering_tracks_a_step_within_a_degree():
    r = run_steering(10 * DEG, 2.0)
    assert abs(r[-1, 0] - 10 * DEG) <= 1.0 * DEG


def test_drivetrain_follows_first_order_lag_to_the_static_map():
    d = SpeedDrivetrain("d", {"pedal0": 0.6, "time_constant": 0.8})
    d.initialize(0.0, 0.01)
    d.u["pedal_valve_voltage"] = 6.0          # neutral: the pedal stays put
    v_ss = steady_state_speed(0.6, 4.0, 0.12, 1.3)
    for k in range(300):
        d.step(k * 0.01, 0.01)
    assert d.y["pedal_position"] == 0.6
    assert d.y["speed"] == pytest.approx(v_ss * (1 - math.exp(-3.0 / 0.8)), rel=1e-9)
    assert steady_state_speed(0.1, 4.0, 0.12, 1.3) == 0.0
    assert steady_state_speed(1.0, 4.0, 0.12, 1.3) == 4.0


def test_pedal_actuator_rate_and_dead_band():
    d = SpeedDrivetrain("d", {})
    d.initialize(0.0, 0.01)
    d.u["pedal_valve_voltage"] = 6.3          # inside the 0.4 V dead-band
    for k in range(100):
        d.step(k * 0.01, 0.01)
    assert d.y["pedal_position"] == 0.0
    d.u["pedal_valve_voltage"] = 12.0         # full opening: 1 pedal travel per second
    for k in range(50):
        d.step(k * 0.01, 0.01)
    assert d.y["pedal_position"] == pytest.approx(0.5, rel=1e-9)


def closed_speed_loop(seconds, v_d=2.0, **pid):
    d, c = SpeedDrivetrain("d", {}), SpeedPID("c", pid)
    d.initialize(0.0, 0.01)
    c.initialize(0.0, 0.05)
    c.u["speed_desired"] = v_d
    n = int(round(seconds / 0.01))
    speeds = []
    for k in range(n):
        if k % 5 == 0:
            c.u.update(speed=d.y["speed"], pedal_position=d.y["pedal_position"])
            c.step(k * 0.01, 0.05)
            d.u["pedal_valve_voltage"] = c.y["pedal_valve_voltage"]
        d.step(k * 0.01, 0.01)
        speeds.append(d.y["speed"])
    return np.array(speeds)


def test_default_speed_pid_leaves_a_steady_state_error_as_the_paper_observed():
    v = closed_speed_loop(60.0)
    err = 2.0 - v[-1000:].mean()
    assert err > 0.05
    # with the integral unclamped, the same loop removes it: the clamp is the cause
    v = closed_speed_loop(60.0, integral_limit=1.0)
    assert abs(2.0 - v[-1000:].mean()) < 0.02


def test_discrete_pid_against_hand_computed_values():
    pid = DiscretePID(2.0, 1.0, 0.5, -10, 10, integral_limit=0.15)
    assert pid.update(1.0, 0.1) == pytest.approx(2.0)                # P; integral then 0.1
    assert pid.update(0.5, 0.1) == pytest.approx(1.0 + 0.1 - 2.5)    # P + I + D(-5)
    assert pid.integral == pytest.approx(0.15)                       # 0.15 clamp
    pid2 = DiscretePID(100.0, 1.0, 0.0, -1, 1)
    pid2.update(1.0, 0.1)
    assert pid2.integral == 0.0                                      # saturated: integral frozen


def test_inlined_substep_loop_equals_the_stated_equations():
    """The component's inlined loop against the module docstring written with DiscretePID,
    valve_opening and quantize, on a random command sequence that crosses the dead-band,
    saturates the voltage and hits the mechanical stop."""
    from agrobot.components.steering_hydraulics import quantize

    rng = np.random.default_rng(7)
    cmds = np.repeat(rng.uniform(-60, 60, 10) * DEG, 100)
    cmds[400:500] = 0.3 * DEG                                    # inside the dead-band
    s = SteeringHydraulics("steering", {})
    s.initialize(0.0, 0.01)
    p = s.p
    pi = DiscretePID(p["kp"], p["ki"], 0.0, p["voltage_min"] - 6.0, p["voltage_max"] - 6.0, p["integral_limit"])
    h, delta, opening, reached = 0.001, 0.0, 0.0, 0.0
    alpha = 1 - math.exp(-h / p["valve_time_constant"])
    rate = p["max_flow"] / p["volume_per_rad"]
    for k, cmd in enumerate(cmds):
        s.u["steer_angle_cmd"] = cmd
        s.step(k * 0.01, 0.01)
        for _ in range(10):
            voltage = 6.0 + pi.update(cmd - quantize(delta, p["potentiometer_resolution"]), h)
            opening += alpha * (valve_opening(voltage, 6.0, p["deadband"], 6.0) - opening)
            delta = min(max(delta + h * opening * rate, -45 * DEG), 45 * DEG)
        assert s.y["steer_angle"] == pytest.approx(delta, abs=1e-12)
        assert s.y["valve_voltage"] == pytest.approx(voltage, abs=1e-9)
        reached = max(reached, abs(delta))
    assert reached == pytest.approx(45 * DEG)                    # the stop was reached


def test_drivetrain_shortcut_for_a_still_pedal_equals_the_substep_equations():
    """Random valve voltages (dead-band, both pedal stops) against the docstring's per-substep
    equations."""
    d = SpeedDrivetrain("d", {})
    d.initialize(0.0, 0.01)
    p = d.p
    h, pedal, v = p["internal_step"], float(p["pedal0"]), float(p["speed0"])
    rng = np.random.default_rng(8)
    volts = np.repeat(rng.choice([0.0, 6.2, 12.0, 3.0, 9.0], 30), 60)
    stops = set()
    for k, volt in enumerate(volts):
        d.u["pedal_valve_voltage"] = volt
        d.step(k * 0.01, 0.01)
        o = valve_opening(volt, p["neutral_voltage"], p["deadband"], p["voltage_max"] - p["neutral_voltage"])
        for _ in range(int(round(0.01 / h))):
            pedal = min(max(pedal + h * o * p["pedal_rate_max"], 0.0), 1.0)
            v_ss = steady_state_speed(pedal, p["max_speed"], p["pedal_dead_zone"], p["speed_exponent"])
            v = v_ss + (v - v_ss) * math.exp(-h / p["time_constant"])
        stops.add(pedal if pedal in (0.0, 1.0) else None)
        assert d.y["pedal_position"] == pytest.approx(pedal, abs=1e-12)
        assert d.y["speed"] == pytest.approx(v, abs=1e-9)
    assert {0.0, 1.0} <= stops


# --- diagnosis-catalogue extensions -----------------------------------------------

def test_command_delay_shifts_the_step_response_by_the_delay():
    base = run_steering(10 * DEG, 1.5, dt=0.01)[:, 0]
    late = run_steering(10 * DEG, 1.5, dt=0.01, command_delay=0.2)[:, 0]
    assert np.all(late[:20] == 0.0)                                   # nothing moves for 0.2 s
    np.testing.assert_allclose(late[20:], base[:-20], atol=1e-12)     # then the same response


def test_angle_deadband_leaves_the_error_inside_the_band_and_small_commands_unexecuted():
    small = run_steering(1.5 * DEG, 2.0, angle_deadband=2 * DEG, ki=0.0)[:, 0]
    assert np.all(small == 0.0)
    big = run_steering(10 * DEG, 3.0, angle_deadband=2 * DEG, ki=0.0, potentiometer_resolution=0.0,
                       valve_time_constant=0.001)[:, 0]
    # a fast spool (no coasting): stops short by D plus the valve dead-band seen through kp
    # (0.5 V / 150 V/rad = 0.19 deg)
    assert 10 * DEG - (2 + 0.19 + 0.05) * DEG <= big[-1] <= 10 * DEG - 2 * DEG


def test_rate_limit_bounds_the_wheel_rate_below_the_valve_limit():
    r = run_steering(40 * DEG, 2.0, dt=0.001, rate_limit=15 * DEG)[:, 0]
    rate = np.diff(r) / 0.001
    assert rate.max() == pytest.approx(15 * DEG, rel=1e-9)
    assert r[-1] == pytest.approx(min(40 * DEG, 15 * DEG * 2.0), abs=0.5 * DEG)
