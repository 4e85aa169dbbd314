"""Fixed-step multirate master algorithm.

At each macro instant t_k = t0 + k*h (never accumulated):
 1. continuous components whose step ended at t_k publish the outputs they reached;
 2. sampled components due at t_k, in dependency order, read their inputs and step
    (their outputs hold on [t_k, t_k + step));
 3. every output is recorded for t_k;
 4. continuous components due at t_k read their inputs (all values of t_k; every read happens
    before any of them steps) and integrate to t_k + step; their outputs stay private until
    step 1 of that instant.
Each component's outputs are recorded at the instants they can change (multiples of its step)
and held in between when the table is built.
Step 2 at k = 0 propagates the outputs at t0 before anything integrates.
"""
from __future__ import annotations

import math
import time
from array import array
from dataclasses import dataclass
from operator import itemgetter

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


def _single(key: str):
    return lambda d: (d[key],)


class _Recorder:
    """Outputs of one component, kept at the instants they can change (multiples of its ratio,
    for sampled and continuous components alike) and held in between when the table is built."""

    __slots__ = ("name", "ratio", "width", "get", "buf")

    def __init__(self, name: str, ratio: int, outputs: list[str]) -> None:
        self.name, self.ratio, self.width = name, ratio, len(outputs)
        self.get = itemgetter(*outputs) if len(outputs) > 1 else _single(outputs[0])
        self.buf = array("d")

    def table(self, rows: int) -> np.ndarray:
        """(rows, width): sample j of the buffer held over base steps j*ratio .. (j+1)*ratio - 1."""
        kept = np.frombuffer(self.buf, dtype=float).reshape(-1, self.width)
        return np.repeat(kept, self.ratio, axis=0)[:rows] if rows else kept[:0]


class Simulation:
    def __init__(self, system: System) -> None:
        self.system = system
        s = system.study.study
        self.t0, self.h = s.start_time, s.base_step
        self.n_steps = int(round((s.stop_time - s.start_time) / s.base_step))
        self.signals = [(node, out) for node in system.nodes.values() for out in node.component.y]
        self.columns = [f"{node.name}.{out}" for node, out in self.signals]
        # schedule over one period of the slowest rhythm: which nodes are due at k mod period
        period = math.lcm(*(node.ratio for node in system.nodes.values())) if system.nodes else 1
        self._period = period
        self._due_sampled = [[nd for nd in system.sampled_order if j % nd.ratio == 0] for j in range(period)]
        self._due_continuous = [[nd for nd in system.continuous if j % nd.ratio == 0] for j in range(period)]
        self._pulls = {nd.name: [(i, src.name, o) for i, src, o in nd.sources] for nd in system.nodes.values()}

    def _recording(self, recorders: list[_Recorder], rows: int, completed: bool, start: float) -> Recording:
        times = self.t0 + np.arange(rows) * self.h
        blocks = [times.reshape(-1, 1)] + [r.table(rows) for r in recorders]
        data = np.hstack(blocks) if rows else np.empty((0, 1 + len(self.signals)))
        return Recording(self.columns, data, time.perf_counter() - start, completed)

    def run(self) -> Recording:
        sys_ = self.system
        start = time.perf_counter()
        published: dict[str, dict] = {}
        n = self.n_steps + 1
        outputs: dict[str, list[str]] = {}
        for node, out in self.signals:
            outputs.setdefault(node.name, []).append(out)
        recorders = {name: _Recorder(name, sys_.nodes[name].ratio, outs) for name, outs in outputs.items()}
        ordered = list(recorders.values())
        for node in sys_.nodes.values():
            try:
                node.component.initialize(self.t0, node.step)
            except (ComponentError, ValueError, ArithmeticError) as exc:
                raise RunError(f"initialising {node.name!r}: {exc}",
                               self._recording(ordered, 0, False, start)) from exc
            published[node.name] = dict(node.component.y)
        period = self._period
        pulls = self._pulls

        def entry(node: Node):
            comp = node.component
            return (node.name, comp.step, comp.u, pulls[node.name], node.step, recorders.get(node.name),
                    comp, node.ratio == 1)

        due_s = [[entry(nd) for nd in nodes] for nodes in self._due_sampled]
        due_c = [[entry(nd) for nd in nodes] for nodes in self._due_continuous]
        # a continuous component stepping every base step publishes its live outputs: every
        # continuous input is pulled before any continuous component steps, so nobody sees a value
        # early. Slower ones publish a copy at the end of their step interval.
        for node in sys_.continuous:
            if node.ratio == 1:
                published[node.name] = node.component.y
        k = 0
        try:
            for k in range(n):
                t = self.t0 + k * self.h
                phase = k % period
                continuous = due_c[phase]
                for name, _, _, _, _, rec, comp, live in continuous:
                    if k and not live:
                        published[name] = dict(comp.y)
                    if rec is not None:
                        rec.buf.extend(rec.get(published[name]))
                for name, step, u, sources, dt, rec, comp, _ in due_s[phase]:
                    for inp, src, out in sources:
                        u[inp] = published[src][out]
                    step(t, dt)
                    y = published[name] = comp.y
                    if rec is not None:
                        rec.buf.extend(rec.get(y))
                if k == n - 1:
                    break
                for _, _, u, sources, _, _, _, _ in continuous:
                    for inp, src, out in sources:
                        u[inp] = published[src][out]
                for _, step, _, _, dt, _, _, _ in continuous:
                    step(t, dt)
        except (ComponentError, FloatingPointError, ValueError, ArithmeticError, TypeError) as exc:
            raise RunError(f"at t = {self.t0 + k * self.h:.6g} s: {exc}",
                           self._recording(ordered, k, False, start)) from exc
        return self._recording(ordered, n, True, start)
