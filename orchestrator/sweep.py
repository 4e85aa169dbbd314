"""Parameter sweeps: every point of a study's ``[sweep]`` section in its own worker process
(a local process pool, or a Dask cluster), results written by the parent only, resumable.

Output folder::

    sweep.json                 the sweep's identity (hash of the resolved study) and its points
    points/pNNNN/metrics.json  per point: parameters, seed, status, error (and its kind), metrics
    points/pNNNN/signals.*     the point's signals, streamed by its worker
    points/pNNNN/run.json, events.log
    results.parquet|csv        one row per point
    plots/                     each metric against the swept parameter, plus the study's own plots

A point's worker records its run into a fresh folder ``.running/pNNNN.XXXX`` (signals streamed: a
long point keeps flat memory, orchestrator.runner.record_run); the parent adds the point's record
and moves the folder into place in one step, so ``points/pNNNN`` is either whole or absent, and a
point rerun (``--retry-failed``) replaces only a failed one. With a scheduler on other machines
(``--scheduler ADDRESS``) the worker records into its own temporary folder and sends the files.

Imported where used: distributed (the dask extra; the rest is in orchestrator.sweep_dask), matplotlib (start-up:
0.9 s in every worker process, which never plots; the Agg backend is chosen before pyplot loads).
"""
from __future__ import annotations

import concurrent.futures as cf
import contextlib
import ctypes
import errno
import hashlib
import itertools
import json
import multiprocessing
import os
import re
import shutil
import signal
import sys
import tempfile
import threading
import time
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator

import pandas as pd
from tqdm import tqdm

from .build import build_system
from .compiled import cores_of, select_engine
from .compiled.simulation import refusal
from .engine import RunError, Simulation
from .resolver import resolve
from .errors import InputError, critical
from .key_figures import sweep_table
from .mcap_out import wants_mcap, write_study_mcap
from .output import (OutputError, OutputLock, ResultFolder, check_output, disk_full, full_reason, remove_stale_staging,
                     study_inputs, swap_folder)
from .registry import import_study_module
from .runner import AnalysisError, _analysis, _metrics, _run_facts, _status, record_run
from .atomic_files import UMASK, atomic_write, write_json, write_table
from .study import Study, StudyError
from .sweep_dask import abandon_cluster, dask_client, execute_dask, point_result
from .sweep_cost import CostRefused, SignalKeeper, check_cost, estimate, folder_bytes, policy, sample_points
from .sweep_judgement import (failing_groups, judgement_lines, length_warning, nominal_from_table, point_row, severity,
                               sweep_bounds, too_short, with_oscillation)


@dataclass(frozen=True)
class Point:
    index: int
    values: dict[str, Any]
    seed: int

    @property
    def key(self) -> str:
        return f"p{self.index:04d}"


def expand(study: Study) -> list[Point]:
    """The sweep's points: grid (every combination) or zip (element by element), each per seed;
    or the Monte Carlo draws (values and seed of each sample from the study's seed)."""
    sweep = study.sweep
    if sweep is None:
        raise StudyError(f"{study.path}: no [sweep] section")
    if sweep.mode == "monte_carlo":
        return [Point(i, values, seed) for i, (values, seed) in enumerate(sweep.draws(study.study.seed))]
    values = sweep.expanded()
    names = list(values)
    if sweep.mode == "zip":
        lengths = {n: len(v) for n, v in values.items()}
        if len(set(lengths.values())) != 1:
            raise StudyError(f"{study.path}: sweep.mode = 'zip' needs lists of equal length, got {lengths}")
        combos = list(zip(*values.values()))
    else:
        combos = list(itertools.product(*values.values()))
    seeds = sweep.seeds or [study.study.seed]
    return [Point(i, dict(zip(names, combo)), seed)
            for i, (combo, seed) in enumerate((c, s) for c in combos for s in seeds)]


def point_study(study: Study, point: Point) -> Study:
    """The study of one point: the sweep values set, its seed, no sweep section."""
    try:
        return study.without("sweep").with_values({**point.values, "study.seed": point.seed})
    except StudyError as exc:
        raise StudyError(str(exc).replace(f"{study.where}: ", f"{study.where}: sweep.parameters.", 1)) from None


def watch_parent(parent: int) -> None:
    """Worker initialiser: the worker ends with the sweep that started it, whatever ends the sweep
    (SIGKILL included). Linux: the kernel sends SIGKILL when the parent dies (PR_SET_PDEATHSIG);
    elsewhere, and as a back-up, a daemon thread exits when the parent is gone (a new parent id)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)        # Ctrl-C reaches the whole group: the parent decides
    try:
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, int(signal.SIGKILL))   # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(1)

    threading.Thread(target=watch, daemon=True, name="watch-parent").start()


@contextlib.contextmanager
def main_file_hidden() -> Iterator[None]:
    """While workers start: a ``__main__`` whose file does not exist (a script read from standard
    input, ``python3 - < script.py``: ``'<stdin>'``) is not named to them. The spawn start method
    runs the parent's main file again in every worker; with none to run, each worker died at start
    and every point was lost. The points need nothing from ``__main__``."""
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    hidden = path is not None and not os.path.isfile(path)
    if hidden:
        del main.__file__
    try:
        yield
    finally:
        if hidden:
            main.__file__ = path


def simulate_point(study: Study, folder: str | None = None, engine: str = "python",
                   keep_signals: bool = True) -> dict[str, Any]:
    """Worker: run one point into ``folder`` (None: a temporary folder whose files are returned);
    never raises (a failure is a result, with its kind: input, run, analysis or bug). ``engine``:
    python, compiled or auto (orchestrator.compiled); ``keep_signals`` False: the point's signal
    table is removed once its metrics are computed."""
    target = Path(folder) if folder is not None else Path(tempfile.mkdtemp(prefix="sweep-point-"))
    try:
        system = build_system(resolve(study))
        simulation = None
        if engine != "python":
            simulation = select_engine(system, engine)[0]
        if not keep_signals and not wants_mcap(study):
            result = _metrics_only(study, system, simulation)
            if folder is None:
                shutil.rmtree(target, ignore_errors=True)
            return result
        outcome = record_run(study, system, target, _analysis(study), plots=False, progress=False,
                             simulation=simulation)
        if outcome.complete and wants_mcap(study):
            write_study_mcap(study, outcome.table.to_pandas(), target / "run.mcap")
    except InputError as exc:           # the point's values refused when its components start
        result = {"status": "failed", "kind": "input", "error": str(exc)}
    except OSError as exc:
        if not disk_full(exc):
            raise
        result = {"status": "failed", "kind": DISK_FULL, "error": f"{exc.strerror or exc}", "errno": exc.errno,
                  "filename": str(exc.filename or "")}
    except Exception as exc:  # a bug in a component: record it, the sweep goes on
        result = {"status": "failed", "kind": "bug", "error": f"{type(exc).__name__}: {exc}\n{traceback.format_exc()}"}
    else:
        error = outcome.error
        result = {"status": "completed" if outcome.complete else "failed", "metrics": outcome.values}
        if error is not None:
            kind = "run" if isinstance(error, RunError) else "analysis" if isinstance(error, AnalysisError) else "bug"
            text = str(error) if kind != "bug" else \
                f"{type(error).__name__}: {error}\n{''.join(traceback.format_exception(error))}"
            result.update(kind=kind, error=text)
    if folder is None and result.get("kind") != DISK_FULL:
        result["files"] = {p.name: p.read_bytes() for p in target.iterdir() if p.is_file()}
    if folder is None:
        shutil.rmtree(target, ignore_errors=True)
    return result


DISK_FULL = "disk_full"        # a point's kind of failure that ends the sweep (SweepDiskFull)


class SweepDiskFull(OutputError):
    """The disk filled while the sweep wrote a point (exit 2): the point is removed, the points
    finished before it are kept (a rerun resumes)."""


def _metrics_only(study: Study, system, simulation) -> dict[str, Any]:
    """A point run in memory: its metrics, no file (its signals are dropped once analysed)."""
    try:
        rec = (simulation or Simulation)(system).run()
    except RunError as exc:
        return {"status": "failed", "kind": "run", "error": str(exc)}
    try:
        values = _metrics(_analysis(study), rec.to_frame(), study)
    except AnalysisError as exc:
        return {"status": "failed", "kind": "analysis", "error": str(exc)}
    values.update(sim_time_s=study.study.stop_time - study.study.start_time, wall_time_s=rec.wall_time_s,
                  **_run_facts(rec))
    return {"status": _status(rec), "metrics": values}


def simulate_points(study: Study, jobs: list[tuple[Point, str | None]], engine: str,
                    keep_signals: bool) -> list[dict[str, Any]]:
    """Worker: several points of ``study``'s sweep in one task (a compiled point takes
    milliseconds: one task each would cost more in the pool than in the run); each point's
    study is made here, not in the parent."""
    results = []
    for point, folder in jobs:
        try:
            one = point_study(study, point)
        except StudyError as exc:
            results.append({"status": "failed", "kind": "input", "error": str(exc)})
            continue
        results.append(simulate_point(one, folder, engine, keep_signals))
    return results


BATCH = 25                   # points per task with the compiled engine
VALIDATE_ALL_UP_TO = 500     # larger sweeps build a representative subset of their points first


def sweep_hash(study: Study) -> str:
    return hashlib.sha256(json.dumps(study.to_data(), sort_keys=True, default=str).encode()).hexdigest()[:16]


class SweepRun:
    def __init__(self, study: Study, out_dir: Path, overwrite: bool = False, engine: str = "python",
                 keep_signals: bool | str | None = None, accept_cost: bool = False) -> None:
        self.study, self.out, self.overwrite = study, Path(out_dir), overwrite
        self.engine, self.accept_cost = engine, accept_cost
        self.where = str(study.path)
        self.kept_in = self.out                 # where an interrupted sweep's finished points are
        self.points = expand(study)
        self._keep_asked = keep_signals
        self.ran = engine                       # the engine the points run with (auto: chosen on the first)
        self._policy(engine)
        self.nominal: dict[str, Any] = {}       # the nominal run's metrics (orchestrator.sweep_judgement)
        self.keeper: SignalKeeper | None = None
        self.fmt = study.study.signals_format
        self._into(self.out)

    def _policy(self, engine: str) -> None:
        """Which points keep their signals (orchestrator.sweep_cost.policy) with ``engine``."""
        self.signals = policy(self._keep_asked, engine, len(self.points))
        self.keep_signals = self.signals != "none"

    def _into(self, folder: Path) -> None:
        """Write into ``folder`` (``--out``, or the staging folder of a sweep that replaces one)."""
        self.folder = folder
        self.points_dir = folder / "points"
        self.running_dir = folder / ".running"          # points being recorded by their workers

    # --- checks before anything runs ----------------------------------------------------------
    def checked_points(self) -> list[Point]:
        """The points built before the sweep runs: all of them up to VALIDATE_ALL_UP_TO; beyond, the
        first and, per swept parameter, the points of its smallest and largest value and the first
        of each distinct value (a value refused is at an end of its range or a choice); the workers
        check the others as they run them."""
        if len(self.points) <= VALIDATE_ALL_UP_TO:
            return self.points
        chosen = {0}
        for name in self.study.sweep.parameters:
            values = [p.values.get(name) for p in self.points]
            try:
                chosen |= {min(range(len(values)), key=values.__getitem__), max(range(len(values)), key=values.__getitem__)}
            except TypeError:
                pass
            seen: dict = {}
            for i, v in enumerate(values):
                seen.setdefault(repr(v), i)
            if len(seen) <= 50:
                chosen |= set(seen.values())
        return [self.points[i] for i in sorted(chosen)]

    def validate(self) -> None:
        """Build the points (types, parameters, units, wiring: ``checked_points``) before running
        any; with the compiled engine, choose it on the first point (compiled: refused with the
        components named; auto: the choice and why printed) and compile its shape once."""
        checked = self.checked_points()
        if len(checked) < len(self.points):
            print(f"sweep: {len(self.points)} points: building {len(checked)} of them before the run (the first, each "
                  f"parameter's extremes and choices); the workers check the others", file=sys.stderr)
        for i, point in enumerate(checked):
            try:
                system = build_system(resolve(point_study(self.study, point)))
                if i == 0 and self.engine != "python":
                    self._choose_engine(system)
            except StudyError as exc:
                raise StudyError(f"{exc}\n  (sweep point {point.key}: {point.values}, seed {point.seed})") from None
        manifest = self.folder / "sweep.json"
        digest = sweep_hash(self.study)
        if manifest.exists():
            old = json.loads(manifest.read_text())
            if old.get("hash") != digest:
                raise StudyError(f"--out {self.out}: holds the results of a different sweep (sweep.json: the study changed); "
                                 f"pass --overwrite to replace them, or choose another folder")
            if old.get("engine", "python") != self.engine:
                raise StudyError(f"--out {self.out}: holds points run with --engine {old.get('engine', 'python')}; "
                                 f"resume with that engine, or choose another folder")
        else:
            write_json(manifest, self.manifest())

    def _choose_engine(self, system) -> None:
        """The compiled engine for the first point's ``system`` (its C cores found once, compiled
        once, or taken from the cache); auto: the engine chosen and why, printed, and the nominal run
        and the points run with it (``ran``), not chosen again."""
        found = cores_of(system)
        if self.engine == "compiled" or not refusal(system, found[1]):
            print(f"sweep: compiling the study's loop for --engine {self.engine} (once; a loop compiled "
                  f"before is taken from the cache) ...", file=sys.stderr, flush=True)
        start = time.perf_counter()
        factory, note = select_engine(system, self.engine, found)
        if factory is not Simulation:
            print(f"sweep: the loop ready in {time.perf_counter() - start:.1f} s", file=sys.stderr)
        if note and self.engine == "auto":
            print(note, file=sys.stderr)
            self.ran = "python" if factory is Simulation else "compiled"
            self._policy(self.ran)

    def manifest(self) -> dict[str, Any]:
        """What sweep.json holds: the study file, the resolved study's hash, the engine, the points."""
        return {"study_file": self.where, "hash": sweep_hash(self.study), "engine": self.engine,
                "points": [{"point": p.key, "seed": p.seed, **p.values} for p in self.points]}

    # --- bookkeeping --------------------------------------------------------------------------
    def record_path(self, point: Point) -> Path:
        return self.points_dir / point.key / "metrics.json"

    def finished(self, retry_failed: bool = False) -> set[str]:
        done = set()
        for point in self.points:
            path = self.record_path(point)
            if path.exists():
                status = json.loads(path.read_text()).get("status")
                if status == "completed" or not retry_failed:
                    done.add(point.key)
        return done

    def new_folder(self, point: Point) -> Path:
        """A fresh folder for the point's worker to record into (on the same file system as the
        point's, to be moved there in one step)."""
        self.points_dir.mkdir(parents=True, exist_ok=True)
        self.running_dir.mkdir(parents=True, exist_ok=True)
        folder = Path(tempfile.mkdtemp(prefix=f"{point.key}.", dir=self.running_dir))
        os.chmod(folder, 0o777 & ~UMASK)
        return folder

    def store(self, point: Point, result: dict[str, Any], folder: Path | None = None) -> dict[str, Any]:
        """Add the point's record to the folder its worker wrote (or write the files it sent) and
        move the folder into place in one step."""
        folder = folder if folder is not None and folder.is_dir() else self.new_folder(point)
        kept = self.record_path(point)
        if kept.exists() and json.loads(kept.read_text()).get("status") == "completed":
            shutil.rmtree(folder, ignore_errors=True)      # a completed point is never replaced
            return json.loads(kept.read_text())
        for name, data in (result.get("files") or {}).items():
            atomic_write(folder / name, lambda p, data=data: p.write_bytes(data))
        record = {"point": point.key, "seed": point.seed, "parameters": point.values,
                  "status": result["status"], "error": result.get("error"), "error_kind": result.get("kind"),
                  "metrics": {k: v for k, v in (result.get("metrics") or {}).items()
                              if isinstance(v, (int, float)) and not isinstance(v, bool)}}
        write_json(folder / "metrics.json", record)
        with critical():
            old = swap_folder(folder, self.points_dir / point.key)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        return record

    def table(self) -> pd.DataFrame:
        """One row per stored point (its parameters, status, error, metrics) and its oscillation
        ratio to the nominal run (orchestrator.sweep_judgement)."""
        rows = []
        for point in self.points:
            path = self.record_path(point)
            if not path.exists():
                continue
            rec = json.loads(path.read_text())
            rows.append({"point": rec["point"], "seed": rec["seed"], **rec["parameters"],
                         "status": rec["status"], "error": rec["error"], **rec["metrics"]})
        return with_oscillation(pd.DataFrame(rows), self.study, self.nominal_metrics())

    # --- the nominal run, and the cost told before it is paid ------------------------------------
    def nominal_metrics(self) -> dict[str, Any]:
        """The nominal run's metrics (empty when it did not complete or has not run)."""
        path = self.folder / "nominal" / "metrics.json"
        if not self.nominal and path.exists():
            record = json.loads(path.read_text())
            self.nominal = record["metrics"] if record["status"] == "completed" else {}
        return self.nominal

    def run_nominal(self) -> tuple[dict[str, Any], Path | None]:
        """(record, folder to move into ``nominal/`` or None when it is there already): the study with
        its own values (no swept value set) run here, before the points, timed and weighed: the
        oscillation bound's reference and the measure of the sweep's cost (orchestrator.sweep_cost)."""
        path = self.folder / "nominal" / "metrics.json"
        if path.exists():
            return json.loads(path.read_text()), None
        print("sweep: the nominal run (the study's own values) first: the reference of the oscillation bound and "
              "the measure of the sweep's cost ...", file=sys.stderr, flush=True)
        self.running_dir.mkdir(parents=True, exist_ok=True)
        folder = Path(tempfile.mkdtemp(prefix="nominal.", dir=self.running_dir))
        start = time.perf_counter()
        result = simulate_point(self.study.without("sweep"), str(folder), self.ran, keep_signals=True)
        elapsed = time.perf_counter() - start
        if not self.keep_signals and result.get("kind") != DISK_FULL:     # timed as the points run: in memory
            start = time.perf_counter()
            simulate_point(self.study.without("sweep"), None, self.ran, keep_signals=False)
            elapsed = time.perf_counter() - start
        signal_bytes, other_bytes = folder_bytes(folder)
        record = {"point": "nominal", "seed": self.study.study.seed, "parameters": {}, "status": result["status"],
                  "error": result.get("error"), "error_kind": result.get("kind"), "elapsed_s": elapsed,
                  "signal_bytes": signal_bytes, "other_bytes": other_bytes + 1024,
                  "metrics": {k: v for k, v in (result.get("metrics") or {}).items()
                              if isinstance(v, (int, float)) and not isinstance(v, bool)}}
        try:
            if result.get("kind") == DISK_FULL:
                raise OSError(result.get("errno") or errno.ENOSPC, result["error"])
            write_json(folder / "metrics.json", record)
        except OSError as exc:
            if not disk_full(exc):
                raise
            shutil.rmtree(folder, ignore_errors=True)
            raise SweepDiskFull(f"--out {self.out}: {full_reason(exc)[0]} ({exc.strerror or exc}) while the nominal run "
                                f"was written; it was removed: {full_reason(exc)[1]} and run the command again") from None
        return record, folder

    def announce_cost(self, todo: int, workers: int) -> None:
        """Print the sweep's expected time and disk use; refuse one beyond the limits (CostRefused)
        unless ``accept_cost``, and say which bounds its nominal run is too short to judge (as are its
        points: orchestrator.sweep_judgement.length_warning); then keep the nominal run in ``nominal/``."""
        record, folder = self.run_nominal()
        warning = length_warning(self.study, record["metrics"], todo) if record["status"] == "completed" else None
        if warning:
            print(warning, file=sys.stderr, flush=True)
        cost = estimate(todo, workers, record["elapsed_s"], record["signal_bytes"], record["other_bytes"],
                        self.signals)
        print(cost.line(self.signals, record["elapsed_s"]), file=sys.stderr, flush=True)
        check_cost(cost, self.folder, self.accept_cost)
        if folder is not None:
            with critical():
                old = swap_folder(folder, self.folder / "nominal")
            if old is not None:
                shutil.rmtree(old, ignore_errors=True)
        self.nominal = {}
        self.nominal_metrics()
        if record["status"] != "completed":
            print(f"sweep: the nominal run failed ({str(record.get('error') or '').splitlines()[0][:200]}); the "
                  f"points are not judged against it", file=sys.stderr)

    def _keep_signals_of(self, point: Point, record: dict[str, Any]) -> None:
        """Under the ``worst`` policy: the point's signals kept while it is among the worst or in the sample."""
        if self.keeper is not None:
            row = point_row(record, self.study, self.nominal)
            self.keeper.keep(point.key, severity(row, sweep_bounds(self.study, self.nominal)), self.points_dir)

    def write_table(self) -> Path:
        return write_table(self.folder / "results", self.table(), self.fmt)

    # --- running ------------------------------------------------------------------------------
    def run(self, workers: int, scheduler: str | None = None, retry_failed: bool = False,
            progress: bool = True) -> pd.DataFrame:
        """Run the points not yet done, under ``--out``'s lock (orchestrator.output): into ``--out``
        itself when it is new, empty or this sweep's (resumed), into a staging folder swapped into
        place at the end with ``--overwrite`` (an interrupted one goes beside ``--out``)."""
        inputs = study_inputs(self.study)
        check_output(self.out, self.overwrite, ("sweep.json",), "sweep", inputs, resume=not self.overwrite)
        if self.overwrite and self.out.is_dir() and any(self.out.iterdir()):
            with ResultFolder(self.out, True, ("sweep.json",), "sweep", inputs) as staging:
                self._into(staging.tmp)
                try:
                    table = self._run(workers, scheduler, retry_failed, progress)
                except KeyboardInterrupt:
                    self.kept_in = staging.commit("interrupted")
                    raise
                finally:
                    self._into(self.out)
                staging.commit("completed")
            return table
        with OutputLock(self.out):
            remove_stale_staging(self.out)
            return self._run(workers, scheduler, retry_failed, progress)

    def _run(self, workers: int, scheduler: str | None, retry_failed: bool, progress: bool) -> pd.DataFrame:
        fresh = not (self.folder / "sweep.json").exists()
        self.validate()
        self._remove_stale()
        done = self.finished(retry_failed)
        todo = [p for p in self.points if p.key not in done]
        try:
            self.announce_cost(len(todo), workers)
        except CostRefused:
            self._remove_stale()
            if fresh:                 # nothing of this sweep is left behind
                (self.folder / "sweep.json").unlink(missing_ok=True)
                with contextlib.suppress(OSError):
                    self.points_dir.rmdir()
            raise
        if self.signals == "worst":
            self.keeper = SignalKeeper(sample_points([p.key for p in self.points]))
            for point in self.points:
                if point.key in done:
                    self._keep_signals_of(point, json.loads(self.record_path(point).read_text()))
        bar = _progress(len(self.points), len(done), progress)
        failures = sum(1 for p in self.points if p.key in done
                       and json.loads(self.record_path(p).read_text())["status"] != "completed")
        try:
            for point, result, folder in self._execute(todo, workers, scheduler):
                record = self._store_or_stop(point, result, folder)
                self._keep_signals_of(point, record)
                failures += record["status"] != "completed"
                bar.update(1)
                bar.set_postfix(failures=failures)
        finally:
            with critical():                # a second Ctrl-C waits for the table and the clean-up
                bar.close()
                try:
                    self.write_table()
                except OSError as exc:      # a full disk: the table is made again from the points on resume
                    if not disk_full(exc):
                        raise
                self._remove_stale()
        return self.table()

    def _store_or_stop(self, point: Point, result: dict[str, Any], folder: Path | None) -> dict[str, Any]:
        """``store``; on a full disk (the worker's or ours) the point's folder is removed and the
        sweep ends with SweepDiskFull, the points finished before it kept."""
        try:
            if result.get("kind") == DISK_FULL:
                raise OSError(result.get("errno") or errno.ENOSPC, result["error"], result.get("filename") or None)
            return self.store(point, result, folder)
        except OSError as exc:
            if not disk_full(exc):
                raise
            if folder is not None:
                shutil.rmtree(folder, ignore_errors=True)
            what, then = full_reason(exc)
            kept = (f"the {len(self.finished())} points finished before it are kept in {self.out}: {then} "
                    f"and run the same command again to resume") if self.folder == self.out else \
                f"{self.out} holds what it held before (--overwrite): {then} and run the command again"
            raise SweepDiskFull(f"--out {self.out}: {what} ({exc.strerror or exc}) while point {point.key} "
                                f"was written; that point was removed and {kept}") from None

    def _remove_stale(self) -> None:
        """Files and point folders left half-written by a run that was killed or interrupted."""
        for stale in self.folder.glob("**/.*.tmp"):
            stale.unlink(missing_ok=True)
        shutil.rmtree(self.running_dir, ignore_errors=True)

    def _execute(self, todo: list[Point], workers: int,
                 scheduler: str | None) -> Iterator[tuple[Point, dict, Path | None]]:
        """(point, result, the folder its worker wrote) as points finish."""
        shared = scheduler in (None, "local")            # the workers see this machine's folders
        if not todo:
            return
        if self.ran != "python":
            yield from self._execute_batched(todo, workers, scheduler, shared)
            return
        jobs = [(p, point_study(self.study, p), self.new_folder(p) if shared else None) for p in todo]
        # one thread per point: parallelism comes from processes (BLAS threads spinning on tiny
        # matrices made two workers four times slower than one on two cores)
        for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
            os.environ.setdefault(var, "1")
        if scheduler is None:
            ctx = multiprocessing.get_context("spawn")
            with main_file_hidden(), cf.ProcessPoolExecutor(max_workers=workers, mp_context=ctx,
                                                            initializer=watch_parent, initargs=(os.getpid(),)) as pool:
                futures = {pool.submit(simulate_point, point, str(folder), "python", self.keep_signals): (p, folder)
                           for p, point, folder in jobs}
                try:
                    for fut in cf.as_completed(futures):
                        point, folder = futures[fut]
                        yield point, point_result(fut), folder
                except BaseException:
                    # interrupted: the points in flight are dropped (a rerun does them again) and
                    # their workers end now, not when their point would have finished
                    for proc in list((pool._processes or {}).values()):
                        proc.terminate()
                    pool.shutdown(wait=False, cancel_futures=True)
                    raise
            return
        with main_file_hidden():
            yield from execute_dask(simulate_point, jobs, workers, scheduler, self.keep_signals)

    def _execute_batched(self, todo: list[Point], workers: int, scheduler: str | None, shared: bool):
        """As ``_execute``, BATCH points per task (the compiled engine); tasks are submitted as
        workers free up, so memory holds a few batches whatever the number of points."""
        for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
            os.environ.setdefault(var, "1")
        batches = [todo[i:i + BATCH] for i in range(0, len(todo), BATCH)]

        def job(batch):
            folders = [self.new_folder(p) if shared else None for p in batch]
            return [(p, str(f) if f else None) for p, f in zip(batch, folders)], folders

        if scheduler is None:
            ctx = multiprocessing.get_context("spawn")
            pool = cf.ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=watch_parent,
                                          initargs=(os.getpid(),))
            submit = lambda jobs: pool.submit(simulate_points, self.study, jobs, self.ran,  # noqa: E731
                                              self.keep_signals)
            wait_first = lambda fs: cf.wait(fs, return_when=cf.FIRST_COMPLETED)[0]  # noqa: E731
        else:
            from distributed import wait

            pool, cluster, before = dask_client(scheduler, workers)
            submit = lambda jobs: pool.submit(simulate_points, self.study, jobs, self.ran,  # noqa: E731
                                              self.keep_signals, pure=False)
            wait_first = lambda fs: wait(list(fs), return_when="FIRST_COMPLETED").done  # noqa: E731
        pending: dict = {}
        queue = iter(batches)
        try:
            with main_file_hidden():
                yield from _drain(queue, pending, job, submit, wait_first, workers)
        except BaseException:
            if scheduler is not None:
                abandon_cluster(pool, cluster, before)
            raise
        finally:
            if scheduler is None:
                for proc in list((pool._processes or {}).values()):
                    proc.terminate()
                pool.shutdown(wait=False, cancel_futures=True)
        if scheduler is not None:
            pool.close()
            if cluster is not None:
                cluster.close()


def _drain(queue, pending: dict, job, submit, wait_first, workers: int):
    """(point, result, folder) as batches finish, 2 x ``workers`` batches in flight at most."""
    while True:
        while len(pending) < 2 * workers:
            batch = next(queue, None)
            if batch is None:
                break
            jobs, folders = job(batch)
            pending[submit(jobs)] = (batch, folders)
        if not pending:
            break
        for fut in wait_first(pending.keys()):
            batch, folders = pending.pop(fut)
            try:
                results = fut.result()
            except Exception as exc:  # a worker process died (killed, out of memory)
                results = [{"status": "failed", "kind": "bug",
                            "error": f"worker lost: {type(exc).__name__}: {exc}"}] * len(batch)
            yield from zip(batch, results, folders)


def _progress(total: int, initial: int, enabled: bool, file=None):
    """The sweep's bar. Its estimate of the time left is the rate so far (points done this time over
    the time taken, ``smoothing=0``): the compiled engine's points arrive in batches, and tqdm's
    moving average of the rate between two updates took a batch's wait for one point's (36 min left
    after the first batch of a 93 s sweep)."""
    return tqdm(total=total, initial=initial, desc="sweep points", unit="pt", disable=not enabled,
                dynamic_ncols=True, smoothing=0.0, file=file)


_AT_T = re.compile(r"^at t = [^:]+ s: ")


def failure_reasons(table: pd.DataFrame) -> list[tuple[str, list[str]]]:
    """The failed points grouped by reason (the error's first line, without the instant it came
    at), most frequent first: [(reason, [point, ...]), ...]."""
    if "status" not in table or table.empty:
        return []
    groups: dict[str, list[str]] = {}
    for _, row in table[table["status"] != "completed"].iterrows():
        text = str(row.get("error") or "no error recorded").strip().splitlines()[0]
        groups.setdefault(_AT_T.sub("", text), []).append(str(row["point"]))
    return sorted(groups.items(), key=lambda item: -len(item[1]))


def sweep_summary(study: Study, table: pd.DataFrame,
                  nominal: dict[str, Any] | None = None) -> tuple[str, list[tuple[str, list[str]]]]:
    """(the text a sweep ends with, its failures grouped by reason): the key figures over the
    completed points with their bounds (orchestrator.key_figures) and the oscillation bound
    against the ``nominal`` run's metrics, the points outside a bound named and grouped by what
    they share (orchestrator.sweep_judgement), the sweep analysis's own summary
    (``summary(table, study)`` of ``sweep.analysis``), the failures with their counts."""
    analysis = _analysis(study)
    done = int((table["status"] == "completed").sum()) if "status" in table else 0
    lines = [f"{study.study.name}: {len(table)} of {len(expand(study))} points, {done} completed, "
             f"{len(table) - done} failed"]
    nominal = nominal or nominal_from_table(table, study)
    if done:
        judged, short = sweep_bounds(study, nominal), too_short(study, nominal)
        text = sweep_table(table, analysis, judged, set(study.sweep.parameters), short)
        lines += [text] if text else []
        lines += judgement_lines(study, table, judged, nominal)
        if study.sweep.analysis:
            module = import_study_module(study.sweep.analysis)
            if hasattr(module, "summary"):
                lines.append(module.summary(table, study))
    reasons = failure_reasons(table)
    if reasons:
        lines.append(f"failed points, by reason ({len(reasons)} reason{'s' if len(reasons) > 1 else ''}):")
        for reason, points in reasons:
            shown = ", ".join(points[:5]) + (", ..." if len(points) > 5 else "")
            lines.append(f"  {len(points):>4} x {reason}  ({shown})")
    return "\n".join(lines), reasons


def _parameter_unit(study: Study, name: str) -> str:
    """The declared SI unit of a swept 'component.parameter' ('' when unknown or a study field)."""
    comp, _, param = name.partition(".")
    try:
        declared = resolve(study).component_class(comp).declared("parameter")
    except (StudyError, KeyError, AttributeError):
        return "s" if name in ("study.stop_time", "study.base_step") else ""
    return declared[param].unit if param in declared else ""


def sweep_plots(study: Study, table: pd.DataFrame, out_dir: Path, nominal: dict[str, Any] | None = None) -> list[Path]:
    """The metrics that matter against the first swept parameter (one line per other value / seed),
    and the sweep analysis module's own plots (``sweep.analysis``). The study's analysis module
    chooses them: ``SWEEP_METRICS`` {metric: bound drawn as a line, or None}; without it, every
    metric but counters and wall time (all stay in results.parquet). The oscillation ratio to the
    ``nominal`` run is drawn with its bound, and the points outside any bound are ringed in red
    (orchestrator.sweep_judgement)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir.mkdir(parents=True, exist_ok=True)
    ok = table[table["status"] == "completed"] if "status" in table else table
    if ok.empty:
        return []
    params = list(study.sweep.parameters)
    x = params[0]
    scatter = study.sweep.mode == "monte_carlo"          # one cloud: each sample is its own point
    group_cols = [] if scatter else params[1:] + (["seed"] if ok["seed"].nunique() > 1 else [])
    skip = set(params) | {"point", "seed", "status", "error", "sim_time_s", "wall_time_s"}
    analysis = import_study_module(study.study.analysis) if study.study.analysis else None
    metric_units = dict(getattr(analysis, "METRIC_UNITS", {}))
    metric_units.update(sim_time_s="s", wall_time_s="s")
    chosen = getattr(analysis, "SWEEP_METRICS", None)
    metrics = [c for c in ok.columns if c not in skip and pd.api.types.is_numeric_dtype(ok[c])]
    metrics = [m for m in chosen if m in metrics] if chosen else [m for m in metrics if metric_units.get(m) != "count"]
    judged = sweep_bounds(study, nominal or nominal_from_table(table, study))
    chosen = {**(chosen or {}), **{k: b.value for k, b in judged.items() if k.endswith("_vs_nominal")}}
    metrics += [k for k in chosen if k.endswith("_vs_nominal") and k in ok and k not in metrics]
    metric_units.update({k: "1" for k in chosen if k.endswith("_vs_nominal")})
    outside = pd.Series(False, index=ok.index)
    for _, _, mask in failing_groups(ok, judged):
        outside |= mask
    cols = 3
    rows = -(-len(metrics) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 2.8 * rows), squeeze=False)
    groups = ok.groupby(group_cols) if group_cols else [((), ok)]
    x_unit = _parameter_unit(study, x)
    for ax, metric in zip(axes.flat, metrics):
        for label, g in groups:
            g = g.sort_values(x)
            text = ", ".join(map(str, label if isinstance(label, tuple) else (label,)))
            ax.plot(g[x], g[metric], "o" if scatter else "o-", ms=3, label=text if group_cols else None)
        if outside.any():
            ax.plot(ok.loc[outside, x], ok.loc[outside, metric], "o", ms=7, mfc="none", mec="tab:red", mew=1.2,
                    label=f"outside a bound ({int(outside.sum())})")
            ax.legend(fontsize=7)
        unit = metric_units.get(metric)
        bound = (chosen or {}).get(metric)
        if bound is not None:
            shown = "" if unit in (None, "1", "count") else f" {unit}"
            ax.axhline(bound, color="tab:red", ls="--", lw=1.2, label=f"bound {bound:g}{shown}")
            ax.legend(fontsize=7)
        ax.set_xlabel(f"{x} [{x_unit}]" if x_unit else x), ax.set_title(metric, fontsize=9), ax.grid(alpha=0.3)
        ax.set_ylabel(f"[{unit}]" if unit else "[-]")
    if group_cols and metrics:
        axes.flat[0].legend(title=", ".join(group_cols), fontsize=7, title_fontsize=7)
    for ax in list(axes.flat)[len(metrics):]:
        ax.axis("off")
    fig.tight_layout()
    path = out_dir / f"metrics_vs_{x.replace('.', '_')}.png"
    fig.savefig(path, dpi=100)
    plt.close(fig)
    written = [path]
    if study.sweep.analysis:
        module = import_study_module(study.sweep.analysis)
        written += module.plots(table, study, out_dir)
    return written
