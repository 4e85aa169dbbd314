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
recorded in full; ``RecordedSignals.ended_by`` says who asked, when and why.
Step 2 at k = 0 propagates the outputs at t0 before anything integrates.

From ``start`` to ``terminate`` the BLAS libraries run on one thread (threadpoolctl): the
components' matrices are a few rows wide, and on a busy machine a BLAS thread pool spends more
waking its threads than computing (a 6x6 matrix exponential: 18 ms instead of 20 us at load 6).

RecordedSignals the signals (orchestrator.signal_recorder), pacing against the wall clock
(orchestrator.realtime) and reporting progress are observers (orchestrator.observers): the
engine calls their hooks and takes no part in what they do.
"""
from __future__ import annotations

import math
import time
from typing import Iterable

import numpy as np

from threadpoolctl import threadpool_limits

from .build import System
from .component import ComponentError, EndRun
from .errors import ComputationError, InputError
from .instants import instant_functions
from .observers import Observer
from .realtime import RealTimePacer
from .signal_recorder import RecordedSignals, SignalRecorder
from .schedule import Schedule, block_rows, budget


class ParameterError(InputError):
    """A component refused its parameters when initialised (the message names the field)."""


class RunError(ComputationError):
    """A component failed mid-run; ``partial`` holds what was recorded before the failure."""

    def __init__(self, message: str, partial: "RecordedSignals") -> None:
        super().__init__(message)
        self.partial = partial


class Simulation:
    def __init__(self, system: System, record: bool = True, observers: Iterable[Observer] = ()) -> None:
        """``record=False``: keep no signal history (a sub-system stepped inside a component);
        ``observers`` watch the run besides the recorder and the real-time pacer."""
        self.system = system
        self.record = record
        s = system.study.study
        self.t0, self.h = s.start_time, s.base_step
        self.n_steps = int(round((s.stop_time - s.start_time) / s.base_step))
        # which nodes are due at k mod period (orchestrator.schedule): its cost checked first
        nodes = list(system.nodes.values())
        period = math.lcm(*(node.ratio for node in nodes)) if nodes else 1
        self._period = period
        self.recorder = SignalRecorder(system, period)
        self.columns = self.recorder.columns
        self.cost = budget(f"{system.study.path}", self.h, s.stop_time - s.start_time, [nd.step for nd in nodes],
                           [nd.ratio for nd in nodes], len(self.columns) if record else 0,
                           block_rows(len(self.columns), self.n_steps + 1))
        self.pacer = RealTimePacer(self.h, s.realtime_tolerance) if s.realtime else None
        self.observers: list[Observer] = [o for o in (self.pacer, self.recorder if record else None) if o is not None]
        self.observers += list(observers)
        self.k, self._drained, self._start = 0, 0, time.perf_counter()
        self.ended_by: dict | None = None
        self._blas_limit = None

    def add_observer(self, observer: Observer) -> None:
        """Watch the run (before ``start``)."""
        self.observers.append(observer)

    def _recording(self, rows: int, completed: bool) -> RecordedSignals:
        """The rows recorded since the last ``drain`` up to base step ``rows`` (absolute)."""
        data = self.recorder.rows(self.t0, self.h, self._drained, rows) if self.record else \
            self.recorder.rows(self.t0, self.h, 0, 0)
        events = sorted((t, node.name, msg) for node in self.system.nodes.values() for t, msg in node.component.events)
        return RecordedSignals(self.columns, data, time.perf_counter() - self._start, completed, events,
                         self.pacer.stats() if self.pacer is not None else None, self.ended_by, self.recorder.units)

    def partial(self) -> RecordedSignals:
        """What the run recorded up to where it stands (not completed)."""
        return self._recording(self.k, False)

    def run(self) -> RecordedSignals:
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
        if self._blas_limit is None:
            self._blas_limit = threadpool_limits(limits=1, user_api="blas")
        self._start = time.perf_counter()
        self.published = published = {}
        self._drained = 0          # a restarted simulation records from its start again
        sys_.restart()             # every component as built: a run depends on the study and seed alone
        for node in sys_.nodes.values():
            try:
                node.component.initialize(self.t0, node.step)
            except (ComponentError, ValueError, ArithmeticError) as exc:
                # a component refusing its parameters before the first step: the user's input (exit 2)
                raise ParameterError(f"{sys_.study.path}: components.{node.name}: {exc}") from None
            except OSError as exc:          # a device or port that cannot be opened: the environment
                raise RunError(f"initialising {node.name!r}: {exc}", self._recording(0, False)) from exc
            published[node.name] = dict(node.component.y)
        sampled = {nd.name for nd in sys_.sampled_order}
        self._due = Schedule(list(sys_.sampled_order) + list(sys_.continuous), lambda nd: nd.ratio,
                             lambda nodes: instant_functions(nodes, sampled, published))
        # a continuous component stepping every base step publishes its live outputs: every
        # continuous input is pulled before any continuous component steps, so nobody sees a value
        # early. Slower ones publish a copy at the end of their step interval.
        for node in sys_.continuous:
            if node.ratio == 1:
                published[node.name] = node.component.y
        self.k = 0
        for observer in self.observers:
            started = getattr(observer, "started", None)
            if started is not None:
                started(self)
        # the other hooks as they stand once started (an observer may set them up there)
        hooks = {name: [getattr(o, name) for o in self.observers if getattr(o, name) is not None]
                 for name in ("instant", "recorded", "advanced")}
        self._instant, self._recorded, self._advanced = hooks["instant"], hooks["recorded"], hooks["advanced"]

    def advance(self, k_end: int, final: bool = False) -> None:
        """Take base steps k .. k_end - 1 in full (publish, sampled steps, record, actuate,
        continuous steps): afterwards the system stands at t0 + k_end h. ``final``: then take the
        instant k_end too, without integrating past it (the last instant of a run)."""
        period, due = self._period, self._due.lookup
        before, after = self._instant, self._recorded
        last = k_end if final else -1
        k, recorded = self.k, self.k
        t0, h = self.t0, self.h
        try:
            for k in range(self.k, k_end + 1 if final else k_end):
                for hook in before:
                    hook(k)
                t = t0 + k * h
                phase = k % period
                publish_and_step, actuate, integrate = due(phase)
                publish_and_step(t, k)
                for hook in after:
                    hook(phase)
                if actuate is not None:
                    actuate(t)
                recorded = k + 1
                if k == last:
                    break
                integrate(t)
        except EndRun as request:
            if recorded == 0:
                raise RunError(f"at t = {self.t0:.6g} s: {request.component} ended the run before its first "
                               f"instant: {request.reason}", self._recording(0, False))
            self.ended_by = {"component": request.component, "t": self.t0 + (recorded - 1) * self.h,
                             "reason": request.reason}
            self.k = self.n_steps = recorded          # every row before `recorded` is complete
            return
        except (ComponentError, FloatingPointError, ValueError, ArithmeticError, TypeError, OSError,
                KeyboardInterrupt) as exc:
            self.k = k
            what = "interrupted" if isinstance(exc, KeyboardInterrupt) else str(exc)
            raise RunError(f"at t = {self.t0 + k * self.h:.6g} s: {what}", self._recording(k, False)) from exc
        self.k = k_end
        for hook in self._advanced:
            hook(k_end)

    @property
    def chunk_period(self) -> int:
        """Base steps after which every recorder has a whole number of samples (drain on multiples)."""
        return self._period

    def drain(self) -> np.ndarray:
        """The rows (time + signals) of the base steps taken since the last drain, which must end on
        a multiple of ``chunk_period``; the recorders' buffers are emptied (memory stays flat)."""
        if self.k % self._period:
            raise ValueError(f"drain at base step {self.k}, not a multiple of {self._period}")
        data = self._recording(self.k, False).data
        self.recorder.clear()
        self._drained = self.k
        return data

    def finish(self) -> RecordedSignals:
        """The last instant (publish, sampled steps, record; nothing integrates past stop_time)."""
        if self.ended_by is not None:             # the last instant is recorded already
            return self._recording(self.k, True)
        self.advance(self.k, final=True)
        return self._recording(self.k + 1, True)

    def terminate(self) -> None:
        """Release every component and give the BLAS libraries their threads back."""
        if self._blas_limit is not None:
            self._blas_limit.restore_original_limits()
            self._blas_limit = None
        for node in self.system.nodes.values():
            try:
                node.component.terminate()
            except Exception:       # noqa: BLE001 - releasing resources must not mask the run's outcome
                pass
