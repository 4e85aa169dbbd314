"""The tractor plant's step on level ground with linear tyres (its state a list of floats, the
product unrolled) against its general step (numpy arrays throughout), to the bit, for every model,
through the low-speed scaling and reversing."""
from __future__ import annotations

import math

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from agrobot.components.tractor_yaw_plant import TractorYawPlant


@pytest.mark.parametrize("params", [{"model": "bicycle"}, {"model": "rlf"}, {"model": "rlfr"},
                                    {"model": "transfer_function"},
                                    {"model": "rlf", "antenna_forward": 0.8, "antenna_left": -0.3,
                                     "steer_angle_offset": 0.01}])
def test_level_step_equals_the_general_step_to_the_bit(params):
    dt = 0.01
    level, general = TractorYawPlant("a", params), TractorYawPlant("b", params)
    for plant in (level, general):
        plant.initialize(0.0, dt)
    assert level._level
    general._level = False                   # the general path on the same level ground
    rng = np.random.default_rng(7)
    # 40 speeds held 10 steps each (a discretisation per speed: the cache's hits and misses)
    speeds = np.repeat(np.concatenate([np.linspace(0.0, 2.5, 25), [0.05] * 5, -np.linspace(0.0, 1.0, 10)]), 10)
    with threadpool_limits(limits=1, user_api="blas"):          # as the engine runs (orchestrator.engine)
        turned = _compare(level, general, speeds, rng, dt)
    assert turned > 0.1 and level.y["x_cg"] != 0.0            # it turned and moved


def _compare(level, general, speeds, rng, dt) -> float:
    """The largest heading reached, the two plants' outputs equal at every step."""
    turned = 0.0
    for k, v in enumerate(speeds):
        delta = math.radians(20.0) * math.sin(0.02 * k) + float(rng.normal(0.0, 0.01))
        for plant in (level, general):
            plant.u["speed"], plant.u["steer_angle"] = float(v), delta
            plant.step(k * dt, dt)
        assert level.y == general.y, (k, {n: (level.y[n], general.y[n]) for n in level.y if level.y[n] != general.y[n]})
        turned = max(turned, abs(level.y["heading"]))
    return turned
