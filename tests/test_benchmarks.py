"""The benchmarks compare like with like: every solver answers the same QPs the same way.

The benchmark runs as the program a user runs (tests and benchmarks import nothing of each other);
it exits non-zero when a solver's answer differs from our MPC's by more than 1e-6."""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_mpc_benchmark_solvers_agree_on_the_closed_loop_qps():
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "mpc_step.py"), "--steps", "300",
                           "--do-mpc-steps", "0"], capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "300 steps" in proc.stdout and "answers equal to 1e-6" in proc.stdout
    rows = {name: float(med) for name, med in re.findall(r"^(ours: full MPC step \(daqp\)|bare QP: daqp|bare QP: proxsuite)"
                                                          r"\s+([\d.]+)", proc.stdout, re.M)}
    assert set(rows) == {"ours: full MPC step (daqp)", "bare QP: daqp", "bare QP: proxsuite"}
    assert all(v > 0 for v in rows.values())
    active = float(re.search(r"rate limit active in (\d+)%", proc.stdout).group(1))
    assert 5 < active < 95                     # the rate limit is active part of the time
