"""The robust-guidance table (docs/guidance-loop.md): the figure-8 under delays, speeds, masses and yaw models,
with the paper's tracker law and with the shipped one.

    python3 benchmarks/robust_guidance.py

Each cell: max Euclidean error straight / curved [m] (the CG against the reference at the same
instant, analysis.figure8), and the steering rate RMS [deg/s]; in brackets the mean error on
straights with the reference held between its 20 Hz samples (the older figure) and the
honest one.
"""
from __future__ import annotations

import math
from pathlib import Path

from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.study import Study

ROOT = Path(__file__).resolve().parent.parent
PAPERS_LAW = ("tracker.lookahead=0", "steering.quantization_guard=0")
CONDITIONS = [
    ("nominal", "figure8.toml", (), True),
    ("steering.command_delay=0.05", "figure8.toml", ("steering.command_delay=0.05",), True),
    ("steering.command_delay=0.1", "figure8.toml", ("steering.command_delay=0.1",), True),
    ("steering.command_delay=0.2", "figure8.toml", ("steering.command_delay=0.2",), False),
    ("command_delay=0.1 + command_link.samples=1", "figure8.toml",
     ("steering.command_delay=0.1", "command_link.samples=1"), True),
    ("command_delay=0.1, reference.speed=1.0", "figure8.toml", ("steering.command_delay=0.1", "reference.speed=1.0"), False),
    ("command_delay=0.1, reference.speed=2.5", "figure8.toml", ("steering.command_delay=0.1", "reference.speed=2.5"), False),
    ("command_delay=0.1, mass and inertia +20 %", "figure8.toml",
     ("steering.command_delay=0.1", "tractor.m=840", "tractor.I=336"), False),
    ("command_delay=0.1, mass and inertia -20 %", "figure8.toml",
     ("steering.command_delay=0.1", "tractor.m=560", "tractor.I=224"), False),
    ("command_delay=0.1, gps.latency=0.1", "figure8.toml", ("steering.command_delay=0.1", "gps.latency=0.1"), False),
    ("tractor.model=rlfr, Table values", "figure8.toml", ("tractor.model=rlfr", "tractor.parameter_set=table"), True),
    ("tractor.model=rlfr, the stable set", "figure8.toml", ("tractor.model=rlfr",), True),
    ("tractor.model=rlfr, stable set, command_delay=0.1", "figure8.toml",
     ("tractor.model=rlfr", "steering.command_delay=0.1"), False),
    ("figure8_rlfr.toml (notch + R = 10)", "figure8_rlfr.toml", (), False),
    ("figure8_rlfr.toml, command_delay=0.1", "figure8_rlfr.toml", ("steering.command_delay=0.1",), False),
    ("figure8_rlfr.toml, reference.speed=2.5", "figure8_rlfr.toml", ("reference.speed=2.5",), False),
    ("tractor.model=bicycle", "figure8.toml", ("tractor.model=bicycle",), True),
    ("tractor.model=transfer_function", "figure8.toml", ("tractor.model=transfer_function",), True),
]


def cell(study: str, overrides: tuple[str, ...]) -> str:
    m = run_study(Study.load(ROOT / "studies" / study, list(overrides)), None, plots=False).metrics
    text = f"{m['euclid_max_straight']:.2f} / {m['euclid_max_curved']:.2f}"
    if m["euclid_max_straight"] > 5:
        return text + " (diverges)"
    return (text + f", {math.degrees(m['steer_rate_rms']):.1f} deg/s"
            f" (mean {m['euclid_mean_straight_held']:.2f} -> {m['euclid_mean_straight']:.2f})")


def main() -> None:
    papers_law = "paper's law (lookahead 0, no guard)"
    print(f"{'condition':52s} {papers_law:44s} shipped")
    for name, study, overrides, with_papers_law in CONDITIONS:
        papers = cell(study, overrides + PAPERS_LAW) if with_papers_law else ""
        print(f"{name:52s} {papers:44s} {cell(study, overrides)}", flush=True)


if __name__ == "__main__":
    main()
