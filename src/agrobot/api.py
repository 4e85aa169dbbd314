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
    tune(study, out=...)                 -> TunedStudy      tracker gains that meet margin targets
    fields(source)                       -> FieldsResult    the fields of a file, a folder or a GNSS track
    export_controller(study, out=...)    -> ExportedFile    the guidance controller as an FMU
    export_fmu(study, out=...)           -> ExportedFile    the whole loop (or a subsystem) as one FMU
    export_ssp(study, out=...)           -> ExportedFile    the study as an SSP archive
    emulate(study, nmea_port)            -> EmulationResult the hardware emulator, run to its end
    load_result(path)                    -> the typed result a command's --out (or save) wrote there
                                                            (agrobot.results)

A study is a study file's path, a shipped study's name (``"figure8"``: agrobot.studies) or a
``Study``; ``set`` maps dotted keys to values (``{"tracker.lookahead": 3.0, "study.stop_time": 30}``),
or lists ``key=value`` strings as ``--set`` on the command line writes them.

Each function imports its own command's package where it is used, so that ``from agrobot import run``
and each command that goes through this module load no other command's package (1.2 s of them together).

Imported where used: agrobot.identification (start-up: 0.6 s), agrobot.diagnosis (1.0 s), agrobot.fields (0.6 s,
the planner), agrobot.measurements (0.2 s), agrobot.analysis (0.2 s), agrobot.fmu_export (0.25 s, fmpy),
and agrobot.components.hardware (the emulator's buses).
"""
from __future__ import annotations

import json
import math
import os
import sys
import tempfile
from contextlib import nullcontext
from dataclasses import replace
from pathlib import Path
from typing import Any, Mapping, Sequence

import pandas as pd

from agrobot.orchestrator.engine import RunError
from agrobot.orchestrator.errors import InputError, Interrupted, Terminated, install_signal_handlers
from agrobot.orchestrator.observers import Stage
from agrobot.orchestrator.output import study_inputs
from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.source_files import set_limit
from agrobot.orchestrator.study import Study, StudyError
from agrobot.orchestrator.sweep import SweepRun, sweep_plots, sweep_summary
from agrobot.studies import shipped

from .results import (Diagnosis, EmulationResult, ExportedFile, FieldsResult, Identification, LoopMargins,
                      PlanResult, Recording, RunResult, SweepResult, TunedStudy, check_file, judged_metrics)

STUDY_SUFFIXES = (".toml", ".yaml", ".yml")


def shipped_name(study) -> bool:
    """A bare name of a shipped study (``"figure8"``: no suffix, no folder), which wins over a file
    or folder of that name in the working folder (write ``"./figure8"`` for that)."""
    return isinstance(study, str) and "/" not in study and not Path(study).suffix \
        and shipped(f"{study}.toml").is_file()


def load(study, set: Mapping[str, Any] | Sequence[str] | None = None):
    """The Study named by ``study`` (a path, a shipped study's name, or a Study) with ``set`` applied:
    a mapping of values, or ``key=value`` strings as ``--set`` writes them (parsed and reported as the
    command line does)."""
    if not isinstance(study, Study):
        if shipped_name(study):
            study = shipped(f"{study}.toml")
        elif Path(study).suffix not in STUDY_SUFFIXES and not Path(study).exists():
            names = sorted(p.stem for p in shipped().glob("*.toml"))
            raise StudyError(f"{study}: no such study file, nor a shipped study (shipped: {', '.join(names)})")
        study = Study.load(study)
    if not set:
        return study
    if not isinstance(set, Mapping) and all(isinstance(item, str) for item in set):
        return study.with_overrides(list(set))
    return study.with_values(dict(set))


def run(study, set: Mapping[str, Any] | None = None, out: str | Path | None = None, *, plots: bool = True,
        overwrite: bool = False, progress: bool = False, engine: str = "auto") -> RunResult:
    """Simulate and analyse a study. Without ``out`` nothing is written (``save`` writes it
    later); with it, the run is recorded there as ``run --out`` does (signals streamed, events.log,
    run.json, metrics.json, figures) under the output rule (orchestrator.output). ``engine``: as
    ``run --engine`` (auto: the compiled engine where it can, saying which ran and why; python)."""
    study = load(study, set)
    done = run_study(study, Path(out) if out is not None else None, plots=plots and out is not None,
                     overwrite=overwrite, progress=progress, engine=engine)
    if out is None:
        return RunResult(study, done.frame, judged_metrics(done.metrics, study), dict(done.metrics), done.summary,
                         list(done.warnings), None, dict(done.record or {}), done.events)
    folder = Path(out)
    return RunResult(study, done.frame.to_pandas(), judged_metrics(done.metrics, study), dict(done.metrics),
                     done.summary, list(done.warnings), folder, json.loads((folder / "run.json").read_text()),
                     (folder / "events.log").read_text())


def sweep(study, set: Mapping[str, Any] | None = None, out: str | Path | None = None, *, workers: int | None = None,
          scheduler: str | None = None, retry_failed: bool = False, progress: bool = False,
          plots: bool = False, engine: str = "auto", keep_signals: bool | str | None = None,
          overwrite: bool = False, accept_cost: bool = False) -> SweepResult:
    """Every point of the study's [sweep] section, on ``workers`` processes (default: every core,
    as ``sweep`` does) or a Dask ``scheduler``, with ``engine`` (as ``--engine``; ``keep_signals``
    True, False, "all", "worst" or "none" as ``--keep-signals``; ``accept_cost`` as ``--accept-cost``).
    ``out`` keeps the points (rerun to resume); without it they go to a temporary folder removed at
    the end. Works from any script, one read from standard input included."""
    study = load(study, set)
    workers = os.cpu_count() or 1 if workers is None else workers
    if workers < 1:
        raise StudyError(f"workers={workers}: must be >= 1")
    if out is None:
        with tempfile.TemporaryDirectory(prefix="agrobot-sweep-") as tmp:
            runner = SweepRun(study, Path(tmp) / "sweep", engine=engine, keep_signals=keep_signals,
                              accept_cost=accept_cost)
            table = runner.run(workers, scheduler, retry_failed, progress=progress)
        return SweepResult(study, table, sweep_summary(study, table, runner.nominal)[0], None, engine, runner.nominal)
    runner = SweepRun(study, Path(out), overwrite, engine=engine, keep_signals=keep_signals, accept_cost=accept_cost)
    table = runner.run(workers, scheduler, retry_failed, progress=progress)
    if plots:
        sweep_plots(study, table, Path(out) / "plots", runner.nominal)
    return SweepResult(study, table, sweep_summary(study, table, runner.nominal)[0], Path(out), engine, runner.nominal)


def identify(source, *, study=None, method: str = "auto", set: Mapping[str, Any] | None = None,
             period: float | None = None, speed: float | None = None, band: tuple[float, float] | None = None,
             models: list[str] | None = None, delay: bool = False, resample: bool = False, recording=None,
             out: str | Path | None = None, plots: bool = True, progress=None,
             overwrite: bool = False, where: str | None = None, keep_unexplained: bool = False,
             course_speed: float | None = None, fit_seconds: float | None = None,
             steering_geometry: str = "auto", input_hold: str = "auto") -> Identification:
    """Identify the yaw dynamics. ``source`` a study (its multisine experiment, simulated: ``set``
    applies to it) or a measured log or raw recording; for a log the method is chosen as the
    command chooses it (identification.from_log.choose_method: ``"auto"`` is multisine when
    delta_cmd repeats with a period, else ordinary driving). ``study``: the vehicle a log comes
    from (path, name or Study), default the paper's tractor. ``recording``: a
    measurements.ImportOptions for a raw recording. ``where``/``keep_unexplained``: the stretches
    judged (measurements.modes, the ``--where`` option). ``out``: checked before anything is computed,
    written as ``Identification.save`` writes. ``course_speed``: the speed [m/s] above which the
    GNSS course measures the yaw (driving method; None: the log's own, yaw_measurement.course_floor).
    ``fit_seconds``: at most this much of the log's segments fitted (driving method; None: 300 s; identification.ordinary_driving).
    ``steering_geometry``: how the wheel angle w drives the single-track model, "w", "tan" or
    "auto" (the better of the two where w reaches 0.17 rad; driving method). ``input_hold``: how the
    steering input is read between its rows, "zoh" (held), "linear" or "auto" (linear; driving
    method; identification.driving.input_hold)."""
    from agrobot.identification.from_log import choose_method, driving_report, write_driving
    from agrobot.identification.pipeline import log_identification, study_identification

    check_identify(band, speed, period, course_speed, fit_seconds)
    if steering_geometry not in ("auto", "w", "tan"):
        raise StudyError(f"--steering-geometry {steering_geometry}: expected auto, w or tan")
    if input_hold not in ("auto", "zoh", "linear"):
        raise StudyError(f"--input-hold {input_hold}: expected auto, zoh or linear")
    recording = _stretches(recording, where, keep_unexplained)
    is_study = not isinstance(source, (str, Path)) or Path(source).suffix in STUDY_SUFFIXES or shipped_name(source)
    vehicle = load(source, set) if is_study else load(study) if study is not None else None
    inputs = [source, *study_inputs(vehicle), getattr(recording, "dbc", None)] if isinstance(source, (str, Path)) \
        else study_inputs(vehicle)
    if out is not None:
        Identification.check(out, overwrite, inputs)
    if is_study:
        report, write = study_identification(vehicle)
        result = Identification(str(vehicle.path), "study", report, vehicle, write, inputs)
    else:
        chosen = _named(source, choose_method, Path(source), method, resample, recording, vehicle)
        if chosen == "driving":
            report, figures = driving_report(Path(source), vehicle, resample, recording, progress, course_speed,
                                             fit_seconds, steering_geometry, input_hold)

            def write(tmp: Path, plots: bool) -> None:
                write_driving(report, figures, tmp, vehicle, source, plots, progress)
        else:
            report, write = _named(source, log_identification, Path(source), period, speed,
                                   tuple(band) if band else None, models, delay, resample, recording, vehicle)
        result = Identification(str(source), chosen, report, vehicle, write, inputs)
    if out is not None:
        result.save(out, overwrite, plots)
    return result


def _stretches(recording, where: str | None, keep_unexplained: bool):
    """The recording options with the stretches judged (measurements.modes); ``where`` checked."""
    if where is None and not keep_unexplained:
        return recording
    from agrobot.measurements.modes import parse_where
    from agrobot.measurements.options import ImportOptions

    if where is not None:
        parse_where(where)
    return replace(recording or ImportOptions(), where=where, keep_unexplained=keep_unexplained)


def check_identify(band, speed, period, course_speed=None, fit_seconds=None) -> None:
    """The identification's numbers: 0 < F_MIN < F_MAX, a positive speed, period, course speed and
    fitted seconds."""
    if band is not None and not 0 < band[0] < band[1]:
        raise StudyError(f"--band {band[0]:g} {band[1]:g}: expected 0 < F_MIN < F_MAX [Hz]")
    for option, value in (("--speed", speed), ("--period", period), ("--course-speed", course_speed),
                          ("--fit-seconds", fit_seconds)):
        if value is not None and not value > 0:
            raise StudyError(f"{option} {value:g}: expected a positive number")


def _named(source, compute, *args):
    """``compute(*args)``, a ValueError (an unknown method or model structure) as a StudyError
    naming ``source``."""
    try:
        return compute(*args)
    except ValueError as exc:
        if isinstance(exc, InputError):       # a LogError is both
            raise
        raise StudyError(f"{source}: {exc}") from None


def diagnose(log, study=None, out: str | Path | None = None, *, fit_fraction: float = 0.6, min_gain: float = 0.05,
             resample: bool = False, recording=None, plots: bool = True, progress=None,
             identify: bool = True, split: str = "auto", overwrite: bool = False, mcap: bool = False,
             where: str | None = None, keep_unexplained: bool = False, workers: int | None = None,
             screen: bool = True, steering_geometry: str = "auto") -> Diagnosis:
    """Name what the simulation of ``study`` (a study file or a shipped study's name; default
    figure8) gets wrong about a measured log. Without ``out`` nothing is written; with it (checked
    before anything is computed), diagnosis.json, report.md, the figures and extended_study.toml go
    there as ``Diagnosis.save`` writes them. A log that cannot be judged gives the verdict
    ``"cannot decide"`` with its ``reason``. ``identify``: identify the vehicle on the same log first
    (one vehicle model for both; False is faster). ``split``: what is held out, "tail" (the last
    1 - ``fit_fraction``), "blocks" (every third 10 s) or "auto" (blocks when the last part is
    driven beyond the first's conditions). ``mcap``: diagnosis.mcap too. ``where``/``keep_unexplained``:
    the stretches judged (measurements.modes, the ``--where`` option). ``workers``: processes for the
    candidate fits (default: every core; the result is the same whatever their number). ``screen``: False
    fits every pair of effects, also those the linearised screen rules out (diagnosis.screen).
    ``steering_geometry``: the yaw model driven by the wheel angle ("w") or its tangent ("tan"); "auto":
    the study's, else the one identify chooses (diagnosis.baseline.geometry_choice)."""
    from agrobot.diagnosis.candidates import SPLITS
    from agrobot.diagnosis.pipeline import diagnosis

    if not 0.2 <= fit_fraction <= 0.8:
        raise StudyError(f"--fit-fraction {fit_fraction:g}: expected a share in [0.2, 0.8]")
    if split not in SPLITS:
        raise StudyError(f"split {split!r}: expected one of {', '.join(SPLITS)}")
    if workers is not None and (not isinstance(workers, int) or workers < 1):
        raise StudyError(f"--workers {workers!r}: expected a whole number of processes, at least 1")
    if steering_geometry not in ("auto", "w", "tan"):
        raise StudyError(f"--steering-geometry {steering_geometry}: expected auto, w or tan")
    baseline = None if study is None else load(study)
    recording = _stretches(recording, where, keep_unexplained)
    inputs = [log, getattr(recording, "dbc", None), *study_inputs(baseline)]
    if out is not None:
        Diagnosis.check(out, overwrite, inputs)
    found, write = diagnosis(log, None if baseline is None else baseline.path, fit_fraction, min_gain, plots=plots,
                             resample=resample, recording=recording, progress=progress, identify=identify,
                             mcap=mcap, split=split, workers=workers, screen=screen,
                             steering_geometry=steering_geometry)
    result = Diagnosis(found, None, write, inputs)
    if out is not None:
        result.save(out, overwrite)
    return result


def convert(source, out: str | Path | None = None, *, options=None, overwrite: bool = False, **fields) -> Recording:
    """Read a raw recording (NMEA, CAN, ROS bag, ISO 11783-10 time log, tables) as a measured log.
    ``options`` a measurements.ImportOptions, or its fields as keywords (``dbc=``, ``signals=``,
    ``run=``, ``time_range=`` ...). With ``out`` (.csv or .parquet) the log and its import report
    are written as ``convert --out`` writes them."""
    from agrobot.measurements.cli import checked_log
    from agrobot.measurements.options import ImportOptions
    from agrobot.measurements.recording import import_recording

    options = replace(options or ImportOptions(), **fields)
    inputs = [source, options.dbc]
    if out is not None:
        check_file(out, (".csv", ".parquet"), overwrite, inputs)
    log, report = import_recording(source, options)
    checked_log(source, log, report)
    result = Recording(str(source), log, report, [options.dbc])
    if out is not None:
        result.save(out, overwrite)
    return result


def plan(field, *, name: str | None = None, crs: str | None = None, sections: int = 0, obstacles=(),
         out: str | Path | None = None, overwrite: bool = False, route_step: float | None = None,
         route_uniform: bool = False, option_names: dict[str, str] | None = None, **settings) -> PlanResult:
    """A coverage plan of ``field`` (a field file or folder, or a fields.Field): ``settings`` are
    fields.planner.Settings' fields in SI units (``working_width=6.0``, ``driving_angle`` in
    radians, ``order="optimised"`` ...); ``obstacles`` round ones as (east, north, radius) in m or
    fields.obstacles.Obstacle, and GeoJSON files' paths; ``sections`` the implement's sections for
    the as-applied figures. ``out``: checked before anything is computed, written as
    ``PlanResult.save`` writes (``route_step``, ``route_uniform``); ``option_names``: how the caller
    calls each setting, for the messages."""
    from agrobot.fields.field import Field, FieldError
    from agrobot.fields.planner.sections import check_sections
    from agrobot.fields.planner.settings import Settings

    given = [obstacles] if isinstance(obstacles, (str, Path)) else list(obstacles)
    inputs = [] if isinstance(field, Field) else [field, *[o for o in given if isinstance(o, (str, Path))]]
    if out is not None:
        PlanResult.check(out, overwrite, inputs)
    if route_step is not None and not route_step > 0:
        raise FieldError(f"--route-step {route_step:g}: expected a positive number of metres")
    chosen = Settings(**settings)
    chosen.check("plan", option_names)
    where = "plan: --sections" if option_names else "plan: sections"
    sections = check_sections(sections, chosen.working_width, where) if sections else 0
    result = _plan(field, crs, name, given, chosen, sections)
    result.inputs = inputs
    if out is not None:
        result.save(out, overwrite, route_step, route_uniform)
    return result


def _plan(field, crs, name, obstacles: list, chosen, sections: int) -> PlanResult:
    """The plan of ``field`` with ``obstacles`` (files read against the field, circles, Obstacles)."""
    from agrobot.fields.field import Field
    from agrobot.fields.obstacles import Obstacle, circle, read_obstacles, with_obstacles
    from agrobot.fields.plan_cli import read_field
    from agrobot.fields.planner import plan as make_plan
    from agrobot.fields.planner.applied import as_applied, summary as applied_summary

    skipped: list[str] = []
    if not isinstance(field, Field):
        field, skipped = read_field(Path(field), crs, name)
    found = [ob if isinstance(ob, Obstacle) else circle(f"obstacle {k + 1}", *ob, "plan: obstacles")
             for k, ob in enumerate(o for o in obstacles if not isinstance(o, (str, Path)))]
    for path in (o for o in obstacles if isinstance(o, (str, Path))):
        found += read_obstacles(Path(path), field)
    field = with_obstacles(field, found)
    made = make_plan(field, chosen)
    applied = as_applied(made, sections)
    summary = made.summary() | {"not_read": skipped, "obstacles": [ob.name for ob in found],
                                "as_applied": applied_summary(made, applied, sections)}
    return PlanResult(made, summary, applied, sections)


def margins(study, set: Mapping[str, Any] | Sequence[str] | None = None, out: str | Path | None = None, *,
            progress=None, overwrite: bool = False, plots: bool = True) -> LoopMargins:
    """Gain, phase and delay margins of the study's guidance loop, linearised from its own
    components (analysis.margins); ``out`` (checked before anything is computed) writes margins.json
    and the Bode and Nyquist plots as ``LoopMargins.save`` writes them."""
    from agrobot.analysis.margins import analyse

    study = load(study, set)
    if out is not None:
        LoopMargins.check(out, overwrite, study_inputs(study))
    result = LoopMargins(analyse(study, progress=progress), study_inputs(study))
    if out is not None:
        result.save(out, overwrite, plots)
    return result


def tune(study, set: Mapping[str, Any] | Sequence[str] | None = None, out: str | Path | None = None, *,
         delay_margin: float | None = None, phase_margin: float | None = None, gain_margin: float | None = None,
         along_track_error: float | None = None, identified: str | Path | None = None, model: str = "second_order",
         grid: float = 1.0, simulate: bool = True, duration: float = 160.0, overwrite: bool = False,
         progress=None) -> TunedStudy:
    """Tracker gains from the study's plant that meet margin targets (analysis.tune): a delay
    margin [s], a phase margin [deg] and a gain margin [dB] at the steering command, and a
    time-based reference's along-track error [m] (None: analysis.tune.Targets' defaults);
    ``identified`` an ``identify`` result (identification.json) whose ``model`` becomes the plant
    and the yaw-rate controller's model; ``grid`` the searched grid's density. ``out`` (a .toml,
    checked before anything is computed) gets the study file that extends the study, as
    ``TunedStudy.save`` writes it; ``simulate`` (as ``tune`` without ``--no-simulation``) then
    checks the proposal in ``duration`` s runs."""
    from agrobot.analysis.tune import Targets, identified_values, propose

    default = Targets()
    targets = Targets(*(default_value if given is None else given for given, default_value in (
        (delay_margin, default.delay), (phase_margin, default.phase_deg), (gain_margin, default.gain_db),
        (along_track_error, default.along_track))))
    check_tune(targets, grid, duration)
    study = load(study, set)
    inputs = [*study_inputs(study), *([identified] if identified is not None else [])]
    if out is not None:
        check_file(out, ".toml", overwrite, inputs)
    values = identified_values(study, identified, model) if identified is not None else None
    result = TunedStudy(propose(study, targets, progress, values, grid), inputs)
    if out is not None:
        result.save(out, overwrite)
    if simulate:
        result.simulate(duration, progress)
    return result


def check_tune(targets, grid: float, duration: float) -> None:
    """tune's numbers: margins >= 0, a positive along-track budget and duration, 0 < grid <= 4."""
    for option, value in (("--delay-margin", targets.delay), ("--phase-margin", targets.phase_deg),
                          ("--gain-margin", targets.gain_db), ("--along-track-error", targets.along_track)):
        if not (math.isfinite(value) and value >= 0):
            raise StudyError(f"{option} {value:g}: expected a number >= 0")
    if not targets.along_track > 0:
        raise StudyError(f"--along-track-error {targets.along_track:g}: expected a positive number of metres")
    if not duration > 0:
        raise StudyError(f"--duration {duration:g}: expected a positive number of seconds")
    if not 0 < grid <= 4:
        raise StudyError(f"--grid {grid:g}: expected a number in (0, 4]")


def fields(source, *, crs: str | None = None, out: str | Path | None = None, overwrite: bool = False,
           plots: bool = True, from_track: bool = False, width: float | None = None, signals: Sequence[str] = (),
           time: str | None = None, max_file_size: str | None = None) -> FieldsResult:
    """The fields a field file or folder holds (GeoJSON, WKT, GML, KML, ISOXML, AgOpenGPS, polygon
    CSV), or with ``from_track`` the field a GNSS track worked (``width`` [m], else the
    recording's; ``signals``/``time`` a table's columns as ``--signal``/``--time`` write them).
    ``out``: checked before anything is read, written as ``FieldsResult.save`` writes."""
    from agrobot.fields.readers import read_fields, read_folder

    set_limit(max_file_size)
    source = Path(source)
    if out is not None:
        FieldsResult.check(out, overwrite, [source])
    if from_track:
        found, track = _track_field(source, width, signals, time)
        result = FieldsResult(str(source), [found], [], track, [source])
    else:
        found, skipped = read_folder(source, crs) if source.is_dir() else (read_fields(source, crs), [])
        result = FieldsResult(str(source), found, skipped, None, [source])
    if out is not None:
        result.save(out, overwrite, plots)
    return result


def _track_field(source: Path, width: float | None, signals: Sequence[str], time: str | None):
    """(the field the track in ``source`` worked, the line that describes the track)."""
    from agrobot.fields.track import field_from_track
    from agrobot.measurements.recording import ImportOptions, positions
    from agrobot.measurements.signal_expressions import parse_signal

    t, lat, lon, report = positions(source, ImportOptions(signals=[parse_signal(s) for s in signals], time=time))
    chosen = width or report.get("working_width_m")
    f = field_from_track(t, lat, lon, source.stem or source.name, str(source), chosen)
    if width is None and chosen is not None:
        f.properties["working_width_from"] = "the recording's ISO 11783 actual working width (DDI 67), median"
    p = f.properties
    return f, (f"track {source}: {p['track_fixes']} fixes in {p['track_pieces']} piece(s), "
               f"{p['track_length_m']:.0f} m; "
               f"working width {p['working_width_m']:g} m ({p['working_width_from']}); {p['passes']} straight passes")


def _export(kind: str, study, out, overwrite: bool, build, stage: str) -> ExportedFile:
    """``build(study)`` -> (bytes, note) under ``Stage(stage)`` (``{name}``: the file's name),
    ``out`` checked before it."""
    inputs = study_inputs(study)
    if out is not None:
        ExportedFile.check(out, kind, overwrite, inputs)
    with Stage(stage.format(name=Path(out).name if out is not None else f"the {kind[1:].upper()}")):
        data, note = build(study)
    result = ExportedFile(kind, data, note, inputs)
    if out is not None:
        result.save(out, overwrite)
    return result


def export_controller(study, set: Mapping[str, Any] | Sequence[str] | None = None, out: str | Path | None = None, *,
                      fmi_version: int = 2, overwrite: bool = False) -> ExportedFile:
    """The study's guidance controller (tracker, yaw-rate MPC, speed PID) as an FMI
    ``fmi_version``.0 co-simulation FMU (fmu_export.controller); ``out`` (a .fmu, checked before
    the build) writes it as ``ExportedFile.save`` does."""
    from agrobot.fmu_export.controller import export_controller as build

    return _export(".fmu", load(study, set), out, overwrite, lambda s: (build(s, fmi_version), ""),
                   "export-controller: generating the C code and compiling {name} (cmake and the C compiler)")


def export_fmu(study, set: Mapping[str, Any] | Sequence[str] | None = None, out: str | Path | None = None, *,
               fmi_version: int = 2, components: Sequence[str] | None = None, overwrite: bool = False) -> ExportedFile:
    """The study's whole loop (or the subsystem of ``components``) as one FMU from the compiled
    engine's C (fmu_export.loop_fmu); a study's [sweep] is left out, and said so (the FMU is the
    study's own point); ``note`` the FMU's ports."""
    from agrobot.fmu_export.loop_fmu import export_loop

    study = load(study, set)
    if study.sweep is not None:
        study = study.without("sweep")
        print(f"{study.path}: its [sweep] is left out: the FMU is the study's own point (--set the values to export "
              f"another)", file=sys.stderr)
    names = None if components is None else list(components)
    count = len(names) if names is not None else len(study.components)
    return _export(".fmu", study, out, overwrite, lambda s: export_loop(s, fmi_version, names),
                   f"export-fmu: compiling the loop of {count} components into {{name}} "
                   f"(the compiled engine's C, cmake and the C compiler)")


def export_ssp(study, set: Mapping[str, Any] | Sequence[str] | None = None, out: str | Path | None = None, *,
               overwrite: bool = False) -> ExportedFile:
    """The study as an SSP 1.0 archive: SystemStructure.ssd and one FMI 2.0 FMU per component
    (fmu_export.ssp_export)."""
    from agrobot.fmu_export.ssp_export import export_ssp as build

    study = load(study, set)
    return _export(".ssp", study, out, overwrite, lambda s: (build(s), ""),
                   f"export-ssp: compiling {len(study.components)} FMUs, one per component (cmake and the C "
                   f"compiler), and validating the SSD")


def emulate(study, nmea_port: int, set: Mapping[str, Any] | Sequence[str] | None = None,
            out: str | Path | None = None, *, duration: float | None = None, record: str | Path | None = None,
            overwrite: bool = False, progress: bool = True, announce=None) -> EmulationResult:
    """Serve the study's simulated tractor (it holds an ``nmea_server``) in real time: NMEA over
    TCP on ``nmea_port``, its CAN links on their buses, until its stop time, ``duration`` seconds,
    or Ctrl-C/SIGTERM. Runs to that end (a blocking call, as ``run``: the engine's signal handlers
    and its real-time pacing belong to the main thread, and a run that stops keeps what it
    recorded); bound it with ``duration``, or run it in a process of its own to hold a handle.
    ``out``: the signals recorded, streamed there as they come (interrupted: what was recorded so
    far, as ``run --out`` keeps it); ``record``: the buses as a field log (DIR/gps.nmea,
    DIR/can.log). ``announce(line)``: told where it listens before it starts."""
    from agrobot.components.hardware.emulate import emulated_study, reach
    from agrobot.components.hardware.record import recordings_aside

    if not 0 <= nmea_port <= 65535:
        raise StudyError(f"--nmea-port {nmea_port}: expected a TCP port, 0-65535")
    if duration is not None and not duration > 0:
        raise StudyError(f"--duration {duration:g}: expected a positive number of seconds")
    study, model, server, named = emulated_study(load(study, set), nmea_port, duration,
                                                 None if record is None else Path(record))
    install_signal_handlers()                   # SIGTERM ends the run like Ctrl-C: partial results are kept
    if announce is not None:
        announce(f"emulating {study.study.name}: {reach(study, model, server, nmea_port)}, real time, until "
                 f"t = {study.study.stop_time:g} s or Ctrl-C")
    try:
        with nullcontext(study) if out is not None else recordings_aside(study, overwrite, record) as placed:
            done = run_study(placed, None if out is None else Path(out), plots=False, overwrite=overwrite,
                             progress=progress, named=named)
    except Interrupted as exc:
        return _stopped(study, f" {exc}", exc.exit_status)
    except RunError as exc:
        cause = exc.__cause__
        status = (143 if isinstance(cause, Terminated) else 130) if isinstance(cause, KeyboardInterrupt) else 1
        return _stopped(study, f": {exc}", status)
    signals = done.frame if out is None else done.frame.to_pandas()
    return EmulationResult(study, signals, judged_metrics(done.metrics, study), dict(done.metrics), done.summary,
                           list(done.warnings), None if out is None else Path(out), dict(done.record or {}),
                           done.events)


def _stopped(study, message: str, exit_status: int) -> EmulationResult:
    """The emulator's result when it did not complete (``message`` says how it stopped)."""
    status = "failed" if exit_status == 1 else "interrupted"
    return EmulationResult(study, pd.DataFrame(), {}, {"status": status}, f"emulator stopped{message}",
                           exit_status=exit_status, stopped=f"emulator stopped{message}")
