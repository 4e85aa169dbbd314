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
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd


def _jsonable(data: Any) -> Any:
    """``data`` with numpy numbers and arrays as Python ones, non-finite numbers as None."""
    from agrobot.identification.from_log import finite_for_json
    from agrobot.identification.pipeline import _json_default

    return finite_for_json(json.loads(json.dumps(data, default=_json_default)))


def _written(folder: str | Path, write, overwrite: bool = True) -> Path:
    """Write a result's files with ``write(tmp_folder)`` into a fresh folder moved into place as a
    whole (orchestrator.output.ResultFolder): an interrupted save leaves ``folder`` as it was."""
    from agrobot.orchestrator.output import ResultFolder

    with ResultFolder(Path(folder), overwrite=overwrite) as out:
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
class RunResult:
    """One run of a study (``agrobot.run``): ``signals`` one column per port (``"tractor.x_cg"``)
    and ``t``; ``metrics`` name -> Metric (the analysis's key figures judged against their bounds);
    ``facts`` everything metrics.json records (status, seed, wall time ...)."""

    study: Any
    signals: pd.DataFrame
    metrics: dict[str, Metric]
    facts: dict[str, Any]
    summary: str
    warnings: list[str] = field(default_factory=list)
    folder: Path | None = None

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

    def save(self, folder: str | Path, plots: bool = True) -> Path:
        """Write the run as ``run --out`` does: signals (the study's format), metrics.json, the
        study (study.toml) and the analysis's figures; returns the folder."""
        from agrobot.orchestrator.registry import import_study_module
        from agrobot.orchestrator.atomic_files import write_json, write_table

        def write(tmp: Path) -> None:
            write_table(tmp / "signals", self.signals, self.study.study.signals_format)
            (tmp / "study.toml").write_text(self.study.to_toml())
            analysis = import_study_module(self.study.study.analysis) if self.study.study.analysis else None
            if plots and analysis is not None and hasattr(analysis, "plots"):
                analysis.plots(self.signals, self.study, tmp)
            write_json(tmp / "metrics.json", _jsonable(self.facts))

        self.folder = _written(folder, write)
        return self.folder

    def __str__(self) -> str:
        return self.summary


def judged_metrics(values: dict[str, Any], study) -> dict[str, Metric]:
    """name -> Metric: the study's analysis's declared figures (METRICS, METRIC_UNITS) and the
    figures a bound names, judged by orchestrator.key_figures (the bounds the run's table shows)."""
    from agrobot.orchestrator.key_figures import bounds, declared
    from agrobot.orchestrator.registry import import_study_module

    analysis = import_study_module(study.study.analysis) if study.study.analysis else None
    table = declared(analysis)
    units = dict(getattr(analysis, "METRIC_UNITS", None) or {})
    judged = bounds(analysis, study.study.bounds)
    out = {}
    for key, value in values.items():
        if key in ("study", "study_file", "status", "seed") or isinstance(value, (dict, list, str)):
            continue
        unit = table.get(key, (units.get(key), None))[0] or units.get(key)
        b = judged.get(key)
        passed = None if b is None else (isinstance(value, (int, float)) and b.holds(float(value)))
        out[key] = Metric(key, value, unit, None if b is None else str(b), None if b is None else b.source, passed)
    return out


@dataclass
class SweepResult:
    """Every point of a sweep (``agrobot.sweep``): ``table`` one row per point (the swept values,
    status, key figures); ``summary`` the sweep's key-figure table; ``folder`` where the points are."""

    study: Any
    table: pd.DataFrame
    summary: str
    folder: Path | None = None

    def __str__(self) -> str:
        return self.summary


@dataclass
class Identification:
    """The yaw dynamics identified from ``source`` by ``method`` (``"study"``: a study's simulated
    multisine experiment; ``"multisine"``: a measured periodic experiment; ``"driving"``: ordinary
    driving, a time-domain fit). ``report`` is what identification.json holds."""

    source: str
    method: str
    report: dict[str, Any]
    study: Any = None
    _figures: Any = field(default=None, repr=False)      # what the figures are drawn from

    def summary(self) -> str:
        """What an engineer reads first (the text ``identify`` prints)."""
        if self.method == "driving":
            from agrobot.identification.ordinary_driving import summary
        else:
            from agrobot.identification.pipeline import summary
        return summary(self.report)

    def to_json(self) -> str:
        return json.dumps(_jsonable(self.report), indent=2)

    def save(self, folder: str | Path, plots: bool = True) -> Path:
        """identification.json and the figures (and, for ordinary driving with a study,
        extended_study.toml); returns the folder."""
        def write(tmp: Path) -> None:
            if self.method == "driving":
                from agrobot.identification.from_log import write_driving

                write_driving(dict(self.report), self._figures, tmp, self.study, self.source, plots)
            else:
                from agrobot.identification.pipeline import write_outputs

                write_outputs(self.report, self._figures, tmp, plots and self._figures is not None)
        return _written(folder, write)

    def __str__(self) -> str:
        return self.summary()


@dataclass
class Diagnosis:
    """What the simulation gets wrong about a measured log (diagnosis.pipeline): the ``verdict``
    (an effect's id, ``"unexplained"``, ``"none"`` or ``"cannot decide"``), the effects found and
    the first step's findings, the stages' residuals; ``result`` is what diagnosis.json holds."""

    result: dict[str, Any]
    folder: Path | None = None

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

    def save(self, folder: str | Path) -> Path:
        """diagnosis.json and report.md (the figures are drawn by ``diagnose(..., out=folder)``)."""
        from agrobot.orchestrator.atomic_files import write_json

        def write(tmp: Path) -> None:
            write_json(tmp / "diagnosis.json", _jsonable(self.result))
            (tmp / "report.md").write_text(self.report())
        return _written(folder, write)

    def __str__(self) -> str:
        return f"verdict: {self.verdict}" + (f" ({self.reason})" if self.reason else "")


@dataclass
class Recording:
    """A raw recording read as a measured log (measurements.recording): ``log`` the canonical
    columns t, delta_cmd, delta, v, yaw_rate, x, y; ``report`` what was read and how."""

    source: str
    log: pd.DataFrame
    report: dict[str, Any]

    def describe(self) -> str:
        from agrobot.measurements.recording import describe

        return describe(self.report)

    def save(self, path: str | Path) -> Path:
        """The log as ``path`` (.csv or .parquet) and the import report beside it
        (<name>.import.json), as ``convert --out`` writes them."""
        from agrobot.measurements.log import LogError
        from agrobot.orchestrator.atomic_files import atomic_write

        path = Path(path)
        if path.suffix not in (".csv", ".parquet"):
            raise LogError(f"{path}: expected a .csv or .parquet file")
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write(path, (lambda p: self.log.to_parquet(p, index=False)) if path.suffix == ".parquet"
                     else (lambda p: self.log.to_csv(p, index=False, float_format="%.9g")))
        atomic_write(path.with_name(path.stem + ".import.json"),
                     lambda p: p.write_text(json.dumps(self.report, indent=2, default=float)))
        return path

    def __str__(self) -> str:
        return self.describe()


@dataclass
class PlanResult:
    """A coverage plan of a field (fields.planner): ``plan`` the headland, swaths, route and path;
    ``summary`` what plan.json holds (distances, time, angle, the as-applied figures)."""

    plan: Any
    summary: dict[str, Any]
    applied: Any
    sections: int = 0

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

    def save(self, folder: str | Path, route_step: float | None = None, route_uniform: bool = False) -> Path:
        """route.csv, route.geojson, plan.json, plan.png, as_applied.geojson, as_applied.png, as
        ``plan --out`` writes them (one set, moved into place whole); returns the folder."""
        from agrobot.fields.plan_cli import write_plan
        from agrobot.fields.planner.sampling import EXPORT_STEP

        write_plan(Path(folder), self.plan, self.applied, self.sections, self.summary,
                   EXPORT_STEP if route_step is None else route_step, route_uniform)
        return Path(folder)


@dataclass
class LoopMargins:
    """Gain, phase and delay margins of a study's guidance loop at each operating point of its
    reference (analysis.margins): ``analysis`` holds the open loops and the margins."""

    analysis: Any

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

    def save(self, folder: str | Path, plots: bool = True) -> Path:
        """margins.json and the Bode and Nyquist plots; returns the folder."""
        from agrobot.analysis.margin_plots import write_plots
        from agrobot.analysis.margins import write_json

        def write(tmp: Path) -> None:
            if plots:
                write_plots(self.analysis, tmp)
            write_json(self.analysis, tmp / "margins.json")
        return _written(folder, write)

    def __str__(self) -> str:
        return self.report()

