"""Real-time pacing on this machine: deadline misses, lateness (jitter) and compute time per step,
for an idle component at 100 Hz and for the figure-8 with the tractor as one component at 20 Hz.
These are the timing figures the tests do not assert (they depend on the machine's load; the tests
check that misses are counted and reported, on a clock that only sleeping moves).

    python benchmarks/realtime_pacing.py [--seconds 30]
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path

from agrobot.orchestrator.runner import simulate
from agrobot.orchestrator.study import load_study, parse_study

ROOT = Path(__file__).resolve().parents[1]


def idle(seconds: float):
    return parse_study({"study": {"name": "idle", "stop_time": seconds, "base_step": 0.01, "seed": 1, "realtime": True},
                        "components": {"s": {"type": "tests.toy_components:Sleeper", "step": 0.01,
                                             "parameters": {"sleep": 0.0, "every": 10}}}}, ROOT / "idle.toml")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=30.0, help="wall time of each paced run")
    args = parser.parse_args()
    cases = [("idle component, 10 ms steps", idle(args.seconds)),
             ("figure-8, hardware layout, 50 ms steps",
              load_study(ROOT / "studies" / "figure8_hardware_layout.toml",
                         [f"study.stop_time={args.seconds}", "study.realtime=true"]))]
    print(f"load average at start: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    print(f"{'run':<40}{'steps':>7}{'misses':>8}{'share':>8}{'late p50/p99/max [ms]':>26}{'compute p50/p99/max [ms]':>28}")
    for name, study in cases:
        rec, _ = simulate(study)
        rt = rec.realtime
        fmt = lambda d: f"{d['p50']:.2f}/{d['p99']:.2f}/{d['max']:.2f}"  # noqa: E731
        print(f"{name:<40}{rt['steps']:>7}{rt['deadline_misses']:>8}{rt['deadline_misses'] / rt['steps']:>8.1%}"
              f"{fmt(rt['jitter_ms']):>26}{fmt(rt['compute_ms']):>28}", flush=True)


if __name__ == "__main__":
    main()
