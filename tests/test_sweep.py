"""Parameter sweeps: same metrics as separate runs, resumable after a kill, Dask equals the
process pool, bad sweeps refused before anything runs."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.study import Study, StudyError, load_study
from agrobot.orchestrator.sweep import SweepRun, expand
from tests.commands import cli

ROOT = Path(__file__).resolve().parents[1]
SHORT = "study.stop_time=20.0"


def sweep_file(tmp_path, body, name="sweep.toml"):
    path = tmp_path / name
    path.write_text(f'extends = "{ROOT / "studies/figure8.toml"}"\n{body}')
    return path


THREE = '[sweep]\nmode = "zip"\nseeds = [5]\n[sweep.parameters]\n"reference.speed" = [1.5, 2.0, 2.5]\n' \
        '"tracker.k_c" = [1.5, 1.5, 1.2]\n'


def comparable(table: pd.DataFrame) -> pd.DataFrame:
    return table.drop(columns=["wall_time_s"]).sort_values("point").reset_index(drop=True)


def run_sweep(path, out, workers=2, scheduler=None, overrides=(SHORT,)):
    return SweepRun(Study.load(path, overrides), out).run(workers, scheduler, progress=False)


def test_points_expand_as_grid_or_zip_with_seeds(tmp_path):
    grid = load_study(sweep_file(tmp_path, '[sweep]\nseeds = [1, 2]\n[sweep.parameters]\n'
                                 '"reference.speed" = {start = 1.0, stop = 2.0, step = 0.5}\n"tracker.k_c" = [1, 2]\n'))
    points = expand(grid)
    assert len(points) == 3 * 2 * 2
    assert {(p.values["reference.speed"], p.values["tracker.k_c"], p.seed) for p in points} == {
        (v, k, s) for v in (1.0, 1.5, 2.0) for k in (1, 2) for s in (1, 2)}
    zipped = load_study(sweep_file(tmp_path, THREE))
    assert [p.values for p in expand(zipped)] == [{"reference.speed": 1.5, "tracker.k_c": 1.5},
                                                  {"reference.speed": 2.0, "tracker.k_c": 1.5},
                                                  {"reference.speed": 2.5, "tracker.k_c": 1.2}]


@pytest.mark.slow
def test_three_point_sweep_equals_three_separate_runs(tmp_path):
    path = sweep_file(tmp_path, THREE)
    table = run_sweep(path, tmp_path / "out")
    assert list(table["status"]) == ["completed"] * 3
    for _, row in table.iterrows():
        single = run_study(load_study(ROOT / "studies/figure8.toml",
                                      [SHORT, "study.seed=5", f"reference.speed={row['reference.speed']}",
                                       f"tracker.k_c={row['tracker.k_c']}"]), None, plots=False).metrics
        for key, value in single.items():
            if isinstance(value, float) and key != "wall_time_s":
                assert row[key] == value or (pd.isna(row[key]) and pd.isna(value)), key
    # each point's full signal table is kept beside it
    signals = pd.read_parquet(tmp_path / "out/points/p0001/signals.parquet")
    assert signals["reference.speed_ref"].max() == pytest.approx(2.0)
    assert pd.read_parquet(tmp_path / "out/results.parquet").shape[0] == 3


@pytest.mark.slow
def test_killed_sweep_resumes_without_rerunning_finished_points(tmp_path):
    body = '[sweep]\nseeds = [3]\n[sweep.parameters]\n"reference.speed" = [1.0, 1.5, 2.0, 2.5]\n'
    path = sweep_file(tmp_path, body)
    out = tmp_path / "interrupted"
    cmd = [sys.executable, "-m", "agrobot", "sweep", str(path), "--out", str(out), "--workers", "1",
           "--set", SHORT, "--no-progress", "--no-plots", "--engine", "python"]     # points that take a while
    proc = subprocess.Popen(cmd, cwd=ROOT, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 120
    while not (out / "points/p0001/metrics.json").exists():
        assert time.time() < deadline and proc.poll() is None
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    finished = {p.parent.name: p.stat().st_mtime_ns for p in out.glob("points/*/metrics.json")}
    assert 2 <= len(finished) < 4
    rerun = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    assert rerun.returncode == 0, rerun.stderr
    assert not list(out.rglob("*.tmp"))
    for name, mtime in finished.items():                 # no finished point was run again
        assert (out / "points" / name / "metrics.json").stat().st_mtime_ns == mtime
    resumed = pd.read_parquet(out / "results.parquet")
    whole = run_sweep(path, tmp_path / "whole", workers=2)
    pd.testing.assert_frame_equal(comparable(resumed), comparable(whole), check_exact=True)


@pytest.mark.slow
def test_dask_local_cluster_gives_the_same_table(tmp_path):
    path = sweep_file(tmp_path, THREE)
    pool = run_sweep(path, tmp_path / "pool", workers=2)
    dask = run_sweep(path, tmp_path / "dask", workers=2, scheduler="local")
    pd.testing.assert_frame_equal(comparable(pool), comparable(dask), check_exact=True)


@pytest.mark.parametrize("body, words", [
    ('[sweep]\n[sweep.parameters]\n"reference.sped" = [1.0, 2.0]\n', ["unknown parameter", "sped", "sweep point"]),
    ('[sweep]\n[sweep.parameters]\n"referee.speed" = [1.0, 2.0]\n', ["no component 'referee'"]),
    ('[sweep]\n[sweep.parameters]\n"reference.speed" = {start = 2.0, stop = 1.0, step = 0.5}\n', ["empty range"]),
    ('[sweep]\n[sweep.parameters]\n"reference.speed" = []\n', ["empty list"]),
    ('[sweep]\nmode = "zip"\n[sweep.parameters]\n"reference.speed" = [1.0, 2.0]\n"tracker.k_c" = [1.0]\n',
     ["equal length"]),
    ('[sweep]\n[sweep.parameters]\n"reference.speed" = ["3 deg"]\n', ["expected 'm/s'"]),
])
def test_bad_sweeps_fail_before_running_anything(tmp_path, body, words):
    path = sweep_file(tmp_path, body)
    out = tmp_path / "out"
    proc = cli("sweep", str(path), "--out", str(out), "--no-progress")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    for w in words:
        assert w in proc.stderr
    assert not (out / "points").exists()


def test_a_failing_point_is_recorded_and_the_sweep_goes_on(tmp_path):
    path = sweep_file(tmp_path, '[sweep]\n[sweep.parameters]\n"reference.speed" = [1.5, -1.0, 2.0]\n')
    table = run_sweep(path, tmp_path / "out")
    assert list(table["status"]) == ["completed", "failed", "completed"]
    assert "speed must be > 0" in table["error"].iloc[1]


def test_a_changed_study_is_not_mixed_into_old_results(tmp_path):
    path = sweep_file(tmp_path, THREE)
    run_sweep(path, tmp_path / "out")
    with pytest.raises(StudyError, match="different sweep"):
        run_sweep(path, tmp_path / "out", overrides=(SHORT, "tracker.k_s=0.5"))


def test_monte_carlo_draws_are_seeded_within_their_ranges_and_distinct(tmp_path):
    body = ('[sweep]\nmode = "monte_carlo"\nsamples = 400\n[sweep.parameters]\n'
            '"reference.speed" = { uniform = [1.0, 2.5] }\n"tracker.k_c" = [1.0, 1.5, 2.0]\n')
    study = load_study(sweep_file(tmp_path, body))
    points = expand(study)
    again = expand(load_study(sweep_file(tmp_path, body)))
    assert [(p.values, p.seed) for p in points] == [(p.values, p.seed) for p in again]      # the study's seed
    speeds = np.array([p.values["reference.speed"] for p in points])
    assert speeds.min() >= 1.0 and speeds.max() <= 2.5 and abs(speeds.mean() - 1.75) < 0.06
    counts = {v: sum(p.values["tracker.k_c"] == v for p in points) for v in (1.0, 1.5, 2.0)}
    assert all(100 < c < 170 for c in counts.values())                                      # uniform choice
    assert len({p.seed for p in points}) == 400
    other = expand(load_study(sweep_file(tmp_path, body), ["study.seed=5"]))
    assert [p.values for p in other] != [p.values for p in points]


@pytest.mark.parametrize("body, words", [
    ('[sweep]\nmode = "monte_carlo"\n[sweep.parameters]\n"reference.speed" = { uniform = [1.0, 2.5] }\n', ["needs 'samples'"]),
    ('[sweep]\n[sweep.parameters]\n"reference.speed" = { uniform = [1.0, 2.5] }\n', ["need mode = 'monte_carlo'"]),
    ('[sweep]\nmode = "monte_carlo"\nsamples = 3\n[sweep.parameters]\n"reference.speed" = { uniform = [2.5, 1.0] }\n',
     ["low <= high"]),
])
def test_bad_monte_carlo_sections_are_refused_by_field(tmp_path, body, words):
    with pytest.raises(StudyError) as err:
        load_study(sweep_file(tmp_path, body))
    for w in words:
        assert w in str(err.value)
    assert "sweep" in str(err.value)


@pytest.mark.slow
def test_robustness_study_runs_on_the_sweep_machinery_and_summarises(tmp_path):
    """A short version of studies/robustness.toml (6 draws, 40 s): every point completes, the
    summary counts them and its percentiles match the table."""
    from agrobot.analysis.robustness import summarise

    study = Study.load(ROOT / "studies" / "robustness.toml", ["sweep.samples=6", "study.stop_time=40"])
    table = SweepRun(study, tmp_path / "mc").run(2, progress=False)
    assert list(table["status"]) == ["completed"] * 6
    s = summarise(table)
    assert s["runs"] == 6 and s["euclid_max_curved"]["max"] == pytest.approx(table["euclid_max_curved"].max())
    assert 0.0 <= s["within_bounds"] <= 1.0
    from agrobot.orchestrator.sweep import sweep_plots

    files = sweep_plots(study, table, tmp_path / "mc" / "plots")
    assert {p.name for p in files} >= {"max_error_vs_delay.png", "robustness.json"}
