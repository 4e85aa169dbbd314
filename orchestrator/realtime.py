"""Real-time pacing: base step k starts no earlier than wall time start + k h.

Per step it records the lateness (wall time at the start of the step minus its deadline: the
jitter) and the compute time; a step that starts later than ``tolerance`` after its deadline is a
deadline miss (the previous steps overran their slot). Statistics in milliseconds. An observer
of the engine (orchestrator.observers): it waits before each base step.
"""
from __future__ import annotations

import time
from array import array

import numpy as np

from .observers import Observer


class RealTimePacer(Observer):
    def __init__(self, step: float, tolerance: float = 0.002) -> None:
        self.h, self.tolerance = step, tolerance
        self.started(None)

    def started(self, sim) -> None:
        """A new run: the clock starts at its first step."""
        self.start: float | None = None
        self.lateness = array("d")
        self.compute = array("d")
        self._step_start = 0.0

    def instant(self, k: int) -> None:
        """Wait until base step ``k``'s deadline."""
        now = time.perf_counter()
        if self.start is None:
            self.start = now
        else:
            self.compute.append(now - self._step_start)
        deadline = self.start + k * self.h
        if now < deadline:
            time.sleep(deadline - now)
            now = time.perf_counter()
        self.lateness.append(now - deadline)
        self._step_start = now

    def stats(self) -> dict:
        late = np.frombuffer(self.lateness, dtype=float) * 1e3
        busy = np.frombuffer(self.compute, dtype=float) * 1e3
        if not len(late):
            return {"steps": 0}

        def pct(x: np.ndarray) -> dict:
            return {"p50": float(np.percentile(x, 50)), "p99": float(np.percentile(x, 99)), "max": float(x.max())} \
                if len(x) else {}

        return {"steps": len(late), "step_ms": self.h * 1e3, "deadline_misses": int(np.sum(late > self.tolerance * 1e3)),
                "tolerance_ms": self.tolerance * 1e3, "jitter_ms": pct(late), "compute_ms": pct(busy)}
