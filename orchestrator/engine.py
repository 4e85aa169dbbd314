"""Fixed-step multirate master algorithm.

At each macro instant t_k = t0 + k*h (never accumulated):
 1. continuous components whose step ended at t_k publish the outputs they reached;
 2. sampled components due at t_k, in dependency order, read their inputs and step
    (their outputs hold on [t_k, t_k + step));
 3. every output is recorded for t_k; components defining ``actuate`` (hardware adapters) write
    the inputs of t_k out;
 4. continuous components due at t_k, and sampled ones that ``advance`` (FMUs), read their inputs
    (all values of t_k; every read happens before any of them steps) and integrate to
    t_k + step; their outputs stay private until step 1 (continuous) or step 2 (advancing) of
    that instant.
A component raising EndRun (an FMU's terminate request) ends the run cleanly at the last instant
recorded in full; ``Recording.ended_by`` says who asked, when and why.
Each component's outputs are recorded at the instants they can change (multiples of its step)
and held in between when the table is built.
Step 2 at k = 0 propagates the outputs at t0 before anything integrates.
"""
from __future__ import annotations

import math
import time
from array import array
from dataclasses import dataclass, field
from operator import itemgetter

import numpy as np

from .build import Node, System
from .component import ComponentError, EndRun
from .errors import ComputationError, InputError
from .realtime import RealTimePacer


class ParameterError(InputError):
    """A component refused its parameters when initialised (the message names the field)."""


class RunError(ComputationError):
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
    events: list[tuple[float, str, str]] = field(default_factory=list)   # (t, component, message)
    realtime: dict | None = None                                          # pacing statistics
    ended_by: dict | None = None          # {"component", "t", "reason"}: a component ended the run

    def to_frame(self):
        import pandas as pd

        return pd.DataFrame(self.data, columns=["t"] + self.columns)


def _numeric_scalar(value) -> bool:
    return isinstance(value, (int, float, np.number)) and not isinstance(value, (str, bytes))


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
    def __init__(self, system: System, record: bool = True) -> None:
        """``record=False``: keep no signal history (a sub-system stepped inside a component)."""
        self.system = system
        self.record = record
        s = system.study.study
        self.t0, self.h = s.start_time, s.base_step
        self.n_steps = int(round((s.stop_time - s.start_time) / s.base_step))
        # the signal table holds every numeric scalar output (strings, bytes and whole arrays of an
        # FMU are exchanged between components but not recorded; array elements are)
        self.signals = [(node, v.name) for node in system.nodes.values() for v in node.component.variables
                        if v.causality == "output" and _numeric_scalar(v.start)]
        self.columns = [f"{node.name}.{out}" for node, out in self.signals]
        # schedule over one period of the slowest rhythm: which nodes are due at k mod period
        period = math.lcm(*(node.ratio for node in system.nodes.values())) if system.nodes else 1
        self._period = period
        self._due_sampled = [[nd for nd in system.sampled_order if j % nd.ratio == 0] for j in range(period)]
        self._due_continuous = [[nd for nd in system.continuous if j % nd.ratio == 0] for j in range(period)]
        self._pulls = {nd.name: [(i, src.name, o) for i, src, o in nd.sources] for nd in system.nodes.values()}
        self.k, self._drained, self._recorders, self._start = 0, 0, [], time.perf_counter()
        self.ended_by: dict | None = None

    def _recording(self, recorders: list[_Recorder], rows: int, completed: bool, start: float) -> Recording:
        """The rows recorded since the last ``drain`` up to base step ``rows`` (absolute)."""
        drained = self._drained
        rows = max(rows - drained, 0)
        times = self.t0 + (drained + np.arange(rows)) * self.h
        blocks = [times.reshape(-1, 1)] + [r.table(rows) for r in recorders]
        data = np.hstack(blocks) if rows and recorders else np.empty((0, 1 + len(self.signals)))
        events = sorted((t, node.name, msg) for node in self.system.nodes.values() for t, msg in node.component.events)
        pacer = getattr(self, "pacer", None)
        return Recording(self.columns, data, time.perf_counter() - start, completed, events,
                         pacer.stats() if pacer is not None else None, self.ended_by)

    def run(self) -> Recording:
        """Initialise, step to stop_time, record; components are terminated afterwards."""
        try:
            self.start()
            self.advance(self.n_steps)
            return self.finish()
        finally:
            self.terminate()

    def start(self) -> None:
        """Initialise every component and publish its outputs at t0 (step 0 not yet taken)."""
        sys_ = self.system
        self._start = time.perf_counter()
        s = sys_.study.study
        self.pacer = RealTimePacer(self.h, s.realtime_tolerance) if s.realtime else None
        self.published = published = {}
        self._drained = 0          # a restarted simulation records from its start again
        outputs: dict[str, list[str]] = {}
        for node, out in self.signals:
            outputs.setdefault(node.name, []).append(out)
        recorders = {name: _Recorder(name, sys_.nodes[name].ratio, outs) for name, outs in outputs.items()} \
            if self.record else {}
        self._recorders = list(recorders.values())
        for node in sys_.nodes.values():
            try:
                node.component.initialize(self.t0, node.step)
            except (ComponentError, ValueError, ArithmeticError) as exc:
                # a component refusing its parameters before the first step: the user's input (exit 2)
                raise ParameterError(f"{sys_.study.path}: components.{node.name}: {exc}") from None
            except OSError as exc:          # a device or port that cannot be opened: the environment
                raise RunError(f"initialising {node.name!r}: {exc}",
                               self._recording(self._recorders, 0, False, self._start)) from exc
            published[node.name] = dict(node.component.y)
        pulls = self._pulls

        def entry(node: Node):
            comp = node.component
            return (node.name, comp.step, comp.u, pulls[node.name], node.step, recorders.get(node.name),
                    comp, node.ratio == 1)

        self._due_s = [[entry(nd) for nd in nodes] for nodes in self._due_sampled]
        self._due_a = [[(nd.component.u, pulls[nd.name], nd.component.actuate) for nd in nodes
                        if nd.component.actuate is not None] for nodes in self._due_sampled]
        self._due_c = [[entry(nd) for nd in nodes] for nodes in self._due_continuous]
        self._due_v = [[(nd.component.u, pulls[nd.name], nd.component.advance, nd.step) for nd in nodes
                        if nd.component.advance is not None] for nodes in self._due_sampled]
        # a continuous component stepping every base step publishes its live outputs: every
        # continuous input is pulled before any continuous component steps, so nobody sees a value
        # early. Slower ones publish a copy at the end of their step interval.
        for node in sys_.continuous:
            if node.ratio == 1:
                published[node.name] = node.component.y
        self.k = 0

    def advance(self, k_end: int, final: bool = False) -> None:
        """Take base steps k .. k_end - 1 in full (publish, sampled steps, record, actuate,
        continuous steps): afterwards the system stands at t0 + k_end h. ``final``: then take the
        instant k_end too, without integrating past it (the last instant of a run)."""
        published, period, pace = self.published, self._period, self.pacer
        due_s, due_c, due_a, due_v = self._due_s, self._due_c, self._due_a, self._due_v
        last = k_end if final else -1
        k, recorded = self.k, self.k
        try:
            for k in range(self.k, k_end + 1 if final else k_end):
                if pace is not None:
                    pace.wait(k)
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
                for u, sources, actuate in due_a[phase]:
                    for inp, src, out in sources:
                        u[inp] = published[src][out]
                    actuate(t)
                recorded = k + 1
                if k == last:
                    break
                advancing = due_v[phase]
                for _, _, u, sources, _, _, _, _ in continuous:
                    for inp, src, out in sources:
                        u[inp] = published[src][out]
                for u, sources, _, _ in advancing:
                    for inp, src, out in sources:
                        u[inp] = published[src][out]
                for _, step, _, _, dt, _, _, _ in continuous:
                    step(t, dt)
                for _, _, advance, dt in advancing:
                    advance(t, dt)
        except EndRun as request:
            if recorded == 0:
                raise RunError(f"at t = {self.t0:.6g} s: {request.component} ended the run before its first "
                               f"instant: {request.reason}", self._recording(self._recorders, 0, False, self._start))
            self.ended_by = {"component": request.component, "t": self.t0 + (recorded - 1) * self.h,
                             "reason": request.reason}
            self.k = self.n_steps = recorded          # every row before `recorded` is complete
            return
        except (ComponentError, FloatingPointError, ValueError, ArithmeticError, TypeError, OSError,
                KeyboardInterrupt) as exc:
            self.k = k
            what = "interrupted" if isinstance(exc, KeyboardInterrupt) else str(exc)
            raise RunError(f"at t = {self.t0 + k * self.h:.6g} s: {what}",
                           self._recording(self._recorders, k, False, self._start)) from exc
        self.k = k_end

    @property
    def chunk_period(self) -> int:
        """Base steps after which every recorder has a whole number of samples (drain on multiples)."""
        return self._period

    def drain(self) -> np.ndarray:
        """The rows (time + signals) of the base steps taken since the last drain, which must end on
        a multiple of ``chunk_period``; the recorders' buffers are emptied (memory stays flat)."""
        if self.k % self._period:
            raise ValueError(f"drain at base step {self.k}, not a multiple of {self._period}")
        data = self._recording(self._recorders, self.k, False, self._start).data
        for rec in self._recorders:
            del rec.buf[:]
        self._drained = self.k
        return data

    def finish(self) -> Recording:
        """The last instant (publish, sampled steps, record; nothing integrates past stop_time)."""
        if self.ended_by is not None:             # the last instant is recorded already
            return self._recording(self._recorders, self.k, True, self._start)
        self.advance(self.k, final=True)
        return self._recording(self._recorders, self.k + 1, True, self._start)

    def terminate(self) -> None:
        for node in self.system.nodes.values():
            try:
                node.component.terminate()
            except Exception:       # noqa: BLE001 - releasing resources must not mask the run's outcome
                pass
