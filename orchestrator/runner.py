"""Run a study end to end: build, simulate, analyse, write ``metrics.json``, the signal table and
plots into an output folder.

The signals are streamed to the folder while the run goes (memory stays flat in the run's length)
and the analysis reads them back by column (orchestrator.signal_table). The folder is written
aside and moved into place when the run ends (orchestrator.output): a complete run replaces what
``--out`` held; an interrupted or failed one never replaces a complete result and goes beside it.

Imported where used: orchestrator.compiled (start-up: 0.016 s on every command, which loads this module;
--engine compiled or auto only).
"""
from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .build import System, build_system
from .engine import RunError, Simulation
from .errors import ComputationError, Interrupted, Terminated, critical
from .fatal_calls import forget, named, watching
from .key_figures import bounds, check_study_bounds, realtime_lines, run_table
from .observers import Progress, Stage
from .output import ResultFolder, disk_full, place_output_parameters, study_inputs
from .signal_recorder import RecordedSignals, SignalRecorder
from .registry import import_study_module
from .resolver import resolve
from .atomic_files import SignalWriter, atomic_write, write_json
from .schedule import WRITE_BYTES, WRITE_EVERY, block_rows
from .signal_table import SignalTable
from .study import Study, StudyError


class AnalysisError(ComputationError):
    """The study's analysis could not compute its metrics (the signals are kept)."""


@dataclass
class RunOutcome:
    metrics: dict[str, Any]
    frame: Any                  # a DataFrame (in memory) or the folder's SignalTable (read by column)
    summary: str                # the key figures with their bounds, and the real-time pacing
    files: list[Path]
    failed_bounds: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    record: dict[str, Any] | None = None    # what run.json holds (a run in memory)
    events: str = ""                        # what events.log holds (a run in memory)


def _analysis(study: Study):
    if not study.study.analysis:
        return None
    try:
        module = import_study_module(study.study.analysis)
    except ModuleNotFoundError as exc:
        raise StudyError(f"{study.path}: study.analysis: cannot import {study.study.analysis!r} ({exc})") from None
    check_study_bounds(module, study.study.bounds, study.origin)
    return module


def say_held_inputs(system: System) -> None:
    """Say, once as a run starts, every input left unconnected that holds its start value."""
    for line in system.held_lines():
        print(f"note: {line}", file=sys.stderr)


def simulate(study: Study):
    """Build and simulate; returns (recording, system). Raises StudyError / RunError."""
    system = build_system(resolve(study))
    return Simulation(system).run(), system


def _run_facts(rec: RecordedSignals) -> dict[str, Any]:
    """Real-time statistics, the number of logged events and who ended the run early (a
    component's terminate request), for metrics.json."""
    facts: dict[str, Any] = {"events": len(rec.events)}
    if rec.realtime is not None:
        facts["realtime"] = rec.realtime
    if rec.ended_by is not None:
        facts["ended_by"] = rec.ended_by
    return facts


def _status(rec: RecordedSignals) -> str:
    """'completed', or 'ended' when a component asked to end the run before the stop time."""
    return "ended" if rec.ended_by is not None else "completed"


def _t_end(study: Study, rec: RecordedSignals) -> float:
    return rec.ended_by["t"] if rec.ended_by is not None else study.study.stop_time


def events_text(rec: RecordedSignals) -> str:
    """What events.log holds: one line per component event, 't [s]  component  message'."""
    lines = [f"{t:10.3f}  {name}  {msg}" for t, name, msg in rec.events]
    return "\n".join(lines) + ("\n" if lines else "")


def write_events(out_dir: Path, rec: RecordedSignals) -> Path:
    """events.log (events_text)."""
    text = events_text(rec)
    return atomic_write(out_dir / "events.log", lambda p: p.write_text(text))


CHUNK_STEPS = WRITE_EVERY     # base steps between two writes of the signal table ...
CHUNK_BYTES = WRITE_BYTES     # ... unless the whole run's table fits in this (schedule.block_rows)
REPORT_EVERY_S = 1.0          # wall time between two calls of Simulation.advance (progress, signals)
SPILL_EVERY_S = 0.1           # ... and between two blocks written when a crash could lose them (fatal_calls.watching)


def _stream(sim: Simulation, writer) -> RecordedSignals:
    """Run ``sim`` to its stop time, writing the signal table block by block: every CHUNK_STEPS
    base steps, or once after the run when its whole table fits in CHUNK_BYTES (schedule.block_rows;
    not a run paced in real time: what a crash would lose stays short). The engine is advanced about
    REPORT_EVERY_S of wall time at a time, so that progress moves as often whether the run is paced in
    real time or runs 500 times faster. Once a component has loaded a binary into this process
    (fatal_calls.watching) the blocks also go to a crash-readable file (SignalWriter.spill) every
    SPILL_EVERY_S, and the loop runs under a frame named after that file, which a fatal signal's
    dump prints. An interrupt outside the engine's step loop becomes the same RunError as one inside it (with
    the rows not yet written); draining and writing a block is never cut in half (errors.critical)."""
    chunk = CHUNK_STEPS if getattr(sim, "pacer", None) is not None else \
        block_rows(len(sim.columns), sim.n_steps + 1, CHUNK_STEPS, CHUNK_BYTES)
    try:
        sim.start()
        if watching() and hasattr(writer, "spill"):     # a binary in this process: its crash ends it at once
            where = writer.spill()
            named(f"the signals recorded until the crash: {where} (Arrow IPC stream of the blocks written, "
                  f"read by atomic_files.read_partial)" if where.suffix == ".arrows" else
                  f"the signals recorded until the crash: {where} (CSV, flushed at each block)",
                  _advance, sim, writer, chunk, True)
        else:
            _advance(sim, writer, chunk)
        with critical():
            rec = sim.finish()
            writer.append(rec.data)
        return rec
    except KeyboardInterrupt as exc:
        raise RunError(f"at t = {sim.t0 + sim.k * sim.h:.6g} s: interrupted", sim.partial()) from exc


def _advance(sim: Simulation, writer, chunk: int, spill: bool = False) -> None:
    """Advance ``sim`` to its stop time about REPORT_EVERY_S of wall time at a time, appending a
    block to ``writer`` every ``chunk`` base steps; ``spill`` (a run whose crash could leave no
    Python code to run): SPILL_EVERY_S at a time (the step at most doubled from one advance to the
    next), a block after every advance."""
    period, every = sim.chunk_period, SPILL_EVERY_S if spill else REPORT_EVERY_S
    step, drained = period, 0
    while sim.k < sim.n_steps:
        began = time.perf_counter()
        sim.advance(min(sim.k + step, sim.n_steps))
        took = time.perf_counter() - began
        rate = step / took if took > 0 else float("inf")
        grown = period * max(1, min(chunk // period, int(every * rate) // period))
        step = min(grown, 2 * step) if spill else grown        # spilling: a step's cost is learnt first
        if (spill or sim.k - drained >= chunk) and sim.k % period == 0 and sim.k > drained:
            with critical():
                writer.append(sim.drain())
                drained = sim.k


@dataclass
class Outcome:
    """What ``record_run`` left in a folder: the status of metrics.json and run.json, the facts
    written there, the error that stopped it (None when complete) and the files."""

    status: str                 # completed, ended, interrupted, failed, analysis_failed
    facts: dict[str, Any]
    error: BaseException | None
    files: list[Path]
    table: SignalTable | None = None
    values: dict[str, Any] = field(default_factory=dict)

    @property
    def complete(self) -> bool:
        return self.status in ("completed", "ended")


def record_run(study: Study, system: System, folder: Path, analysis=None, plots: bool = True,
               progress: bool = True, observers=(), simulation=None) -> Outcome:
    """Simulate ``system`` into ``folder`` (signals streamed, events.log, run.json), analyse the
    signals and write metrics.json (and the analysis's plots). Never raises for what a run can
    meet: a component failing, SIGINT/SIGTERM (in the simulation or the analysis), the analysis
    failing; the outcome says which, and metrics.json holds the status. ``simulation``: the
    engine's class (orchestrator.compiled.select_engine), the Python engine by default."""
    sim = (simulation or Simulation)(system)
    base = {**_base_facts(study), "engine": getattr(sim, "engine_name", "python")}
    recorder = getattr(sim, "recorder", None) or SignalRecorder(system, 1)     # the columns' units
    writer = SignalWriter(folder / "signals", sim.columns, study.study.signals_format, recorder.units)
    watch = Progress(sim.n_steps, sim.h) if progress else None
    for observer in ([watch] if watch is not None else []) + list(observers):
        sim.add_observer(observer)
    try:
        rec = _stream(sim, writer)
    except RunError as err:
        interrupt = err.__cause__ if isinstance(err.__cause__, KeyboardInterrupt) else None
        with critical():
            writer.append(err.partial.data)
            writer.close()
            write_events(folder, err.partial)
            status = "interrupted" if interrupt is not None else "failed"
            t_reached = study.study.start_time + (writer.rows - 1) * sim.h if writer.rows else study.study.start_time
            facts = {**base, "status": status, "t_reached_s": t_reached, "wall_time_s": err.partial.wall_time_s,
                     **_run_facts(err.partial)}
            if interrupt is None:
                facts["error"] = str(err)
            _write_status(folder, study, system, facts, t_reached)
        return Outcome(status, facts, interrupt if interrupt is not None else err,
                       [writer.path, folder / "events.log", folder / "metrics.json", folder / "run.json"])
    finally:
        if watch is not None:
            watch.close()
        try:
            sim.terminate()
        finally:
            forget()                            # a binary loaded by this run: the next run says so again
    facts = {**base, "status": _status(rec), "wall_time_s": rec.wall_time_s, **_run_facts(rec)}
    files: list[Path] = []
    table = None
    try:
        with critical():
            files = [writer.close(), write_events(folder, rec)]
            files.append(write_json(folder / "run.json", _run_json(study, system, _status(rec), _t_end(study, rec))))
            files.append(write_json(folder / "metrics.json", {**facts, "status": "analysing"}))
        table = SignalTable(writer.path)
        with Stage(f"analysing the signals ({study.study.analysis})" if analysis else "analysing the signals"):
            values = _metrics(analysis, table, study)
        values.update(sim_time_s=base["sim_time_s"], wall_time_s=rec.wall_time_s, **_run_facts(rec))
        metrics = {**base, "status": _status(rec), **values}
        if plots and analysis is not None and hasattr(analysis, "plots"):
            with Stage("drawing the figures"):
                files.extend(analysis.plots(table, study, folder))
        write_json(folder / "metrics.json", metrics)      # last: a folder whose metrics say completed is whole
    except (AnalysisError, KeyboardInterrupt) as exc:
        interrupted = isinstance(exc, KeyboardInterrupt)
        status = "interrupted" if interrupted else "analysis_failed"
        facts.update(status=status, **({"interrupted_in": "analysis (the simulation is complete)"} if interrupted
                                       else {"error": str(exc)}))
        _write_status(folder, study, system, facts, _t_end(study, rec))
        return Outcome(status, facts, exc, files, table)
    except Exception as exc:                    # a bug in the analysis: the signals are kept all the same
        if disk_full(exc):                      # the output's trouble, not the analysis's (a named error)
            raise
        facts.update(status="analysis_failed", error=f"{type(exc).__name__}: {exc}")
        _write_status(folder, study, system, facts, _t_end(study, rec))
        return Outcome("analysis_failed", facts, exc, files, table)
    return Outcome(_status(rec), metrics, None, files, table, values)


def _write_status(folder: Path, study: Study, system, facts: dict[str, Any], t_reached: float) -> None:
    with critical():
        write_json(folder / "metrics.json", facts)
        write_json(folder / "run.json", _run_json(study, system, facts["status"], t_reached))


COMPILED_HELD_BYTES = 512 * 1024 ** 2     # auto: a longer run's table streams through the Python engine


def _announced(factory, note: str):
    """``factory`` that prints ``note`` on stderr once the run is accepted (its budget checked)."""
    def make(system: System):
        sim = factory(system)
        print(note, file=sys.stderr)
        return sim
    return make


def choose_engine(system: System, engine: str):
    """The engine's class for ``engine`` (python, compiled, auto); the choice of ``auto``, and
    why, is printed on stderr when the run starts (orchestrator.compiled.select_engine). ``auto``
    keeps the Python engine for a run whose signal table passes COMPILED_HELD_BYTES: the compiled
    engine holds the whole table until the run ends, the Python one writes it as it goes."""
    if engine == "python":
        return Simulation
    if engine == "auto":
        s = system.study.study
        rows = int(round((s.stop_time - s.start_time) / s.base_step)) + 1
        held = rows * (len(SignalRecorder(system, 1).columns) + 1) * 8
        if held > COMPILED_HELD_BYTES:
            return _announced(Simulation, f"engine: python (auto: the compiled engine would hold the run's {rows} rows, "
                                          f"{held / 1024 ** 3:.3g} GB, in memory; the Python engine writes them as "
                                          f"it goes; --engine compiled forces it)")
    from .compiled import select_engine

    factory, note = select_engine(system, engine)
    return _announced(factory, note) if note and engine == "auto" else factory


def run_study(study: Study, out_dir: Path | None, plots: bool = True, overwrite: bool = False,
              progress: bool = True, engine: str = "python", observers=(),
              named: tuple[Path, ...] = ()) -> RunOutcome:
    """Simulate and analyse ``study``. With ``out_dir``: the output folder is checked and locked
    before anything runs (orchestrator.output), the run is recorded into a fresh folder beside it
    (``record_run``) and moved into place or beside it. A file the study writes besides
    (``record_file``) goes with the result when it lies inside ``out_dir``, and elsewhere only when
    the user named it (``--set``, or ``named``). Raises Interrupted (exit 130/143) on
    SIGINT/SIGTERM, RunError or AnalysisError on a failure, with ``where`` the folder that holds
    what was kept. ``engine``: python, compiled or auto (orchestrator.compiled)."""
    if out_dir is None:
        return _run_in_memory(study, plots, engine, observers)
    analysis = _analysis(study)
    inputs = study_inputs(study)
    folder = ResultFolder(Path(out_dir), overwrite, inputs=inputs)
    system = build_system(resolve(study))
    simulation = choose_engine(system, engine)
    say_held_inputs(system)
    with folder:
        placed, aside = place_output_parameters(study, Path(out_dir), folder.tmp, named, inputs, overwrite)
        try:
            if placed is not study:
                study, system = placed, build_system(resolve(placed))
            outcome = record_run(study, system, folder.tmp, analysis, plots, progress, observers, simulation)
        except KeyboardInterrupt as exc:        # a second signal while the first one's results were saved
            if not (folder.tmp / "metrics.json").exists():
                aside.finish(keep=False)
                raise
            outcome = Outcome("interrupted", json.loads((folder.tmp / "metrics.json").read_text()), exc, [])
        except BaseException:
            aside.finish(keep=False)
            raise
        aside.finish(keep=not disk_full(getattr(outcome.error, "__cause__", None)))
        tmp = folder.tmp
        where = folder.commit(outcome.status)
    kept = _kept(Path(out_dir), where)
    error = outcome.error
    if isinstance(error, KeyboardInterrupt):
        code = 143 if isinstance(error, Terminated) else 130
        t = outcome.facts.get("t_reached_s")
        at = f"at t = {t:.6g} s" if t is not None else "in the analysis (the simulation had completed)"
        raise Interrupted(f"{at}; the signals up to then are in {where}{kept}", code) from None
    if error is not None:
        error.where = where
        error.kept = kept
        raise error
    return _result(outcome.values, outcome.facts, analysis, study, [where / f.relative_to(tmp) for f in outcome.files],
                   SignalTable(where / outcome.table.path.name))


def _kept(out: Path, where: Path) -> str:
    """What the message of an unfinished run says of ``--out`` when the run went beside it."""
    return "" if where == out else f" (the earlier result in {out} is untouched)"


def _result(values: dict[str, Any], metrics: dict[str, Any], analysis, study: Study, files: list[Path],
            frame) -> RunOutcome:
    table, failed = run_table(values, analysis, bounds(analysis, study.study.bounds), study)
    lines, warning = realtime_lines(values.get("realtime"))
    return RunOutcome(metrics, frame, "\n".join([table, *lines]), files, failed, [warning] if warning else [])


def _base_facts(study: Study) -> dict[str, Any]:
    return {"study": study.study.name, "study_file": str(study.path), "seed": study.study.seed,
            "sim_time_s": study.study.stop_time - study.study.start_time}


def _run_json(study: Study, system, status: str, t_reached: float) -> dict[str, Any]:
    return {"status": status, "t_reached_s": t_reached, "study": study.to_data(),
            "unconnected_inputs": system.unconnected_inputs,
            "held_inputs": {port: {"value": value if isinstance(value, (int, float, str)) else repr(value),
                                   "unit": unit, "why": why}
                            for port, value, unit, why in system.held_inputs},
            "order_sampled": [n.name for n in system.sampled_order]}


def _metrics(analysis, frame, study: Study) -> dict[str, Any]:
    if analysis is None:
        return {}
    try:
        return dict(analysis.metrics(frame, study))
    except (ValueError, KeyError) as exc:
        raise AnalysisError(f"{study.path}: study.analysis {study.study.analysis!r}: {exc}") from None


def _run_in_memory(study: Study, plots: bool, engine: str = "python", observers=()) -> RunOutcome:
    """No output folder: simulate, analyse, return (tests, benchmarks)."""
    analysis = _analysis(study)
    system = build_system(resolve(study))
    say_held_inputs(system)
    sim = choose_engine(system, engine)(system)
    for observer in observers:
        sim.add_observer(observer)
    rec = sim.run()
    if not rec.units:                      # an engine without the Python recorder: the declared units
        rec.units = SignalRecorder(system, 1).units
    frame = rec.to_frame()
    values = _metrics(analysis, frame, study)
    base = {**_base_facts(study), "engine": getattr(sim, "engine_name", "python")}
    values.update(sim_time_s=base["sim_time_s"], wall_time_s=rec.wall_time_s, **_run_facts(rec))
    done = _result(values, {**base, "status": _status(rec), **values}, analysis, study, [], frame)
    done.record = _run_json(study, system, _status(rec), _t_end(study, rec))
    done.events = events_text(rec)
    return done
