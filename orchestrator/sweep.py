"""Parameter sweeps: every point of a study's ``[sweep]`` section in its own worker process
(a local process pool, or a Dask cluster), results written by the parent only, resumable.

Output folder::

    sweep.json                 the sweep's identity (hash of the resolved study) and its points
    points/pNNNN/metrics.json  per point: parameters, seed, status, error, metrics (written last:
    points/pNNNN/signals.*     its presence marks the point finished)
    results.parquet|csv        one row per point
    plots/                     each metric against the swept parameter, plus the study's own plots
"""
from __future__ import annotations

import concurrent.futures as cf
import hashlib
import importlib
import io
import itertools
import json
import multiprocessing
import os
import time
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator

import pandas as pd

from .build import build_system
from .resolver import resolve
from .results import atomic_write, write_json, write_table
from .study import Study, StudyError


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
    import signal
    import threading

    signal.signal(signal.SIGINT, signal.SIG_IGN)        # Ctrl-C reaches the whole group: the parent decides
    try:
        import ctypes

        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, int(signal.SIGKILL))   # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(1)

    threading.Thread(target=watch, daemon=True, name="watch-parent").start()


def simulate_point(study: Study) -> dict[str, Any]:
    """Worker: run one point; never raises (a failure is a result)."""
    from .engine import RunError
    from .runner import AnalysisError, run_study

    def parquet_bytes(frame: pd.DataFrame) -> bytes:
        buf = io.BytesIO()
        frame.to_parquet(buf, index=False)
        return buf.getvalue()

    try:
        result = run_study(study, None, plots=False)
        return {"status": "completed", "metrics": result.metrics, "signals": parquet_bytes(result.frame)}
    except RunError as exc:
        return {"status": "failed", "error": str(exc), "signals": parquet_bytes(exc.partial.to_frame())}
    except (AnalysisError, StudyError) as exc:
        return {"status": "failed", "error": str(exc), "signals": None}
    except Exception as exc:  # a bug in a component: record it, the sweep goes on
        return {"status": "failed", "error": f"{type(exc).__name__}: {exc}\n{traceback.format_exc()}",
                "signals": None}


def sweep_hash(study: Study) -> str:
    return hashlib.sha256(json.dumps(study.to_data(), sort_keys=True, default=str).encode()).hexdigest()[:16]


class SweepRun:
    def __init__(self, study: Study, out_dir: Path) -> None:
        self.study, self.out = study, Path(out_dir)
        self.where = str(study.path)
        self.points = expand(study)
        self.fmt = study.study.signals_format
        self.points_dir = self.out / "points"

    # --- checks before anything runs ----------------------------------------------------------
    def validate(self) -> None:
        """Build every point (types, parameters, units, wiring) before running any."""
        from .output import check_output

        check_output(self.out, overwrite=True)
        for point in self.points:
            try:
                build_system(resolve(point_study(self.study, point)))
            except StudyError as exc:
                raise StudyError(f"{exc}\n  (sweep point {point.key}: {point.values}, seed {point.seed})") from None
        manifest = self.out / "sweep.json"
        digest = sweep_hash(self.study)
        if manifest.exists():
            old = json.loads(manifest.read_text())
            if old.get("hash") != digest:
                raise StudyError(f"{self.out}: holds results of a different sweep (study changed); "
                                 f"use another --out folder or remove it")
        else:
            write_json(manifest, {"study_file": self.where, "hash": digest,
                                  "points": [{"point": p.key, "seed": p.seed, **p.values} for p in self.points]})

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

    def store(self, point: Point, result: dict[str, Any]) -> dict[str, Any]:
        folder = self.points_dir / point.key
        if result.get("signals"):
            frame = pd.read_parquet(io.BytesIO(result["signals"]))
            if self.fmt == "parquet":
                atomic_write(folder / "signals.parquet", lambda p: p.write_bytes(result["signals"]))
            else:
                write_table(folder / "signals", frame, self.fmt)
        record = {"point": point.key, "seed": point.seed, "parameters": point.values,
                  "status": result["status"], "error": result.get("error"),
                  "metrics": {k: v for k, v in result.get("metrics", {}).items()
                              if isinstance(v, (int, float)) and not isinstance(v, bool)}}
        write_json(self.record_path(point), record)
        return record

    def table(self) -> pd.DataFrame:
        rows = []
        for point in self.points:
            path = self.record_path(point)
            if not path.exists():
                continue
            rec = json.loads(path.read_text())
            rows.append({"point": rec["point"], "seed": rec["seed"], **rec["parameters"],
                         "status": rec["status"], "error": rec["error"], **rec["metrics"]})
        return pd.DataFrame(rows)

    def write_table(self) -> Path:
        return write_table(self.out / "results", self.table(), self.fmt)

    # --- running ------------------------------------------------------------------------------
    def run(self, workers: int, scheduler: str | None = None, retry_failed: bool = False,
            progress: bool = True) -> pd.DataFrame:
        self.validate()
        for stale in self.out.glob("**/.*.tmp"):     # left by a killed run mid-write
            stale.unlink()
        done = self.finished(retry_failed)
        todo = [p for p in self.points if p.key not in done]
        bar = _progress(len(self.points), len(done), progress)
        failures = sum(1 for p in self.points if p.key in done
                       and json.loads(self.record_path(p).read_text())["status"] != "completed")
        try:
            for point, result in self._execute(todo, workers, scheduler):
                record = self.store(point, result)
                failures += record["status"] != "completed"
                bar.update(1)
                bar.set_postfix(failures=failures)
        finally:
            bar.close()
            self.write_table()
        return self.table()

    def _execute(self, todo: list[Point], workers: int, scheduler: str | None) -> Iterator[tuple[Point, dict]]:
        jobs = [(p, point_study(self.study, p)) for p in todo]
        if not jobs:
            return
        # one thread per point: parallelism comes from processes (BLAS threads spinning on tiny
        # matrices made two workers four times slower than one on two cores)
        for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
            os.environ.setdefault(var, "1")
        if scheduler is None:
            ctx = multiprocessing.get_context("spawn")
            with cf.ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=watch_parent,
                                        initargs=(os.getpid(),)) as pool:
                futures = {pool.submit(simulate_point, point): p for p, point in jobs}
                try:
                    for fut in cf.as_completed(futures):
                        yield futures[fut], _result(fut)
                except BaseException:
                    # interrupted: the points in flight are dropped (a rerun does them again) and
                    # their workers end now, not when their point would have finished
                    for proc in list((pool._processes or {}).values()):
                        proc.terminate()
                    pool.shutdown(wait=False, cancel_futures=True)
                    raise
            return
        yield from _execute_dask(jobs, workers, scheduler)


def _result(fut) -> dict[str, Any]:
    try:
        return fut.result()
    except Exception as exc:  # a worker process died (killed, out of memory)
        return {"status": "failed", "error": f"worker lost: {type(exc).__name__}: {exc}", "signals": None}


CONNECT_TIMEOUT = 6.0        # s: a wrong --scheduler address fails well within 10 s


class SchedulerError(StudyError):
    """The --scheduler address does not lead to a Dask scheduler (exit 2)."""


def _execute_dask(jobs, workers: int, scheduler: str):
    from distributed import Client, LocalCluster, as_completed

    cluster = None
    if scheduler == "local":
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    else:
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT)
        except (OSError, TimeoutError, ValueError) as exc:
            raise SchedulerError(f"--scheduler {scheduler}: no Dask scheduler answered within "
                                 f"{CONNECT_TIMEOUT:g} s ({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}); "
                                 f"expected an address like tcp://HOST:8786, or 'local'") from None
    try:
        futures = {client.submit(simulate_point, point, pure=False, key=f"{p.key}-{time.time_ns()}"): p
                   for p, point in jobs}
        for fut in as_completed(futures):
            yield futures[fut], _result(fut)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _progress(total: int, initial: int, enabled: bool):
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, desc="sweep points", unit="pt", disable=not enabled,
                dynamic_ncols=True)


def _parameter_unit(study: Study, name: str) -> str:
    """The declared SI unit of a swept 'component.parameter' ('' when unknown or a study field)."""
    comp, _, param = name.partition(".")
    try:
        declared = resolve(study).component_class(comp).declared("parameter")
    except (StudyError, KeyError, AttributeError):
        return "s" if name in ("study.stop_time", "study.base_step") else ""
    return declared[param].unit if param in declared else ""


def sweep_plots(study: Study, table: pd.DataFrame, out_dir: Path) -> list[Path]:
    """The metrics that matter against the first swept parameter (one line per other value / seed),
    and the sweep analysis module's own plots (``sweep.analysis``). The study's analysis module
    chooses them: ``SWEEP_METRICS`` {metric: bound drawn as a line, or None}; without it, every
    metric but counters and wall time (all stay in results.parquet)."""
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
    analysis = importlib.import_module(study.study.analysis) if study.study.analysis else None
    metric_units = dict(getattr(analysis, "METRIC_UNITS", {}))
    metric_units.update(sim_time_s="s", wall_time_s="s")
    chosen = getattr(analysis, "SWEEP_METRICS", None)
    metrics = [c for c in ok.columns if c not in skip and pd.api.types.is_numeric_dtype(ok[c])]
    metrics = [m for m in chosen if m in metrics] if chosen else [m for m in metrics if metric_units.get(m) != "count"]
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
        unit = metric_units.get(metric)
        bound = (chosen or {}).get(metric)
        if bound is not None:
            ax.axhline(bound, color="tab:red", ls="--", lw=1.2, label=f"bound {bound:g} {'' if unit in (None, '1', 'count') else unit}".rstrip())
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
        module = importlib.import_module(study.sweep.analysis)
        written += module.plots(table, study, out_dir)
    return written
