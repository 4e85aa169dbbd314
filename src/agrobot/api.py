"""The project from Python: one function per command, each returning a typed result
(agrobot.results) that holds its data in memory; ``out=FOLDER`` also writes what the command
writes (or call the result's ``save(folder)`` later).

    run(study, set=..., out=None)        -> RunResult       a study's run, judged against its bounds
    sweep(study, set=..., out=None)      -> SweepResult     every point of its [sweep] section
    identify(source, ...)                -> Identification  yaw dynamics from a study or a log
    diagnose(log, study=None, out=None)  -> Diagnosis       what the simulation gets wrong about a log
    convert(source, ...)                 -> Recording       a raw recording as a measured log
    plan(field, ...)                     -> PlanResult      a coverage plan of a field
    margins(study)                       -> LoopMargins     the guidance loop's stability margins

A study is a study file's path, a shipped study's name (``"figure8"``: agrobot.studies) or a
``Study``; ``set`` maps dotted keys to values (``{"tracker.lookahead": 3.0, "study.stop_time": 30}``,
as ``--set`` on the command line).
"""
from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any, Mapping

from .results import (Diagnosis, Identification, LoopMargins, PlanResult, Recording, RunResult, SweepResult,
                      judged_metrics)

STUDY_SUFFIXES = (".toml", ".yaml", ".yml")


def shipped_name(study) -> bool:
    """A bare name of a shipped study (``"figure8"``: no suffix, no folder), which wins over a file
    or folder of that name in the working folder (write ``"./figure8"`` for that)."""
    from agrobot.studies import shipped

    return isinstance(study, str) and "/" not in study and not Path(study).suffix \
        and shipped(f"{study}.toml").is_file()


def load(study, set: Mapping[str, Any] | None = None):
    """The Study named by ``study`` (a path, a shipped study's name, or a Study) with ``set`` applied."""
    from agrobot.orchestrator.study import Study, StudyError
    from agrobot.studies import shipped

    if not isinstance(study, Study):
        if shipped_name(study):
            study = shipped(f"{study}.toml")
        elif Path(study).suffix not in STUDY_SUFFIXES and not Path(study).exists():
            names = sorted(p.stem for p in shipped().glob("*.toml"))
            raise StudyError(f"{study}: no such study file, nor a shipped study (shipped: {', '.join(names)})")
        study = Study.load(study)
    return study.with_values(dict(set)) if set else study


def run(study, set: Mapping[str, Any] | None = None, out: str | Path | None = None, *, plots: bool = True,
        overwrite: bool = False, progress: bool = False) -> RunResult:
    """Simulate and analyse a study. Without ``out`` nothing is written; with it, the run is
    recorded there as ``run --out`` does (signals streamed, metrics.json, figures)."""
    from agrobot.orchestrator.runner import run_study

    study = load(study, set)
    done = run_study(study, Path(out) if out is not None else None, plots=plots and out is not None,
                     overwrite=overwrite, progress=progress)
    signals = done.frame if out is None else done.frame.to_pandas()
    return RunResult(study, signals, judged_metrics(done.metrics, study), dict(done.metrics), done.summary,
                     list(done.warnings), Path(out) if out is not None else None)


def sweep(study, set: Mapping[str, Any] | None = None, out: str | Path | None = None, *, workers: int = 1,
          scheduler: str | None = None, retry_failed: bool = False, progress: bool = False,
          plots: bool = False) -> SweepResult:
    """Every point of the study's [sweep] section, on ``workers`` processes (or a Dask
    ``scheduler``). ``out`` keeps the points (rerun to resume); without it they go to a temporary
    folder removed at the end."""
    from agrobot.orchestrator.sweep import SweepRun, sweep_plots, sweep_summary

    study = load(study, set)
    if out is None:
        with tempfile.TemporaryDirectory(prefix="agrobot-sweep-") as tmp:
            table = SweepRun(study, Path(tmp) / "sweep").run(workers, scheduler, retry_failed, progress=progress)
        return SweepResult(study, table, sweep_summary(study, table)[0])
    table = SweepRun(study, Path(out)).run(workers, scheduler, retry_failed, progress=progress)
    if plots:
        sweep_plots(study, table, Path(out) / "plots")
    return SweepResult(study, table, sweep_summary(study, table)[0], Path(out))


def identify(source, *, study=None, method: str = "auto", set: Mapping[str, Any] | None = None,
             period: float | None = None, speed: float | None = None, band: tuple[float, float] | None = None,
             models: list[str] | None = None, delay: bool = False, resample: bool = False, recording=None,
             out: str | Path | None = None, plots: bool = True, progress=None) -> Identification:
    """Identify the yaw dynamics. ``source`` a study (its multisine experiment, simulated: ``set``
    applies to it) or a measured log or raw recording; for a log the method is chosen as the
    command chooses it (identification.from_log.choose_method: ``"auto"`` is multisine when
    delta_cmd repeats with a period, else ordinary driving). ``study``: the vehicle a log comes
    from (path, name or Study), default the paper's tractor. ``recording``: a
    measurements.ImportOptions for a raw recording."""
    from agrobot.identification.from_log import choose_method, driving_report, write_driving
    from agrobot.identification.pipeline import identify_log, identify_study

    if out is not None:
        from agrobot.orchestrator.output import check_output

        check_output(Path(out), overwrite=True)

    is_study = not isinstance(source, (str, Path)) or Path(source).suffix in STUDY_SUFFIXES or shipped_name(source)
    if is_study:
        vehicle = load(source, set)
        report = identify_study(vehicle, Path(out) if out is not None else None, plots)
        return Identification(str(vehicle.path), "study", report, vehicle)
    vehicle = load(study) if study is not None else None
    chosen = choose_method(Path(source), method, resample, recording, vehicle)
    if chosen == "driving":
        report, figures = driving_report(Path(source), vehicle, resample, recording, progress)
        result = Identification(str(source), chosen, report, vehicle, figures)
        if out is not None:
            write_driving(report, figures, Path(out), vehicle, source, plots, progress)
        return result
    report = identify_log(Path(source), Path(out) if out is not None else None, period, speed,
                          tuple(band) if band else None, models, delay, plots=plots, resample=resample,
                          recording=recording, study=vehicle)
    return Identification(str(source), chosen, report, vehicle)


def diagnose(log, study=None, out: str | Path | None = None, *, fit_fraction: float = 0.6, min_gain: float = 0.05,
             resample: bool = False, recording=None, plots: bool = True, progress=None,
             identify: bool = True, split: str = "auto") -> Diagnosis:
    """Name what the simulation of ``study`` (a study file or a shipped study's name; default
    figure8) gets wrong about a measured log. Without ``out`` nothing is written; with it,
    diagnosis.json, report.md, the figures and extended_study.toml go there. A log that cannot be
    judged gives the verdict ``"cannot decide"`` with its ``reason``. ``identify``: identify the
    vehicle on the same log first (one vehicle model for both; False is faster). ``split``: what
    is held out, "tail" (the last 1 - ``fit_fraction``), "blocks" (every third 10 s) or "auto"
    (blocks when the last part is driven beyond the first's conditions)."""
    from agrobot.diagnosis.candidates import SPLITS
    from agrobot.diagnosis.pipeline import diagnose as run_diagnosis
    from agrobot.orchestrator.study import StudyError

    if not 0.2 <= fit_fraction <= 0.8:
        raise StudyError(f"fit_fraction {fit_fraction:g}: expected a share in [0.2, 0.8]")
    if split not in SPLITS:
        raise StudyError(f"split {split!r}: expected one of {', '.join(SPLITS)}")
    path = None if study is None else load(study).path
    if out is not None:
        from agrobot.orchestrator.output import check_output

        check_output(Path(out), overwrite=True)
    result = run_diagnosis(log, Path(out) if out is not None else None, path, fit_fraction, min_gain,
                           plots=plots, resample=resample, recording=recording, progress=progress,
                           identify=identify, split=split)
    return Diagnosis(result, Path(out) if out is not None else None)


def convert(source, out: str | Path | None = None, *, options=None, **fields) -> Recording:
    """Read a raw recording (NMEA, CAN, ROS bag, ISO 11783-10 time log, tables) as a measured log.
    ``options`` a measurements.ImportOptions, or its fields as keywords (``dbc=``, ``signals=``,
    ``run=``, ``time_range=`` ...). With ``out`` (.csv or .parquet) the log and its import report
    are written as ``convert --out`` writes them."""
    from dataclasses import replace

    from agrobot.measurements.log import check_log
    from agrobot.measurements.options import ImportOptions
    from agrobot.measurements.recording import import_recording

    options = replace(options or ImportOptions(), **fields)
    log, report = import_recording(source, options)
    check_log(log, f"{source} ({report['used']['how']})", ("t",))
    result = Recording(str(source), log, report)
    if out is not None:
        result.save(out)
    return result


def plan(field, *, name: str | None = None, crs: str | None = None, sections: int = 0, obstacles=(),
         out: str | Path | None = None, **settings) -> PlanResult:
    """A coverage plan of ``field`` (a field file or folder, or a fields.Field): ``settings`` are
    fields.planner.Settings' fields in SI units (``working_width=6.0``, ``driving_angle`` in
    radians, ``order="optimised"`` ...); ``obstacles`` round ones as (east, north, radius) in m, or a
    GeoJSON file's path; ``sections`` the implement's sections for the as-applied figures."""
    from agrobot.fields.field import Field
    from agrobot.fields.obstacles import circle, read_obstacles, with_obstacles
    from agrobot.fields.plan_cli import read_field
    from agrobot.fields.planner import plan as make_plan
    from agrobot.fields.planner.applied import as_applied, summary as applied_summary
    from agrobot.fields.planner.sections import check_sections
    from agrobot.fields.planner.settings import Settings

    chosen = Settings(**settings)
    chosen.check("plan")
    sections = check_sections(sections, chosen.working_width, "plan: sections") if sections else 0
    skipped: list[str] = []
    if not isinstance(field, Field):
        field, skipped = read_field(Path(field), crs, name)
    if isinstance(obstacles, (str, Path)):
        found = read_obstacles(Path(obstacles), field)
    else:
        found = [circle(f"obstacle {k + 1}", x, y, r, "plan: obstacles") for k, (x, y, r) in enumerate(obstacles)]
    field = with_obstacles(field, found)
    made = make_plan(field, chosen)
    applied = as_applied(made, sections)
    summary = made.summary() | {"not_read": skipped, "obstacles": [ob.name for ob in found],
                                "as_applied": applied_summary(made, applied, sections)}
    result = PlanResult(made, summary, applied, sections)
    if out is not None:
        result.save(out)
    return result


def margins(study, set: Mapping[str, Any] | None = None, out: str | Path | None = None, *,
            progress=None) -> LoopMargins:
    """Gain, phase and delay margins of the study's guidance loop, linearised from its own
    components (analysis.margins); ``out`` writes margins.json and the Bode and Nyquist plots."""
    from agrobot.analysis.margins import analyse

    result = LoopMargins(analyse(load(study, set), progress=progress))
    if out is not None:
        result.save(out)
    return result
