"""The diagnosis's yaw replay (blocked recursion, blocks run side by side) against the plain
sample-by-sample recursion Z_k = A_k Z_{k-1} + b_k, on random time-varying systems and on the
yaw replay of a real F1TENTH log (the plain loop substituted for the blocked one)."""
from __future__ import annotations

import numpy as np
import pytest

import agrobot.diagnosis.replay as replay_module
from agrobot.components.models.yaw_dynamics import TractorParameters
from agrobot.diagnosis.replay import YawReplay, blocked_recursion
from tests.vehicle_logs import frictionmaps_log


def plain_recursion(A, b, row):
    """State before each sample's update, one sample at a time."""
    N, n, m = b.shape
    rows = [row] if isinstance(row, int) else list(row)
    z, out = np.zeros((n, m)), np.empty((N, len(rows), m))
    for k in range(N):
        out[k] = z[rows]
        z = A[k] @ z + b[k]
    return out[:, 0, :] if isinstance(row, int) else out


@pytest.mark.parametrize("N, n, m", [(1, 2, 1), (2, 1, 1), (37, 2, 4), (1000, 2, 4), (999, 4, 3), (2501, 3, 1)])
def test_blocked_recursion_equals_the_plain_recursion(N, n, m):
    rng = np.random.default_rng(N + n + m)
    A = 0.9 * np.eye(n) + 0.1 * rng.standard_normal((N, n, n)) / np.sqrt(n)
    b = rng.standard_normal((N, n, m))
    for row in ([0, (n - 1, 0)] if n > 1 else [0]):
        ref = plain_recursion(A, b, row)
        for block in (0, 1, 5, 64, N + 3):
            got = blocked_recursion(A, b, row, block=block)
            assert got.shape == ref.shape
            assert np.max(np.abs(got - ref)) <= 1e-9 * np.max(np.abs(ref))


@pytest.mark.parametrize("name", ["DS1", "DS5"])
def test_yaw_replay_of_a_real_log_equals_the_plain_recursion(name, monkeypatch):
    log = frictionmaps_log(name)
    t = log["t"].to_numpy(float)
    n = min(len(t), 3000)
    h = float(np.median(np.diff(t[:n])))
    delta = np.nan_to_num(log["delta_cmd"].to_numpy(float)[:n]) if "delta_cmd" in log else np.zeros(n)
    speed = np.nan_to_num(log["v"].to_numpy(float)[:n]) if "v" in log else np.full(n, 2.0)
    heading = np.cumsum(np.nan_to_num(log["yaw_rate"].to_numpy(float)[:n])) * h
    p = TractorParameters(m=3.33, I=0.0687, l_f=0.112, l_r=0.208, C_f=106.0, C_r=57.0)
    v = dict(cornering_front_scale=1.3, cornering_rear_scale=0.8, cornering_speed_slope=0.2,
             cornering_reference_speed=2.0, relaxation_scale=1.0, steer_angle_offset=0.01, slope_north=0.3,
             slope_east=-0.2, yaw_rate_bias=0.02)

    replayed = 0.5 * delta

    def run():
        """A replayed wheel angle's response first (one recursion with the four responses),
        then the measured one's; and in the other order on a second replay."""
        r, r2 = YawReplay("bicycle", p, h, delta, speed, heading), YawReplay("bicycle", p, h, delta, speed, heading)
        out = [r.yaw_rate(v, replayed), r.yaw_rate(v), r.rear_lateral_velocity(v)]
        return out + [r2.yaw_rate(v), r2.yaw_rate(v, replayed)]

    blocked = run()
    monkeypatch.setattr(replay_module, "blocked_recursion", plain_recursion)
    plain = run()
    assert np.max(np.abs(blocked[0] - blocked[1])) > 0.0
    for x, y in zip(blocked, plain):
        assert np.max(np.abs(x - y)) <= 1e-9 * np.max(np.abs(y))
    assert np.max(np.abs(blocked[0] - blocked[4])) <= 1e-12 * np.max(np.abs(blocked[4]))
