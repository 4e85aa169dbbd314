"""The benchmarks compare like with like: every solver answers the same QPs the same way."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import mpc_step  # noqa: E402


def test_mpc_benchmark_solvers_agree_on_the_closed_loop_qps():
    res = mpc_step.measure(steps=300, do_mpc_steps=0)      # raises if any answer differs by > 1e-6
    assert set(res["rows"]) == {"ours: full MPC step (daqp)", "bare QP: daqp", "bare QP: proxsuite"}
    assert all(len(t) == 300 and np.all(t > 0) for t in res["rows"].values())
    assert 0.05 < res["active"] < 0.95                     # the rate limit is active part of the time
