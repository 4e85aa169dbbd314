"""The yaw model's C kernel (identification.single_track_kernel) against the Python reference path
of identification.driving.YawModel on the same segments and parameter sets (to 1e-9 relative, yaw
rate and lateral velocity), and against the linear bicycle's steady turn (v delta / (L + K v^2),
an independent truth); without a compiler, ``auto`` runs Python and says so once."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from agrobot.components.models.tyre import axle_loads
from agrobot.components.models.yaw_dynamics import TractorParameters
from agrobot.identification import single_track_kernel
from agrobot.identification.driving import (DrivingLog, Segments, YawModel, cut_segments, steady_state_gain,
                                            understeer_gradient)
from agrobot.orchestrator.compiled import CompilerMissing

P = TractorParameters()
FZF, FZR = axle_loads(P.m, P.l_f, P.l_r)
SETS = [      # lag > 0 and lag = 0, a speed-dependent cornering, a delay, an offset, a gain
    {"c_f": 1.1 * P.C_f / FZF, "c_r": 0.9 * P.C_r / FZR, "lag": 0.12, "delay": 0.1, "gyro_bias": 0.01},
    {"c_f": P.C_f / FZF, "c_r": P.C_r / FZR, "lag": 0.0, "steer_offset": 0.02, "steer_gain": 0.9},
    {"c_f": 0.8 * P.C_f / FZF, "c_r": 1.2 * P.C_r / FZR, "lag": 0.05, "cornering_speed_slope": 0.3,
     "cornering_reference_speed": 1.5},
]


def driving_log(seconds: float = 24.0, h: float = 0.05, heading: bool = False) -> DrivingLog:
    """Steering sweeps at speeds from a crawl (below the simulation's floor) to 5 m/s, two runs."""
    t = np.arange(0.0, seconds, h)
    u = 0.25 * np.sin(0.9 * t) + 0.1 * np.sign(np.sin(0.31 * t))
    v = 2.6 + 2.4 * np.sin(0.2 * t)
    run = (t >= seconds / 2).astype(int)
    kernel = np.ones(5) / 5 if heading else None         # a yaw rate derived from a heading: a 5-sample average
    return DrivingLog(t, u, v, np.zeros_like(t), run, h, "delta", kernel=kernel)


def both(model: str, sets: list[dict], log: DrivingLog, params: TractorParameters = P, segs: Segments | None = None):
    segs = segs or cut_segments(log, 0.02, length=4.0)
    m = YawModel(model, params, log, segs, min_sim_speed=0.3)
    m.kernel = "python"
    ref = m.simulate_many(sets, lateral=True)
    m.kernel = "c"
    return ref, m.simulate_many(sets, lateral=True)


def assert_close(ref, got):
    for name, a, b in zip(("yaw rate", "lateral velocity"), ref, got):
        assert a.shape == b.shape
        err = np.max(np.abs(a - b)) / np.max(np.abs(a))
        assert err < 1e-9, f"{name}: relative difference {err:.3g}"


@pytest.mark.parametrize("friction", [np.inf, 0.6])
@pytest.mark.parametrize("model", ["bicycle", "rlf", "rlfr"])
def test_the_kernel_equals_the_python_path(model, friction):
    sets = [{**v, "friction": friction, "shape": 1.1 + 0.3 * i} for i, v in enumerate(SETS)]
    ref, got = both(model, sets, driving_log())
    assert np.max(np.abs(ref[0])) > 0.1                 # the log turns
    assert_close(ref, got)


def test_the_kernel_equals_the_python_path_on_mixed_friction_and_a_heading():
    """Some rows with linear tyres beside rows that saturate, the yaw rate averaged as a heading's."""
    sets = [{**SETS[0], "friction": np.inf}, {**SETS[2], "friction": 0.4, "shape": 1.6}, {**SETS[1], "friction": 0.8}]
    assert_close(*both("rlf", sets, driving_log(heading=True)))


def test_the_kernel_takes_relaxation_lengths_per_row():
    """The diagnosis's replays give each row its own relaxation lengths (arrays over R S rows)."""
    log = driving_log()
    segs = cut_segments(log, 0.02, length=4.0)
    rows = 2 * len(segs.idx)
    params = replace(P, sigma_f=np.repeat([0.1, 0.4], rows // 2), sigma_r=np.repeat([1.5, 0.8], rows // 2))
    assert_close(*both("rlfr", [SETS[0], SETS[2]], log, params, segs))


def test_sets_that_differ_in_the_gyro_bias_alone_are_each_their_own():
    """A Jacobian's bias column: the same simulation, shifted by the bias, in any order."""
    log = driving_log(heading=True)
    model = YawModel("rlf", P, log, cut_segments(log, 0.02, length=4.0), min_sim_speed=0.3, kernel="c")
    sets = [SETS[0], {**SETS[0], "gyro_bias": 0.03}, SETS[1], {**SETS[1], "gyro_bias": -0.02}]
    many = model.simulate_many(sets)
    for got, v in zip(many, sets):
        np.testing.assert_array_equal(got, model.simulate(v))
    np.testing.assert_allclose(many[1] - many[0], 0.02, rtol=1e-12)
    np.testing.assert_allclose(many[3] - many[2], -0.02, rtol=1e-12)


@pytest.mark.parametrize("slope", [0.0, 0.25])
def test_the_kernel_reaches_the_steady_turn(slope):
    """Constant speed and wheel angle: the bicycle settles at v delta / (L + K v^2), K of the
    cornering coefficients scaled by 1 + k (v - v_ref)."""
    h, v, delta = 0.05, 4.0, 0.05
    t = np.arange(0.0, 30.0, h)
    log = DrivingLog(t, np.full_like(t, delta), np.full_like(t, v), np.zeros_like(t), np.zeros(len(t), int), h, "delta")
    segs = Segments(np.arange(len(t))[None, :], np.ones((1, len(t)), bool), np.zeros(1, bool))
    model = YawModel("bicycle", P, log, segs, kernel="c")
    values = {"c_f": P.C_f / FZF, "c_r": P.C_r / FZR, "lag": 0.3, "cornering_speed_slope": slope,
              "cornering_reference_speed": 2.0}
    yaw = model.simulate(values)[0]
    scale = 1.0 + slope * (v - 2.0)
    K = understeer_gradient(values["c_f"] * scale, values["c_r"] * scale)
    assert yaw[-1] == pytest.approx(delta * float(steady_state_gain(v, K, P.l_f + P.l_r)), rel=1e-6)


def test_without_a_compiler_auto_runs_python_and_says_so_once(monkeypatch, capsys):
    def missing():
        raise CompilerMissing("no C compiler (test)")

    monkeypatch.setattr(single_track_kernel.LIBRARY, "state", {})
    monkeypatch.setattr(single_track_kernel.LIBRARY, "load", missing)
    assert single_track_kernel.choose("auto") == "python"
    assert single_track_kernel.choose("auto") == "python"
    assert capsys.readouterr().err.count("run in Python") == 1
    with pytest.raises(CompilerMissing):
        single_track_kernel.choose("c")
