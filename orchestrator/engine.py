"""Fixed-step multirate master algorithm.

At each macro instant t_k = t0 + k*h (never accumulated):
 1. continuous components whose step ended at t_k publish the outputs they reached;
 2. sampled components due at t_k, in dependency order, read their inputs and step
    (their outputs hold on [t_k, t_k + step));
 3. every output is recorded for t_k;
 4. continuous components due at t_k read their inputs (all values of t_k) and integrate to
    t_k + step; their outputs stay private until step 1 of that instant.
Step 2 at k = 0 propagates the outputs at t0 before anything integrates.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .build import Node, System
from .component import ComponentError


class RunError(Exception):
    """A component failed mid-run; ``partial`` holds what was recorded before the failure."""

    def __init__(self, message: str, partial: "Recording") -> None:
        super().__init__(message)
        self.partial = partial


@dataclass
class Recording:
    columns: list[str]
    data: np.ndarray            # shape (n_samples, 1 + n_signals); column 0 is time
    wall_time_s: float
    completed: bool

    def to_frame(self):
        import pandas as pd

        return pd.DataFrame(self.data, columns=["t"] + self.columns)


class Simulation:
    def __init__(self, system: System) -> None:
        self.system = system
        s = system.study.study
        self.t0, self.h = s.start_time, s.base_step
        self.n_steps = int(round((s.stop_time - s.start_time) / s.base_step))
        self.signals = [(node, out) for node in system.nodes.values() for out in node.component.y]
        self.columns = [f"{node.name}.{out}" for node, out in self.signals]
        self._published: dict[str, dict] = {n.name: n.component.y for n in system.nodes.values()}

    @staticmethod
    def _pull(node: Node, published: dict[str, dict]) -> None:
        u = node.component.u
        for inp, src, out in node.sources:
            u[inp] = published[src.name][out]

    def run(self) -> Recording:
        sys_ = self.system
        start = time.perf_counter()
        published: dict[str, dict] = {}
        n = self.n_steps + 1
        data = np.full((n, 1 + len(self.signals)), np.nan)
        for node in sys_.nodes.values():
            try:
                node.component.initialize(self.t0, node.step)
            except (ComponentError, ValueError, ArithmeticError) as exc:
                rec = Recording(self.columns, data[:0], time.perf_counter() - start, False)
                raise RunError(f"initialising {node.name!r}: {exc}", rec) from exc
            published[node.name] = dict(node.component.y)
        sampled, continuous = sys_.sampled_order, sys_.continuous
        k = 0
        try:
            for k in range(n):
                t = self.t0 + k * self.h
                for node in continuous:
                    if k and k % node.ratio == 0:
                        published[node.name] = dict(node.component.y)
                for node in sampled:
                    if k % node.ratio == 0:
                        self._pull(node, published)
                        node.component.step(t, node.step)
                        published[node.name] = node.component.y
                row = data[k]
                row[0] = t
                for j, (node, out) in enumerate(self.signals, start=1):
                    row[j] = published[node.name][out]
                if k == n - 1:
                    break
                for node in continuous:
                    if k % node.ratio == 0:
                        self._pull(node, published)
                        node.component.step(t, node.step)
        except (ComponentError, FloatingPointError, ValueError, ArithmeticError) as exc:
            rec = Recording(self.columns, data[:k], time.perf_counter() - start, False)
            raise RunError(f"at t = {self.t0 + k * self.h:.6g} s: {exc}", rec) from exc
        return Recording(self.columns, data, time.perf_counter() - start, True)
