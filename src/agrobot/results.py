"""What the Python API returns: typed results that hold their data in memory and write themselves
to a folder only when asked (``save``), after python-control's ``TimeResponseData`` and FMPy's
simulation result.

    RunResult       one run of a study: the signals (a DataFrame), the key figures with their bounds
    SweepResult     every point of a sweep: one row per point
    Identification  the yaw dynamics identified from a study's experiment or a measured log
    Diagnosis       what the simulation gets wrong about a measured log: verdict, findings, residuals
    Recording       a raw recording read as a measured log, with its import report
    PlanResult      a coverage plan of a field with its as-applied figures
    LoopMargins     gain, phase and delay margins at the study's operating points
    FieldsResult    the fields a file, a folder or a GNSS track holds
    ExportedFile    an FMU or SSP archive made from a study, in memory until saved
    EmulationResult a run of the hardware emulator (a RunResult) and how it stopped
    TunedStudy      tracker gains proposed for margin targets, as a study file that extends the study

``load_result(path)`` reads back what a command's ``--out`` (or a result's ``save``) wrote: a run,
sweep, identification, diagnosis, margins or fields folder, an exported .fmu/.ssp, a converted log.

What a result reads or writes with another command's package is imported where it is used, so that a
result loads no command's package it does not need (1.2 s of them together).

Imported where used: agrobot.identification (start-up: 0.6 s), agrobot.diagnosis (1.0 s), agrobot.fields (0.6 s,
the planner), agrobot.measurements (0.2 s), agrobot.analysis (0.2 s), matplotlib (0.9 s; the plot methods only).
"""
from __future__ import annotations

import json
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from agrobot.orchestrator.atomic_files import atomic_write, read_table, write_json, write_table
from agrobot.orchestrator.errors import InputError
from agrobot.orchestrator.key_figures import bounds, declared, hook
from agrobot.orchestrator.output import (OutputLock, ResultFile, ResultFolder, check_output, check_output_file,
                                         study_inputs)
from agrobot.orchestrator.registry import import_study_module
from agrobot.orchestrator.study import load_study, parse_study
from agrobot.orchestrator.sweep import SweepRun, sweep_summary


def _jsonable(data: Any) -> Any:
    """``data`` with numpy numbers and arrays as Python ones, non-finite numbers as None."""
    from agrobot.identification.from_log import finite_for_json
    from agrobot.identification.pipeline import _json_default

    return finite_for_json(json.loads(json.dumps(data, default=_json_default)))


class Saved:
    """What every result's ``save(folder, overwrite=False)`` goes through: the one output rule of
    orchestrator.output (a new or empty folder is written; a folder holding this kind of result's
    SIGNATURE file is replaced only with ``overwrite``; any other folder, or one that is, holds or
    lies inside an input, is refused), one writer at a time, the files written aside and moved into
    place whole."""

    SIGNATURE: tuple[str, ...] = ()
    WHAT = "result"

    @classmethod
    def check(cls, folder: str | Path, overwrite: bool = False, inputs=()) -> None:
        """Refuse ``folder`` before anything is computed, as ``save`` would (a folder another
        command is writing to included)."""
        check_output(Path(folder), overwrite, cls.SIGNATURE, cls.WHAT, list(inputs))
        with OutputLock(Path(folder)):
            pass

    def _save(self, folder: str | Path, overwrite: bool, write) -> Path:
        """``write(staging_folder)`` under the rule; returns the folder."""
        with ResultFolder(Path(folder), overwrite, self.SIGNATURE, self.WHAT, getattr(self, "inputs", [])) as out:
            write(out.tmp)
            return out.commit("completed")


@dataclass(frozen=True)
class Metric:
    """A key figure of a run: its value, unit, and the bound it is judged against (``"< 0.40"``,
    from the paper, the analysis or the study), ``passed`` None when it has no bound."""

    name: str
    value: Any
    unit: str | None = None
    bound: str | None = None
    source: str | None = None
    passed: bool | None = None


@dataclass
class RunResult(Saved):
    """One run of a study (``agrobot.run``): ``signals`` one column per port (``"tractor.x_cg"``)
    and ``t``; ``metrics`` name -> Metric (the analysis's key figures judged against their bounds);
    ``facts`` everything metrics.json records (status, seed, wall time ...); ``record`` what
    run.json holds, ``events`` what events.log holds."""

    SIGNATURE = ("run.json", "metrics.json")
    WHAT = "run"

    study: Any
    signals: pd.DataFrame
    metrics: dict[str, Metric]
    facts: dict[str, Any]
    summary: str
    warnings: list[str] = field(default_factory=list)
    folder: Path | None = None
    record: dict[str, Any] = field(default_factory=dict, repr=False)
    events: str = field(default="", repr=False)

    @property
    def inputs(self) -> list[Path]:
        """The study's files (never written over)."""
        return study_inputs(self.study)

    @property
    def status(self) -> str:
        return self.facts.get("status", "completed")

    @property
    def values(self) -> dict[str, Any]:
        """name -> value of every key figure."""
        return {k: m.value for k, m in self.metrics.items()}

    @property
    def failed(self) -> list[str]:
        """The figures outside their bounds."""
        return [k for k, m in self.metrics.items() if m.passed is False]

    @property
    def passed(self) -> bool:
        """Every bounded figure within its bound."""
        return not self.failed

    def metrics_frame(self) -> pd.DataFrame:
        """The key figures as a table: value, unit, bound, source, passed (one row each)."""
        rows = [{"value": m.value, "unit": m.unit, "bound": m.bound, "source": m.source, "passed": m.passed}
                for m in self.metrics.values()]
        return pd.DataFrame(rows, index=pd.Index(list(self.metrics), name="figure"))

    def plot(self, *columns: str, x: str = "t", ax=None, label: str = ""):
        """Plot ``columns`` against ``x`` (default: the time); without columns, the path driven
        (every ``.x_cg``/``.y_cg`` and ``.x_ref``/``.y_ref`` pair: the reference, the plant, the
        estimate) or else every signal; ``label`` prefixes the legend's entries. Returns the
        matplotlib Axes."""
        import matplotlib.pyplot as plt

        if ax is None:
            ax = plt.subplots(figsize=(6, 4))[1]
        if not columns:
            path = [(c, c.replace(".x_", ".y_")) for c in self.signals.columns if c.endswith((".x_cg", ".x_ref"))]
            if path:
                for cx, cy in path:
                    ax.plot(self.signals[cx], self.signals[cy], label=f"{label} {cy.split('.')[0]}".strip())
                ax.set(xlabel="east [m]", ylabel="north [m]", aspect="equal")
                ax.legend()
                return ax
            columns = tuple(c for c in self.signals.columns if c != x)
        for c in columns:
            ax.plot(self.signals[x], self.signals[c], label=f"{label} {c}".strip())
        ax.set_xlabel("t [s]" if x == "t" else x)
        ax.legend()
        return ax

    def save(self, folder: str | Path, overwrite: bool = False, plots: bool = True) -> Path:
        """Write the run as ``run --out`` does: the signals (the study's format), events.log,
        run.json, metrics.json and the analysis's figures; returns the folder."""
        def write(tmp: Path) -> None:
            write_table(tmp / "signals", self.signals, self.study.study.signals_format)
            (tmp / "events.log").write_text(self.events)
            write_json(tmp / "run.json", self.record)
            analysis = import_study_module(self.study.study.analysis) if self.study.study.analysis else None
            if plots and analysis is not None and hasattr(analysis, "plots"):
                analysis.plots(self.signals, self.study, tmp)
            write_json(tmp / "metrics.json", self.facts)

        self.folder = self._save(folder, overwrite, write)
        return self.folder

    @classmethod
    def from_folder(cls, folder: Path) -> "RunResult":
        """A run as ``run --out`` or ``save`` left it: the study from run.json (as it ran, every
        --set applied), the signals, the key figures judged against the study's bounds."""
        record, facts = _read_json(folder / "run.json"), _read_json(folder / "metrics.json")
        study = _study_of(folder / "run.json", facts.get("study_file"), record.get("study"))
        tables = sorted(folder.glob("signals.*"))
        if not tables:
            raise InputError(f"{folder}: a run folder without its signals (signals.parquet or signals.csv)")
        metrics = {k: v for k, v in facts.items() if isinstance(v, (int, float)) and not isinstance(v, bool)}
        events = (folder / "events.log").read_text() if (folder / "events.log").is_file() else ""
        return cls(study, read_table(tables[0]), judged_metrics(metrics, study), facts,
                   f"run {facts.get('study', folder.name)}: {facts.get('status', '?')} (loaded from {folder})",
                   [], folder, record, events)

    def __str__(self) -> str:
        return self.summary


def judged_metrics(values: dict[str, Any], study) -> dict[str, Metric]:
    """name -> Metric: the study's analysis's declared figures (METRICS, METRIC_UNITS) and the
    figures a bound names, judged by orchestrator.key_figures (the bounds the run's table shows); a
    bound the analysis says the run cannot judge (``unjudged``) is neither passed nor failed."""
    analysis = import_study_module(study.study.analysis) if study.study.analysis else None
    table = declared(analysis)
    units = dict(getattr(analysis, "METRIC_UNITS", None) or {})
    judged = bounds(analysis, study.study.bounds)
    not_judged = hook(analysis, "unjudged", values, study)
    out = {}
    for key, value in values.items():
        if key in ("study", "study_file", "status", "seed") or isinstance(value, (dict, list, str)):
            continue
        unit = table.get(key, (units.get(key), None))[0] or units.get(key)
        b = judged.get(key)
        passed = None if b is None or key in not_judged else (isinstance(value, (int, float)) and b.holds(float(value)))
        out[key] = Metric(key, value, unit, None if b is None else str(b), None if b is None else b.source, passed)
    return out


@dataclass
class SweepResult(Saved):
    """Every point of a sweep (``agrobot.sweep``): ``table`` one row per point (the swept values,
    status, key figures); ``summary`` the sweep's key-figure table; ``folder`` where the points are;
    ``nominal`` the nominal run's metrics (the oscillation bound's reference; the bounds it was too
    short to judge), kept in ``nominal/metrics.json``."""

    SIGNATURE = ("sweep.json",)
    WHAT = "sweep"

    study: Any
    table: pd.DataFrame
    summary: str
    folder: Path | None = None
    engine: str = "python"
    nominal: dict = field(default_factory=dict, repr=False)

    @property
    def inputs(self) -> list[Path]:
        return study_inputs(self.study)

    def save(self, folder: str | Path, overwrite: bool = False) -> Path:
        """The sweep as ``sweep --out`` leaves it: every point's folder (when the points were kept),
        sweep.json and the results table; without kept points, sweep.json and the table only (a
        later ``sweep --out`` on that folder runs the points again). Returns the folder."""
        def write(tmp: Path) -> None:
            if self.folder is not None and (self.folder / "sweep.json").is_file():
                shutil.copytree(self.folder, tmp, dirs_exist_ok=True, ignore=shutil.ignore_patterns(".running"))
                return
            runner = SweepRun(self.study, tmp, engine=self.engine)
            write_json(tmp / "sweep.json", runner.manifest())
            write_table(tmp / "results", self.table, runner.fmt)
            if self.nominal:
                (tmp / "nominal").mkdir()
                write_json(tmp / "nominal" / "metrics.json", {"point": "nominal", "status": "completed",
                                                              "metrics": self.nominal})

        self.folder = self._save(folder, overwrite, write)
        return self.folder

    @classmethod
    def from_folder(cls, folder: Path) -> "SweepResult":
        manifest = _read_json(folder / "sweep.json")
        study = _study_of(folder / "sweep.json", manifest.get("study_file"))
        tables = sorted(folder.glob("results.*"))
        if not tables:
            raise InputError(f"{folder}: a sweep folder without its results table (results.parquet or results.csv): "
                             f"rerun the sweep with --out {folder} to finish it")
        table = read_table(tables[0])
        kept = folder / "nominal" / "metrics.json"
        record = _read_json(kept) if kept.is_file() else {}
        nominal = dict(record.get("metrics") or {}) if record.get("status") == "completed" else {}
        return cls(study, table, sweep_summary(study, table, nominal)[0], folder, manifest.get("engine", "python"),
                   nominal)

    def __str__(self) -> str:
        return self.summary


@dataclass
class Identification(Saved):
    """The yaw dynamics identified from ``source`` by ``method`` (``"study"``: a study's simulated
    multisine experiment; ``"multisine"``: a measured periodic experiment; ``"driving"``: ordinary
    driving, a time-domain fit). ``report`` is what identification.json holds."""

    SIGNATURE = ("identification.json",)
    WHAT = "identification"

    source: str
    method: str
    report: dict[str, Any]
    study: Any = None
    _write: Any = field(default=None, repr=False)      # write(folder, plots): the files, figures included
    inputs: list = field(default_factory=list, repr=False)

    def summary(self) -> str:
        """What an engineer reads first (the text ``identify`` prints)."""
        if self.method == "driving":
            from agrobot.identification.ordinary_driving import summary
        else:
            from agrobot.identification.pipeline import summary
        return summary(self.report)

    def to_json(self) -> str:
        return json.dumps(_jsonable(self.report), indent=2)

    def save(self, folder: str | Path, overwrite: bool = False, plots: bool = True) -> Path:
        """identification.json and the figures (for a study, experiment_log.csv; for ordinary
        driving with a study, extended_study.toml); returns the folder."""
        from agrobot.identification.pipeline import write_outputs

        write = self._write or (lambda tmp, plots: write_outputs(self.report, None, tmp, False))
        return self._save(folder, overwrite, lambda tmp: write(tmp, plots))

    @classmethod
    def from_folder(cls, folder: Path) -> "Identification":
        """An identification as ``identify --out`` or ``save`` left it (identification.json)."""
        report = _read_json(folder / "identification.json")
        source = str(report.get("source", folder))
        study = Path(source).suffix in (".toml", ".yaml", ".yml")
        method = "driving" if "segments" in report else "study" if study else "multisine"
        return cls(source, method, report)

    def __str__(self) -> str:
        return self.summary()


@dataclass
class Diagnosis(Saved):
    """What the simulation gets wrong about a measured log (diagnosis.pipeline): the ``verdict``
    (an effect's id, ``"unexplained"``, ``"none"`` or ``"cannot decide"``), the effects found and
    the first step's findings, the stages' residuals; ``result`` is what diagnosis.json holds."""

    SIGNATURE = ("diagnosis.json",)
    WHAT = "diagnosis"

    result: dict[str, Any]
    folder: Path | None = None
    _write: Any = field(default=None, repr=False)      # write(folder): the files, figures included
    inputs: list = field(default_factory=list, repr=False)

    @property
    def verdict(self) -> str:
        return self.result["verdict"]

    @property
    def effects(self) -> list[dict]:
        return self.result.get("effects", [])

    @property
    def findings(self) -> list[dict]:
        return self.result.get("findings", [])

    @property
    def residuals(self) -> dict[str, Any]:
        """stage -> the baseline's residual evidence (RMS, noise floor, correlations)."""
        return self.result.get("residuals", {})

    @property
    def reason(self) -> str | None:
        """Why the log could not be judged (verdict ``cannot decide``), else None."""
        return self.result.get("reason")

    @property
    def warnings(self) -> list[str]:
        return self.result.get("warnings", [])

    def to_json(self) -> str:
        return json.dumps(_jsonable(self.result), indent=2)

    def report(self) -> str:
        """The report (Markdown) that report.md holds."""
        from agrobot.diagnosis.report import markdown

        return markdown(self.result, sorted(p.name for p in self.folder.glob("*.png")) if self.folder else [])

    def save(self, folder: str | Path, overwrite: bool = False) -> Path:
        """diagnosis.json, report.md, the figures and extended_study.toml, as ``diagnose --out``
        writes them; returns the folder."""
        from agrobot.diagnosis.pipeline import _write as write_bare

        write = self._write or (lambda tmp: write_bare(tmp, self.result, []))
        self.folder = self._save(folder, overwrite, write)
        return self.folder

    @classmethod
    def from_folder(cls, folder: Path) -> "Diagnosis":
        """A diagnosis as ``diagnose --out`` or ``save`` left it (diagnosis.json)."""
        return cls(_read_json(folder / "diagnosis.json"), folder)

    def __repr__(self) -> str:
        return f"Diagnosis(verdict={self.verdict!r}, effects={[e.get('id') for e in self.effects]}, folder={self.folder})"

    def __str__(self) -> str:
        return f"verdict: {self.verdict}" + (f" ({self.reason})" if self.reason else "")


@dataclass
class Recording:
    """A raw recording read as a measured log (measurements.recording): ``log`` the canonical
    columns t, delta_cmd, delta, v, yaw_rate, x, y; ``report`` what was read and how."""

    source: str
    log: pd.DataFrame
    report: dict[str, Any]
    inputs: list = field(default_factory=list, repr=False)

    def describe(self) -> str:
        from agrobot.measurements.recording import describe

        return describe(self.report)

    def save(self, path: str | Path, overwrite: bool = False) -> Path:
        """The log as ``path`` (.csv or .parquet) and the import report beside it
        (<name>.import.json), as ``convert --out`` writes them: an existing file is replaced only
        with ``overwrite``, the recording read (or any input) never."""
        from agrobot.measurements.cli import write_converted

        path = Path(path)
        inputs = [self.source, *self.inputs]
        with ResultFile(path, overwrite, inputs, suffixes=(".csv", ".parquet")):
            check_output_file(path.with_name(path.stem + ".import.json"), overwrite, inputs)
            write_converted(path, self.log, self.report)
        return path

    @classmethod
    def from_file(cls, path: Path) -> "Recording":
        """A log ``convert --out`` (or ``save``) wrote, with its import report (<name>.import.json)."""
        report = _read_json(path.with_name(path.stem + ".import.json"))
        return cls(str(report.get("source", path)), read_table(path), report)

    def __str__(self) -> str:
        return self.describe()


@dataclass
class PlanResult(Saved):
    """A coverage plan of a field (fields.planner): ``plan`` the headland, swaths, route and path;
    ``summary`` what plan.json holds (distances, time, angle, the as-applied figures)."""

    SIGNATURE = ("plan.json",)
    WHAT = "plan"

    plan: Any
    summary: dict[str, Any]
    applied: Any
    sections: int = 0
    inputs: list = field(default_factory=list, repr=False)
    route_rows: int | None = None          # route.csv's rows, once saved

    def route(self, step: float | None = None, uniform: bool = False) -> pd.DataFrame:
        """The route as route.csv holds it: s, x, y, heading, curvature, speed, kind (by name),
        index; rows at most ``step`` m apart where it curves (fields.planner.export)."""
        from agrobot.fields.planner.export import KIND_NAMES
        from agrobot.fields.planner.sampling import EXPORT_STEP

        parts = [pd.DataFrame(self.plan.path.evaluate(s))
                 for s in self.plan.path.knots(EXPORT_STEP if step is None else step, uniform)]
        table = pd.concat(parts, ignore_index=True)
        table["kind"] = KIND_NAMES[table["kind"].to_numpy()]
        return table

    def plot(self, ax=None):
        """The field's boundary and the route on ``ax`` (a new figure without); returns it."""
        import matplotlib.pyplot as plt

        if ax is None:
            ax = plt.subplots(figsize=(6, 6))[1]
        route = self.route()
        ax.plot(route["x"], route["y"], lw=0.8, label="route")
        boundary = self.plan.field.boundary
        for ring in [boundary.exterior, *boundary.interiors]:
            ax.plot(*ring.xy, color="k", lw=1)
        ax.set(xlabel="east [m]", ylabel="north [m]", aspect="equal")
        return ax

    def save(self, folder: str | Path, overwrite: bool = False, route_step: float | None = None,
             route_uniform: bool = False) -> Path:
        """route.csv, route.geojson, plan.json, plan.png, as_applied.geojson, as_applied.png, as
        ``plan --out`` writes them (one set, moved into place whole); returns the folder."""
        from agrobot.fields.plan_cli import write_plan_files
        from agrobot.fields.planner.sampling import EXPORT_STEP

        step = EXPORT_STEP if route_step is None else route_step

        def write(tmp: Path) -> None:
            self.route_rows = write_plan_files(tmp, self.plan, self.applied, self.sections, self.summary, step,
                                               route_uniform)
        return self._save(folder, overwrite, write)


@dataclass
class LoopMargins(Saved):
    """Gain, phase and delay margins of a study's guidance loop at each operating point of its
    reference (analysis.margins): ``analysis`` holds the open loops and the margins."""

    SIGNATURE = ("margins.json",)
    WHAT = "margins"

    analysis: Any
    inputs: list = field(default_factory=list, repr=False)
    files: list[str] = field(default_factory=list, repr=False)      # the names the last save wrote

    @property
    def points(self) -> list:
        return self.analysis.points

    @property
    def delay_limit(self) -> float:
        """The steering command delay [s] at which the loop loses stability, at the first
        operating point (where a run spends its time)."""
        return self.analysis.points[0].delay_limit

    def as_dict(self) -> dict:
        from agrobot.analysis.margins import as_dict

        return as_dict(self.analysis)

    def to_json(self) -> str:
        return json.dumps(self.as_dict(), indent=2)

    def report(self) -> str:
        from agrobot.analysis.margins import report

        return report(self.analysis)

    def save(self, folder: str | Path, overwrite: bool = False, plots: bool = True) -> Path:
        """margins.json (the margins and the study analysed, every --set applied) and the Bode and
        Nyquist plots; returns the folder."""
        from agrobot.analysis.margin_plots import write_plots

        def write(tmp: Path) -> None:
            data = self.as_dict() | {"analysed_study": self.analysis.study.to_data()}
            files = (write_plots(self.analysis, tmp) if plots else []) + [write_json(tmp / "margins.json", data)]
            self.files = [f.name for f in files]
        return self._save(folder, overwrite, write)

    @classmethod
    def from_folder(cls, folder: Path) -> "LoopMargins":
        """Margins as ``margins --out`` or ``save`` left them (margins.json): the study as it was
        analysed, the margins at each operating point (the open loops themselves are not saved:
        ``open_loops`` is empty; ``agrobot.margins(result.analysis.study)`` computes them)."""
        from agrobot.analysis.loop_anatomy import anatomy
        from agrobot.analysis.margins import Analysis

        data = _read_json(folder / "margins.json")
        study = _study_of(folder / "margins.json", data.get("study"), data.get("analysed_study"))
        an = anatomy(study, "margins")
        if an.tracker != data.get("tracker") or ".".join(an.steering_break) != data.get("steering_command"):
            raise InputError(f"{folder / 'margins.json'}: its tracker and steering command are not those of the "
                             f"study it names ({study.where})")
        return cls(Analysis(study, an, [_margins_point(p, folder) for p in data.get("operating_points", [])],
                            list(data.get("notes", []))), study_inputs(study))

    def __str__(self) -> str:
        return self.report()



@dataclass
class FieldsResult(Saved):
    """The fields of a field file or folder, or of a GNSS track (``fields`` command): ``fields``
    the fields.Field objects, ``skipped`` why files of a folder were not read, ``track`` the line
    describing the track a field was made from (None for a file)."""

    SIGNATURE = ("fields.json",)
    WHAT = "fields"

    source: str
    fields: list
    skipped: list[str] = field(default_factory=list)
    track: str | None = None
    inputs: list = field(default_factory=list, repr=False)

    saved: list[dict] | None = field(default=None, repr=False)      # fields.json's summaries, when read back

    def summaries(self) -> list[dict]:
        """What fields.json holds of each field (area, rings, lines, headland, validity)."""
        return list(self.saved) if self.saved is not None else [f.summary() for f in self.fields]

    def save(self, folder: str | Path, overwrite: bool = False, plots: bool = True) -> Path:
        """fields.json, fields.geojson (longitude/latitude) and fields.png, as ``fields --out``
        writes them; returns the folder."""
        from agrobot.fields.cli import write_fields

        return self._save(folder, overwrite, lambda tmp: write_fields(tmp, self.source, self.fields, plots, self.track))

    @classmethod
    def from_folder(cls, folder: Path) -> "FieldsResult":
        """Fields as ``fields --out`` or ``save`` left them: each field's summary from fields.json,
        its boundary and guidance lines from fields.geojson, back in the field's local frame (the
        headland polygon is not saved: ``summaries()`` gives fields.json's). A field in local
        coordinates has no geometry in fields.geojson: it is named in ``skipped``. A field made from a
        track comes back with its ``track`` line."""
        data = _read_json(folder / "fields.json")
        features = _read_json(folder / "fields.geojson").get("features", [])
        found, skipped = _saved_fields(folder, data.get("fields", []), features)
        source = str(data.get("source", folder))
        track = data.get("track")
        return cls(source, found, skipped, track if isinstance(track, str) else None, [],
                   saved=list(data.get("fields", [])))


@dataclass
class ExportedFile:
    """An archive a study was exported as (``export-controller``, ``export-fmu``: an FMU;
    ``export-ssp``: an SSP), its bytes held in memory; ``note`` what the export says of its ports.
    ``save`` writes it under the one-file rule of orchestrator.output: an input never, an existing
    file only with ``overwrite``, one writer at a time, written under a unique temporary name
    beside it and renamed into place."""

    kind: str                   # ".fmu" or ".ssp"
    data: bytes = field(repr=False)
    note: str = ""
    inputs: list = field(default_factory=list, repr=False)
    path: Path | None = None

    @staticmethod
    def check(path: str | Path, kind: str, overwrite: bool = False, inputs=()) -> None:
        """Refuse ``path`` as ``save`` would, before anything is built (a file another command
        is writing included)."""
        check_file(path, kind, overwrite, inputs)

    def save(self, path: str | Path, overwrite: bool = False) -> Path:
        """The archive at ``path``; returns it."""
        self.path = save_file(path, self.kind, overwrite, self.inputs, lambda tmp: tmp.write_bytes(self.data))
        return self.path

    @classmethod
    def from_file(cls, path: Path) -> "ExportedFile":
        """An archive an export (or ``save``) wrote, its bytes read (its note is not in the file)."""
        return cls(path.suffix, path.read_bytes(), "", [], path)


def check_file(path: str | Path, suffix: str | tuple[str, ...], overwrite: bool = False, inputs=()) -> None:
    """Refuse ``path`` as ``save_file`` would (not ``suffix``, or one of them, an input, an existing
    file without ``overwrite``, a file another command is writing), before anything is computed."""
    check_output_file(Path(path), overwrite, list(inputs), (suffix,) if isinstance(suffix, str) else tuple(suffix))
    with OutputLock(Path(path)):
        pass


def save_file(path: str | Path, suffix: str, overwrite: bool, inputs, write) -> Path:
    """``write(temporary_path)`` moved to ``path`` under the one-file rule of orchestrator.output:
    an input never, an existing file only with ``overwrite``, one writer at a time, written under a
    unique temporary name beside it and renamed into place."""
    path = Path(path)
    with ResultFile(path, overwrite, inputs, suffixes=(suffix,)):
        atomic_write(path, write)
    return path


@dataclass
class EmulationResult(RunResult):
    """A run of the hardware emulator (``emulate``): a RunResult (the signals when it completed
    in memory) and how it stopped: ``exit_status`` 0 (its stop time), 130 (Ctrl-C), 143 (SIGTERM)
    or 1 (failed), ``stopped`` the message when it did not complete."""

    exit_status: int = 0
    stopped: str | None = None



@dataclass
class TunedStudy:
    """Tracker gains proposed by ``tune`` (analysis.tune.propose) for margin targets: ``proposal``
    the tuned study, the values set and the margins before and after; ``text`` the study file that
    extends the study; ``checked`` the simulated check's lines, once ``simulate`` ran. ``save``
    writes the study file under the one-file rule (``agrobot.load(path)`` reads it back as a Study)."""

    proposal: Any = field(repr=False)
    inputs: list = field(default_factory=list, repr=False)
    checked: list[str] = field(default_factory=list, repr=False)
    path: Path | None = None

    @property
    def study(self):
        """The tuned Study."""
        return self.proposal.study

    @property
    def values(self) -> dict[str, Any]:
        """The values set (dotted keys, as ``set=`` takes them)."""
        return dict(self.proposal.values)

    @property
    def text(self) -> str:
        return self.proposal.text

    def comparison(self) -> str:
        """The values and the whole loop's margins, the study's against the proposal's (the table
        ``tune`` prints)."""
        from agrobot.analysis.tune import comparison

        return comparison(self.proposal)

    def simulate(self, duration: float = 160.0, progress=None) -> list[str]:
        """The proposal simulated (its key figures against the paper's bounds, the steering
        command delay at which it loses stability against the predicted one); kept in ``checked``."""
        from agrobot.analysis.tune import simulated_check

        self.checked = simulated_check(self.proposal, duration, progress)
        return self.checked

    def save(self, path: str | Path, overwrite: bool = False) -> Path:
        """The study file (.toml) at ``path``, as ``tune --out`` writes it; returns it."""
        self.path = save_file(path, ".toml", overwrite, self.inputs, lambda tmp: tmp.write_text(self.text))
        return self.path

    def __str__(self) -> str:
        return self.comparison()


LOADABLE = {"run.json": RunResult, "sweep.json": SweepResult, "identification.json": Identification,
            "diagnosis.json": Diagnosis, "margins.json": LoopMargins, "fields.json": FieldsResult}
WHAT_WROTE = "run, sweep, identify, diagnose, margins or fields --out (or a result's save)"


def load_result(path: str | Path):
    """The typed result a command or ``save`` wrote at ``path``: a folder holding run.json (a
    RunResult, an emulator's run included), sweep.json (SweepResult), identification.json
    (Identification), diagnosis.json (Diagnosis), margins.json (LoopMargins) or fields.json
    (FieldsResult); an exported .fmu or .ssp (ExportedFile); a log ``convert`` wrote, its
    <name>.import.json beside it (Recording). A tuned study is a study file (``agrobot.load``);
    anything else is refused with what was looked for."""
    path = Path(path)
    if path.is_file():
        if path.suffix in (".fmu", ".ssp"):
            return ExportedFile.from_file(path)
        if path.suffix in (".csv", ".parquet") and path.with_name(path.stem + ".import.json").is_file():
            return Recording.from_file(path)
        raise InputError(f"{path}: a file that is neither an exported .fmu or .ssp nor a log convert wrote (a .csv "
                         f"or .parquet with its {path.stem}.import.json beside it); a result folder is read whole")
    if not path.is_dir():
        raise InputError(f"{path}: no such folder (expected what {WHAT_WROTE} wrote)")
    for name, kind in LOADABLE.items():
        if (path / name).is_file():
            return kind.from_folder(path)
    if (path / "plan.json").is_file():
        raise InputError(f"{path}: a plan (plan.json) is not read back into a PlanResult (the plan's geometry is "
                         f"not all in its files): read route.csv with pandas, or plan the field again")
    raise InputError(f"{path}: holds none of {', '.join(LOADABLE)}: not a folder that {WHAT_WROTE} wrote")


def _margins_point(data: dict, folder: Path):
    """An operating point's margins as margins.json holds them (null: the value a loop without that
    crossing has, analysis.margins.Margins)."""
    from agrobot.analysis.margins import Margins, OperatingPoint, PointResult

    def num(x, absent: float) -> float:
        return absent if x is None else float(x)

    try:
        loops = {name: Margins(num(m["gain_margin"], np.inf), m["gain_reduction"], num(m["phase_margin_deg"], np.inf),
                               num(m["crossover_rad_s"], np.nan), num(m["delay_margin_s"], np.inf),
                               num(m["phase_crossover_rad_s"], np.nan)) for name, m in data["loops"].items()}
        op = OperatingPoint(float(data["speed_m_s"]), float(data["along_track_error_m"]), data["label"])
        return PointResult(op, loops, {}, bool(data["closed_loop_stable"]), num(data["delay_limit_s"], np.inf),
                           data.get("speed_excess_m_s"))
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise InputError(f"{folder / 'margins.json'}: an operating point without {exc} as margins writes it") from None


def _saved_fields(folder: Path, summaries: list[dict], features: list[dict]) -> tuple[list, list[str]]:
    """The fields fields.geojson holds (a boundary feature, then its guidance lines), in the local
    frame about each field's origin (fields.json), and what could not be rebuilt."""
    from agrobot.fields.field import Field, GuidanceLine, local_frame, polygon

    groups: list[list[dict]] = []
    for feature in features:
        if feature.get("properties", {}).get("kind") == "boundary":
            groups.append([feature])
        elif groups:
            groups[-1].append(feature)
    found, skipped, placed = [], [], iter(groups)
    for summary in summaries:
        if summary.get("origin_lat_lon_deg") is None:
            skipped.append(f"{summary.get('name')}: in local coordinates, so fields.geojson holds none of its "
                           f"geometry (its summary is in fields.json)")
            continue
        group = next(placed, None)
        if group is None or group[0]["properties"].get("name") != summary.get("name"):
            raise InputError(f"{folder / 'fields.geojson'}: no boundary of field {summary.get('name')!r} where "
                             f"fields.json lists it")
        _, to_local = local_frame([], tuple(summary["origin_lat_lon_deg"]))
        rings = [to_local(np.asarray(ring, float)) for ring in group[0]["geometry"]["coordinates"]]
        lines = [GuidanceLine(f["properties"]["name"], to_local(np.asarray(f["geometry"]["coordinates"], float)))
                 for f in group[1:]]
        found.append(Field(summary["name"], polygon(rings[0], rings[1:]), tuple(summary["origin_lat_lon_deg"]),
                           summary.get("source", ""), summary.get("crs", ""), lines, None,
                           dict(summary.get("properties") or {})))
    return found, skipped


def _read_json(path: Path) -> dict[str, Any]:
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise InputError(f"{path}: missing (the folder is not a whole result)") from None
    except (OSError, ValueError) as exc:
        raise InputError(f"{path}: cannot read as JSON: {exc}") from None


def _study_of(where: Path, study_file: str | None, data: dict | None = None):
    """The study a result ran: ``data`` (the resolved study it recorded) or its study file."""
    if data:
        return parse_study(data, study_file or where)
    if study_file and Path(study_file).is_file():
        return load_study(study_file)
    raise InputError(f"{where}: names no study file that exists ({study_file!r}); the result cannot be judged")
