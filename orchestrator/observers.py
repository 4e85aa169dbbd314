"""Observers of a run, kept apart from the master algorithm (after libcosim's observers): they see
the simulation, never change it. The engine (orchestrator.engine) calls each hook an observer
defines, and only those:

- ``started(sim)``: every component initialised and its outputs at t0 published;
- ``instant(k)``: before base step k is taken (real-time pacing, orchestrator.realtime);
- ``recorded(phase)``: every output of instant k is published (``sim.published``), before
  anything integrates past t_k (the signal recorder, orchestrator.recording); ``phase`` is
  k modulo the schedule's period;
- ``advanced(k)``: a call to ``Simulation.advance`` has reached base step k (progress).
"""
from __future__ import annotations

import sys
import time


class Observer:
    """Base of the observers: a hook left None is not called."""

    started = None
    instant = None
    recorded = None
    advanced = None


class Progress(Observer):
    """tqdm on a terminal; otherwise a line on stderr every ``every`` seconds of wall time, and only
    for runs that last longer than that."""

    def __init__(self, total_steps: int, h: float, every: float = 10.0) -> None:
        self.total, self.h, self.every = total_steps, h, every
        self.t_start = self.last = time.perf_counter()
        self.bar = None
        if sys.stderr.isatty():
            from tqdm import tqdm

            self.bar = tqdm(total=total_steps, unit="step", file=sys.stderr, leave=False, mininterval=1.0)

    def advanced(self, k: int) -> None:
        if self.bar is not None:
            self.bar.n = k
            self.bar.refresh()
            return
        now = time.perf_counter()
        if now - self.last >= self.every:
            self.last = now
            done = k / self.total if self.total else 1.0
            print(f"progress: t = {k * self.h:.6g} of {self.total * self.h:.6g} s ({100 * done:.0f}%), "
                  f"{k * self.h / (now - self.t_start):.3g} x real time", file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
