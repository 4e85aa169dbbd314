"""Run a study end to end: build, simulate, analyse, write ``metrics.json``, the signal table and
plots into an output folder."""
from __future__ import annotations

import importlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .build import build_system
from .errors import ComputationError
from .engine import Recording, RunError, Simulation
from .results import atomic_write, write_json, write_table
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
    system = build_system(study)
    return Simulation(system).run(), system


def _run_facts(rec: Recording) -> dict[str, Any]:
    """Real-time statistics and the number of logged events, for metrics.json."""
    facts: dict[str, Any] = {"events": len(rec.events)}
    if rec.realtime is not None:
        facts["realtime"] = rec.realtime
    return facts


def write_events(out_dir: Path, rec: Recording) -> Path:
    """events.log: one line per component event, 't [s]  component  message'."""
    lines = [f"{t:10.3f}  {name}  {msg}" for t, name, msg in rec.events]
    return atomic_write(out_dir / "events.log", lambda p: p.write_text("\n".join(lines) + ("\n" if lines else "")))


def run_study(study: Study, out_dir: Path | None, plots: bool = True) -> RunResult:
    analysis = _analysis(study)
    out_dir = Path(out_dir) if out_dir is not None else None
    fmt = study.study.signals_format
    system = build_system(study)
    base = {"study": study.study.name, "study_file": str(study.path), "seed": study.study.seed,
            "sim_time_s": study.study.stop_time - study.study.start_time}
    try:
        rec = Simulation(system).run()
    except RunError as err:
        if out_dir is not None:
            write_table(out_dir / "signals", err.partial.to_frame(), fmt)
            write_events(out_dir, err.partial)
            write_json(out_dir / "metrics.json", {**base, "status": "failed", "error": str(err),
                                                   "wall_time_s": err.partial.wall_time_s,
                                                   **_run_facts(err.partial)})
        raise
    frame = rec.to_frame()
    files: list[Path] = []
    if out_dir is not None:
        files.append(write_table(out_dir / "signals", frame, fmt))
        files.append(write_events(out_dir, rec))
    values: dict[str, Any] = {}
    if analysis is not None:
        try:
            values.update(analysis.metrics(frame, study))
        except (ValueError, KeyError) as exc:
            if out_dir is not None:
                write_json(out_dir / "metrics.json", {**base, "status": "analysis_failed", "error": str(exc),
                                                       "wall_time_s": rec.wall_time_s, **_run_facts(rec)})
            raise AnalysisError(f"{study.path}: study.analysis {study.study.analysis!r}: {exc}") from None
    values.update(sim_time_s=base["sim_time_s"], wall_time_s=rec.wall_time_s, **_run_facts(rec))
    metrics = {**base, "status": "completed", **values}
    summary = analysis.summary(values) if analysis is not None and hasattr(analysis, "summary") else \
        json.dumps(values, indent=2)
    if out_dir is not None:
        files.append(write_json(out_dir / "metrics.json", metrics))
        files.append(write_json(out_dir / "run.json", {
            "study": study.to_data(),
            "unconnected_inputs": system.unconnected_inputs,
            "order_sampled": [n.name for n in system.sampled_order],
        }))
        if plots and analysis is not None and hasattr(analysis, "plots"):
            files.extend(analysis.plots(frame, study, out_dir))
    return RunResult(metrics, frame, summary, files)
