"""Kinematic tracker and the 8-shaped reference against their geometry."""
from __future__ import annotations

import math

import numpy as np
import pytest

from agrobot.components.figure8_reference import Figure8Reference
from agrobot.components.kinematic_tracker import KinematicTracker, inverse_kinematics
from agrobot.components.models.figure8_path import CURVED, STRAIGHT, Figure8Path


def test_inverse_kinematics_inverts_the_point_ahead_model():
    rng = np.random.default_rng(1)
    for _ in range(100):
        v, gamma, psi, lr = rng.uniform(-3, 3), rng.uniform(-1, 1), rng.uniform(-4, 4), rng.uniform(0.2, 2)
        # forward model (paper eq. for the kinematic controller): [xdot, ydot] = M(psi) [v, gamma]
        xdot = v * math.cos(psi) - lr * gamma * math.sin(psi)
        ydot = v * math.sin(psi) + lr * gamma * math.cos(psi)
        assert inverse_kinematics(xdot, ydot, psi, lr) == pytest.approx((v, gamma), abs=1e-12)


def tracker(**params):
    t = KinematicTracker("tracker", params)
    t.initialize(0.0, 0.05)
    return t


def test_tracker_without_error_returns_the_reference_feed_forward():
    t = tracker()
    t.u.update(x_ref=3.0, y_ref=4.0, x=3.0, y=4.0, xdot_ref=0.0, ydot_ref=2.0, heading=math.pi / 2)
    t.step(0.0, 0.05)
    assert t.y["speed_desired"] == pytest.approx(2.0) and t.y["yaw_rate_desired"] == pytest.approx(0.0, abs=1e-12)


def test_tracker_correction_is_saturated_by_k_s():
    t = tracker(k_s=0.6, k_c=1.5)
    t.u.update(x_ref=100.0, y_ref=0.0, x=0.0, y=0.0, xdot_ref=0.0, ydot_ref=0.0, heading=0.0)
    t.step(0.0, 0.05)
    assert t.y["speed_desired"] == pytest.approx(0.6 * math.tanh(150.0))
    assert t.y["speed_desired"] <= 0.6
    t.u.update(x_ref=0.0, y_ref=0.1)
    t.step(0.05, 0.05)
    assert t.y["yaw_rate_desired"] == pytest.approx(0.6 * math.tanh(0.15) / 0.4)


PATH = Figure8Path(10.0, 20.0)


def test_path_is_continuous_with_continuous_heading_and_right_curvature():
    s = np.linspace(0, PATH.lap_length, 20001)
    poses = np.array([PATH.pose(si) for si in s])
    ds = s[1] - s[0]
    steps = np.hypot(np.diff(poses[:, 0]), np.diff(poses[:, 1]))
    assert steps.max() == pytest.approx(ds, rel=1e-6)        # unit speed, no jumps
    dh = np.angle(np.exp(1j * np.diff(poses[:, 2])))
    assert np.abs(dh).max() <= ds / 10.0 * (1 + 1e-6)        # heading continuous, |curvature| <= 1/r
    # heading is the direction of motion, curvature is the heading's derivative
    # (away from the 4 segment joints, where a chord spans two segments)
    inside = (np.diff(poses[:, 4]) == 0) & (np.abs(np.diff(poses[:, 3])) == 0)
    direction = np.arctan2(np.diff(poses[:, 1]), np.diff(poses[:, 0]))
    chord_error = np.angle(np.exp(1j * (direction - poses[:-1, 2] - dh / 2)))
    assert np.abs(chord_error[inside]).max() < 1e-6
    np.testing.assert_allclose((dh / ds)[inside], poses[:-1, 3][inside], atol=1e-6)
    assert np.count_nonzero(~inside) <= 4
    assert np.hypot(*poses[-1, :2]) < 1e-9                   # closed lap


def test_path_labels_and_lengths():
    th = math.asin(0.5)
    assert PATH.lap_length == pytest.approx(4 * math.sqrt(300) + 2 * 10 * (math.pi + 2 * th))
    s = np.linspace(0, PATH.lap_length, 100001)[:-1]
    labels = np.array([PATH.pose(si)[4] for si in s])
    assert set(labels) == {STRAIGHT, CURVED}
    assert np.mean(labels == CURVED) == pytest.approx(2 * 10 * (math.pi + 2 * th) / PATH.lap_length, abs=1e-4)
    # the loops' centres are where the geometry says: every curved sample is r from one of them
    pts = np.array([PATH.pose(si)[:2] for si in s[labels == CURVED]])
    d = np.minimum(np.hypot(pts[:, 0] - 20, pts[:, 1]), np.hypot(pts[:, 0] + 20, pts[:, 1]))
    np.testing.assert_allclose(d, 10.0, atol=1e-9)


def test_reference_velocity_is_the_time_derivative_of_position():
    ref = Figure8Reference("ref", {"speed": 1.7, "ramp_time": 5.0})
    ref.initialize(0.0, 0.05)
    t = np.arange(0, 120, 0.01)
    rows = []
    for ti in t:
        ref.step(ti, 0.01)
        rows.append((ref.y["x_ref"], ref.y["y_ref"], ref.y["xdot_ref"], ref.y["ydot_ref"], ref.y["speed_ref"]))
    r = np.array(rows)
    vel = np.gradient(r[:, :2], 0.01, axis=0)[2:-2]
    np.testing.assert_allclose(vel, r[2:-2, 2:4], atol=2e-3)
    assert r[0, 4] == 0.0 and r[-1, 4] == pytest.approx(1.7)
    assert ref.progress(5.0)[0] == pytest.approx(1.7 * 5.0 / 2)
