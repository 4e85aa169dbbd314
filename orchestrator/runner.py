"""Run a study end to end: build, simulate, analyse, write ``metrics.json``, the signal table and
plots into an output folder."""
from __future__ import annotations

import importlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .build import build_system
from .errors import ComputationError, Interrupted, Terminated, critical
from .engine import RunError, Simulation
from .observers import Progress
from .recording import Recording
from .resolver import resolve
from .results import SignalWriter, atomic_write, read_table, write_json
from .study import Study, StudyError


class AnalysisError(ComputationError):
    """The study's analysis could not compute its metrics (the signals are kept)."""


@dataclass
class RunResult:
    metrics: dict[str, Any]
    frame: Any
    summary: str
    files: list[Path]


def _analysis(study: Study):
    if not study.study.analysis:
        return None
    try:
        return importlib.import_module(study.study.analysis)
    except ModuleNotFoundError as exc:
        raise StudyError(f"{study.path}: study.analysis: cannot import {study.study.analysis!r} ({exc})") from None


def simulate(study: Study):
    """Build and simulate; returns (recording, system). Raises StudyError / RunError."""
    system = build_system(resolve(study))
    return Simulation(system).run(), system


def _run_facts(rec: Recording) -> dict[str, Any]:
    """Real-time statistics, the number of logged events and who ended the run early (a
    component's terminate request), for metrics.json."""
    facts: dict[str, Any] = {"events": len(rec.events)}
    if rec.realtime is not None:
        facts["realtime"] = rec.realtime
    if rec.ended_by is not None:
        facts["ended_by"] = rec.ended_by
    return facts


def _status(rec: Recording) -> str:
    """'completed', or 'ended' when a component asked to end the run before the stop time."""
    return "ended" if rec.ended_by is not None else "completed"


def _t_end(study: Study, rec: Recording) -> float:
    return rec.ended_by["t"] if rec.ended_by is not None else study.study.stop_time


def write_events(out_dir: Path, rec: Recording) -> Path:
    """events.log: one line per component event, 't [s]  component  message'."""
    lines = [f"{t:10.3f}  {name}  {msg}" for t, name, msg in rec.events]
    return atomic_write(out_dir / "events.log", lambda p: p.write_text("\n".join(lines) + ("\n" if lines else "")))


CHUNK_STEPS = 10_000          # base steps between two writes of the signal table


def _stream(sim: Simulation, writer) -> Recording:
    """Run ``sim`` to its stop time, writing the signal table block by block. An interrupt outside
    the engine's step loop becomes the same RunError as one inside it (with the rows not yet
    written); draining and writing a block is never cut in half (errors.critical)."""
    step = max(1, CHUNK_STEPS // sim.chunk_period) * sim.chunk_period
    try:
        sim.start()
        while sim.k < sim.n_steps:
            sim.advance(min(sim.k + step, sim.n_steps))
            with critical():
                if sim.k % sim.chunk_period == 0:
                    writer.append(sim.drain())
        with critical():
            rec = sim.finish()
            writer.append(rec.data)
        return rec
    except KeyboardInterrupt as exc:
        raise RunError(f"at t = {sim.t0 + sim.k * sim.h:.6g} s: interrupted", sim.partial()) from exc


def run_study(study: Study, out_dir: Path | None, plots: bool = True, overwrite: bool = False) -> RunResult:
    """Simulate and analyse ``study``. With ``out_dir``: the output folder is checked and locked
    before anything runs (orchestrator.output), the signals are streamed into a fresh folder beside
    it, and the folder is moved into place at the end (completed, interrupted or failed: see
    ResultFolder). An interrupt (SIGINT/SIGTERM) keeps every row up to the instant and raises
    Interrupted (exit 130/143)."""
    if out_dir is None:
        return _run_in_memory(study, plots)
    from .output import ResultFolder

    analysis = _analysis(study)
    folder = ResultFolder(Path(out_dir), overwrite)
    system = build_system(resolve(study))
    base = _base_facts(study)
    with folder:
        tmp = folder.tmp
        sim = Simulation(system)
        writer = SignalWriter(tmp / "signals", sim.columns, study.study.signals_format)
        progress = Progress(sim.n_steps, sim.h)
        sim.add_observer(progress)
        try:
            rec = _stream(sim, writer)
        except RunError as err:
            interrupt = err.__cause__ if isinstance(err.__cause__, KeyboardInterrupt) else None
            writer.append(err.partial.data)
            writer.close()
            write_events(tmp, err.partial)
            status = "interrupted" if interrupt is not None else "failed"
            t_reached = study.study.start_time + (writer.rows - 1) * sim.h if writer.rows else study.study.start_time
            facts = {**base, "status": status, "t_reached_s": t_reached, "wall_time_s": err.partial.wall_time_s,
                     **_run_facts(err.partial)}
            if interrupt is None:
                facts["error"] = str(err)
            write_json(tmp / "metrics.json", facts)
            write_json(tmp / "run.json", _run_json(study, system, status, t_reached))
            where = folder.commit(status)
            if interrupt is not None:
                code = 143 if isinstance(interrupt, Terminated) else 130
                raise Interrupted(f"at t = {t_reached:.6g} s; the signals up to then are in {where}", code) from None
            err.where = where
            raise
        finally:
            progress.close()
            sim.terminate()
        files = [writer.close(), write_events(tmp, rec)]
        frame = read_table(writer.path)
        try:
            values = _metrics(analysis, frame, study)
        except AnalysisError as exc:
            write_json(tmp / "metrics.json", {**base, "status": "analysis_failed", "error": str(exc),
                                              "wall_time_s": rec.wall_time_s, **_run_facts(rec)})
            write_json(tmp / "run.json", _run_json(study, system, "analysis_failed", _t_end(study, rec)))
            exc.where = folder.commit("analysis_failed")
            raise
        values.update(sim_time_s=base["sim_time_s"], wall_time_s=rec.wall_time_s, **_run_facts(rec))
        metrics = {**base, "status": _status(rec), **values}
        files.append(write_json(tmp / "metrics.json", metrics))
        files.append(write_json(tmp / "run.json", _run_json(study, system, _status(rec), _t_end(study, rec))))
        if plots and analysis is not None and hasattr(analysis, "plots"):
            files.extend(analysis.plots(frame, study, tmp))
        where = folder.commit("completed")   # an ended run (terminate request) is a clean result too
    return RunResult(metrics, frame, _summary(analysis, values), [where / f.relative_to(tmp) for f in files])


def _base_facts(study: Study) -> dict[str, Any]:
    return {"study": study.study.name, "study_file": str(study.path), "seed": study.study.seed,
            "sim_time_s": study.study.stop_time - study.study.start_time}


def _run_json(study: Study, system, status: str, t_reached: float) -> dict[str, Any]:
    return {"status": status, "t_reached_s": t_reached, "study": study.to_data(),
            "unconnected_inputs": system.unconnected_inputs, "order_sampled": [n.name for n in system.sampled_order]}


def _metrics(analysis, frame, study: Study) -> dict[str, Any]:
    if analysis is None:
        return {}
    try:
        return dict(analysis.metrics(frame, study))
    except (ValueError, KeyError) as exc:
        raise AnalysisError(f"{study.path}: study.analysis {study.study.analysis!r}: {exc}") from None


def _summary(analysis, values: dict) -> str:
    return analysis.summary(values) if analysis is not None and hasattr(analysis, "summary") else \
        json.dumps(values, indent=2)


def _run_in_memory(study: Study, plots: bool) -> RunResult:
    """No output folder: simulate, analyse, return (sweep points, tests)."""
    analysis = _analysis(study)
    rec = Simulation(build_system(resolve(study))).run()
    frame = rec.to_frame()
    values = _metrics(analysis, frame, study)
    base = _base_facts(study)
    values.update(sim_time_s=base["sim_time_s"], wall_time_s=rec.wall_time_s, **_run_facts(rec))
    return RunResult({**base, "status": _status(rec), **values}, frame, _summary(analysis, values), [])
