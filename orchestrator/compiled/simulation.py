"""The compiled engine: a study whose every component has a C core runs as one compiled program,
one call per run, with the interface of orchestrator.engine.Simulation (``start``, ``advance``,
``drain``, ``finish``, ``terminate``), so the runner streams and analyses it as a Python run.

The Python components are still built and initialised: their parameters are checked as in a
Python run (a refused value exits 2 the same way) and their outputs at t0 (before any step) are
the loop's initial published values. ``start`` runs the whole loop; ``advance`` and ``drain``
then hand the rows out. The C cores log no events (events.log stays empty) and nothing is paced
in real time (such a study is refused).
"""
from __future__ import annotations

import ctypes
import time

import numpy as np

from ..build import System
from ..component import ComponentError
from ..engine import ParameterError, RunError, Simulation
from ..errors import InputError
from ..signal_recorder import RecordedSignals, SignalRecorder
from .cores import CCore, NoCCore, c_core
from .generate import component_unit, layout, loop_unit
from .toolchain import CompilerMissing, UntrustedCache, library

ENGINES = ("python", "compiled", "auto")


class CompiledRefused(InputError):
    """--engine compiled on a study the compiled engine cannot take (the message names the components)."""


def cores_of(system: System) -> tuple[dict[str, CCore], dict[str, str]]:
    """({component: its C core}, {component: why it has none}) of a system."""
    cores, missing = {}, {}
    for name in system.nodes:
        try:
            cores[name] = c_core(system, name)
        except NoCCore as exc:
            missing[name] = str(exc)
    return cores, missing


def refusal(system: System, missing: dict[str, str]) -> str:
    """Why the compiled engine cannot take a system ('' when it can)."""
    parts = []
    if missing:
        parts.append("components without a C core: " + "; ".join(f"{n} ({why})" for n, why in missing.items()))
    if system.study.study.realtime:
        parts.append("the study is paced in real time (study.realtime)")
    return ", ".join(parts)


def select_engine(system: System, engine: str, found: tuple[dict, dict] | None = None):
    """(a Simulation-like class for ``system``, a line saying which engine runs and why, or None).
    ``compiled`` on a system it cannot take raises CompiledRefused; ``auto`` falls back to the
    Python engine and says why. ``found``: ``cores_of(system)`` when the caller has it already."""
    if engine not in ENGINES:
        raise InputError(f"--engine {engine!r}: expected one of {', '.join(ENGINES)}")
    if engine == "python":
        return Simulation, None
    cores, missing = found if found is not None else cores_of(system)
    why = refusal(system, missing)
    prepared = None
    if not why:
        try:
            prepared = CompiledSimulation.prepare(system, cores)
        except (CompilerMissing, UntrustedCache) as exc:     # auto: the Python engine, saying why
            if engine == "compiled":
                raise
            why = str(exc)
    if why:
        if engine == "compiled":
            raise CompiledRefused(f"{system.study.path}: --engine compiled: {why}; --engine auto or python runs "
                                  f"it in Python")
        return Simulation, f"engine: python (auto: the compiled engine cannot take this study: {why})"
    return (lambda sys_: CompiledSimulation(sys_, cores, prepared=prepared if sys_ is system else None)), \
        "engine: compiled (auto: a C compiler was found and every component has a C core; --engine python for " \
        "the reference engine)"


class CompiledSimulation:
    """A run of ``system`` by its compiled loop (``cores``: from ``cores_of``, all present)."""

    engine_name = "compiled"                # metrics.json and run.json say which engine ran

    def __init__(self, system: System, cores: dict[str, CCore] | None = None, record: bool = True,
                 prepared=None) -> None:
        self.system = system
        s = system.study.study
        self.t0, self.h = s.start_time, s.base_step
        self.n_steps = int(round((s.stop_time - s.start_time) / s.base_step))
        if cores is None:
            cores, missing = cores_of(system)
            why = refusal(system, missing)
            if why:
                raise CompiledRefused(f"{system.study.path}: {why}")
        self.cores = cores
        self.record = record
        self.columns = SignalRecorder(system, 1).columns
        self.lib, self.key, self.compiled_now = prepared or self.prepare(system, cores)
        self.layout = layout(system, cores, self.columns)
        self.observers: list = []
        self.k, self._drained, self._data, self._wall = 0, 0, None, 0.0
        self.ended_by = None

    @staticmethod
    def sources(system: System, cores: dict[str, CCore]) -> tuple[dict[str, str], list, list]:
        """({file name: C text} of the system's shape: one unit per component, c<i>.c, and
        loop.c), the include folders, every file the units include."""
        lay = layout(system, cores, SignalRecorder(system, 1).columns)
        units = {f"c{i}.c": component_unit(i, name, cores[name], float(system.nodes[name].step),
                                           not system.nodes[name].component.sampled)
                 for i, name in enumerate(lay.names)}
        units["loop.c"] = loop_unit(system, cores, lay)
        dirs = sorted({d for c in cores.values() for d in c.include_dirs})
        files = [f for c in cores.values() for f in c.files]
        return units, dirs, files

    @staticmethod
    def prepare(system: System, cores: dict[str, CCore]):
        """(library, key, compiled now) of the system's shape: compiled once, then cached."""
        return library(*CompiledSimulation.sources(system, cores))

    @property
    def chunk_period(self) -> int:
        return 1

    def add_observer(self, observer) -> None:
        self.observers.append(observer)

    def initial_vectors(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Initialise the Python components (parameter checks, outputs at t0) and return the
        loop's run-time arguments: parameters, initial published outputs, initial inputs."""
        for name, node in self.system.nodes.items():
            try:
                node.component.initialize(self.t0, node.step)
            except (ComponentError, ValueError, ArithmeticError) as exc:
                raise ParameterError(f"{self.system.study.path}: components.{name}: {exc}") from None
        return self._vectors()

    def _vectors(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The run-time arguments: parameters, initial published outputs, initial inputs."""
        par, pub0, in0 = [], [], []
        for name in self.layout.names:
            core, comp = self.cores[name], self.system.nodes[name].component
            par += [v for _, v in core.parameters]
            pub0 += [float(comp.y[o]) for o in core.outputs]
            in0 += [float(comp.u[i]) for i in core.inputs]
        return tuple(np.ascontiguousarray(v, dtype=float) for v in (par, pub0, in0))

    def start(self) -> None:
        """Initialise the components (checks, outputs at t0) and run the whole loop."""
        began = time.perf_counter()
        par, pub0, in0 = self.initial_vectors()
        width = 1 + len(self.layout.columns)
        columns = np.empty((width, self.n_steps + 1)) if self.record else None
        ptr = ctypes.POINTER(ctypes.c_double)
        status = self.lib.agc_run(par.ctypes.data_as(ptr), pub0.ctypes.data_as(ptr), in0.ctypes.data_as(ptr),
                                  self.n_steps, columns.ctypes.data_as(ptr) if columns is not None else None)
        if status != 0:
            raise RunError(f"the compiled loop could not allocate its state (status {status})", self.partial())
        if columns is not None:
            columns[0] = self.t0 + np.arange(self.n_steps + 1) * self.h
        self._data = columns.T if columns is not None else None        # (rows, 1 + signals), a view
        self._wall = time.perf_counter() - began
        self.k, self._drained = 0, 0
        for obs in self.observers:
            if getattr(obs, "started", None) is not None:
                obs.started(self)

    def advance(self, k_end: int, final: bool = False) -> None:
        self.k = k_end
        for obs in self.observers:
            if getattr(obs, "advanced", None) is not None:
                obs.advanced(k_end)

    def _rows(self, first: int, last: int) -> np.ndarray:
        if self._data is None:
            return np.empty((0, 1 + len(self.columns)))
        return self._data[first:last]

    def _recording(self, rows: int, completed: bool) -> RecordedSignals:
        return RecordedSignals(self.columns, self._rows(self._drained, rows), self._wall, completed, [], None, None)

    def partial(self) -> RecordedSignals:
        return self._recording(self.k, False)

    def drain(self) -> np.ndarray:
        data = self._rows(self._drained, self.k)
        self._drained = self.k
        return data

    def finish(self) -> RecordedSignals:
        rec = self._recording(self.n_steps + 1, True)
        self.k = self.n_steps
        return rec

    def run(self) -> RecordedSignals:
        try:
            self.start()
            return self.finish()
        finally:
            self.terminate()

    def terminate(self) -> None:
        for node in self.system.nodes.values():
            try:
                node.component.terminate()
            except Exception:       # noqa: BLE001 - releasing resources must not mask the run's outcome
                pass
