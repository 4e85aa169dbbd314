"""The diagnosis's stage replays in C (diagnosis.replay_kernels) against their Python references on
the same candidates, to 1e-9: the steering's first-order equivalent, the yaw replay's indexed
recursion and its first-order hold, and whole replays of a generated tractor log
(every stage, the command-only yaw stage too). The kernels are also held to truths of their own:
a step through the first-order lag, the hold of a rotation generator."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import expm

from agrobot.components.models import steering_equivalent
from agrobot.components.models.yaw_dynamics import TractorParameters
from agrobot.diagnosis import replay_kernels
from agrobot.diagnosis.baseline import baseline_from_study
from agrobot.diagnosis.candidates import Replay
from agrobot.diagnosis.replay import YawReplay, blocked_recursion, first_order_hold, steering_replay
from agrobot.orchestrator.study import load_study
from harness.truth_tractor import make_log

ROOT = Path(__file__).resolve().parents[1]
pytestmark = pytest.mark.skipif(replay_kernels.choose("auto") != "c", reason="no C compiler")


def close(a, b, tol=1e-9):
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert a.shape == b.shape and np.array_equal(np.isnan(a), np.isnan(b))
    a, b = np.nan_to_num(a), np.nan_to_num(b)
    assert np.max(np.abs(a - b), initial=0.0) <= tol * max(1.0, float(np.max(np.abs(b), initial=0.0)))


@pytest.mark.parametrize("tau, deadband, rate, delay", [(0.07, 0.0, 10.0, 0.0), (0.2, 0.01, 0.3, 0.1),
                                                        (0.05, 0.003, 0.5, 0.237), (1e-6, 0.02, 0.2, 0.049)])
def test_steering_kernel_equals_the_python_loop(tau, deadband, rate, delay):
    rng = np.random.default_rng(3)
    h = 0.05
    cmd = np.repeat(rng.uniform(-0.4, 0.4, 60), 20) + 0.01 * rng.standard_normal(1200)
    v = {"steering_time_constant": tau, "steering_deadband": deadband, "steering_rate_limit": rate,
         "command_delay": delay}
    python = steering_replay(cmd, h, v, 0.02, kernel="python")
    assert np.ptp(python) > 0.3
    close(steering_replay(cmd, h, v, 0.02, kernel="c"), python)


def test_steering_kernel_follows_a_step_through_the_lag():
    """A step of c after a whole-sample delay d: delta_k = c (1 - exp(-(k h - d)/tau)), no dead-band or limit."""
    h, tau, c, n_d = 0.02, 0.15, 0.3, 5
    cmd = np.r_[0.0, np.full(299, c)]
    pieces = steering_equivalent.step_pieces(cmd, h, tau, 1e9, n_d * h)
    out = replay_kernels.steering_first_order(pieces, 0.0, 0.0)
    k = np.arange(len(cmd))
    truth = np.where(k > n_d, c * (1.0 - np.exp(-(k - n_d - 1) * h / tau)), 0.0)
    close(out, truth, 1e-12)


def test_recursion_kernel_equals_the_blocked_recursion():
    rng = np.random.default_rng(5)
    R, S, N, n, p = 3, 7, 1501, 4, 2
    A = 0.9 * np.eye(n) + 0.1 * rng.standard_normal((R, S, n, n)) / np.sqrt(n)
    B = rng.standard_normal((R, S, n, p))
    index, columns = rng.integers(0, S, N), [0, 0, 1, 1, 0]
    u = rng.standard_normal((R, N, len(columns)))
    got = replay_kernels.indexed_recursion(A, B, index, columns, u, (1, 0))
    b = np.stack([B[r][index][:, :, columns] * u[r][:, None, :] for r in range(R)])
    close(got, blocked_recursion(np.stack([A[r][index] for r in range(R)]), b, row=(1, 0)))
    z = np.zeros((n, len(columns)))                    # the plain loop of the first set
    for k in range(N):
        close(got[0, k], z[[1, 0]])
        z = A[0, index[k]] @ z + b[0, k]


def test_hold_kernel_equals_the_python_hold():
    """The C first-order hold (phi_step.h) against its Python twin (identification.driving.phi_steps),
    over norms that take from no squaring to many; and Phi of a rotation's generator: Rot(w dt)."""
    rng = np.random.default_rng(7)
    size = np.linspace(0.01, 60.0, 40)[:, None, None]
    for n, p in ((2, 2), (4, 2), (3, 1), (5, 4)):
        A, B = rng.standard_normal((40, n, n)) * size, rng.standard_normal((40, n, p)) * size
        for dt in (0.01, 0.05):
            for got, want in zip(replay_kernels.first_order_hold(A, B, dt), first_order_hold(A, B, dt, "python")):
                close(got, want, 1e-12)
    close(replay_kernels.first_order_hold(A[:3], B[:3], 0.05)[0][2], expm(A[2] * 0.05), 1e-11)
    w, dt = 2.5, 0.4                 # a rotation's generator: exp = Rot(w dt)
    c, s = math.cos(w * dt), math.sin(w * dt)
    rotation = replay_kernels.first_order_hold(np.array([[[0.0, -w], [w, 0.0]]]), np.zeros((1, 2, 1)), dt)[0]
    close(rotation[0], [[c, -s], [s, c]], 1e-13)
    with pytest.raises(ValueError, match="at most 5 states"):
        replay_kernels.first_order_hold(np.zeros((1, 6, 6)), np.zeros((1, 6, 1)), dt)


@pytest.mark.parametrize("model", ["bicycle", "rlfr"])
def test_yaw_replay_kernel_equals_the_python_replay(model):
    rng = np.random.default_rng(11)
    n, h = 2400, 0.05
    t = np.arange(n) * h
    delta = 0.1 * np.sin(0.4 * t) + 0.02 * rng.standard_normal(n)
    speed = 2.0 + 1.5 * np.sin(0.05 * t)
    heading = np.cumsum(speed * delta / 1.4) * h
    p = TractorParameters()
    v = dict(cornering_front_scale=1.2, cornering_rear_scale=0.9, cornering_speed_slope=0.1,
             cornering_reference_speed=2.0, relaxation_scale=1.3, steer_angle_offset=0.01, slope_north=0.3,
             slope_east=-0.2, yaw_rate_bias=0.02)
    replayed = 0.8 * delta
    out = {}
    for kernel in ("python", "c"):
        r = YawReplay(model, p, h, delta, speed, heading, kernel=kernel)
        r.prepare([v, {**v, "cornering_rear_scale": 1.1}], [None, replayed])
        out[kernel] = [r.yaw_rate(v), r.yaw_rate({**v, "cornering_rear_scale": 1.1}, replayed),
                       r.rear_lateral_velocity(v), r.response_to(np.column_stack([delta, replayed]), v)]
    assert np.std(out["python"][0]) > 0.05
    for a, b in zip(out["c"], out["python"]):
        close(a, b)


@pytest.mark.parametrize("command_only", [False, True])
def test_replays_of_a_generated_log_are_the_same_in_c_and_python(command_only):
    """Every stage's prediction on a truth-tractor log (a hidden actuator delay), at the baseline and
    at a candidate with a fractional delay, dead-band and rate limit."""
    frame, _ = make_log(1000, "actuator_delay", duration=90.0)
    if command_only:
        frame = frame.drop(columns=["delta"])
    baseline = baseline_from_study(load_study(ROOT / "studies" / "figure8.toml"))
    replays = {k: Replay(frame, baseline, kernel=k) for k in ("python", "c")}
    stages = replays["c"].stages
    assert ("steering" in stages) != command_only and "yaw" in stages
    candidate = {**baseline.values, "command_delay": 0.213, "steering_deadband": 0.004, "steering_rate_limit": 0.35,
                 "cornering_rear_scale": 0.9}
    for stage in stages:
        for v in (baseline.values, candidate):
            close(replays["c"].predicted(stage, v), replays["python"].predicted(stage, v))
