"""The API's doors for identify and sweep, and results loaded back: each command's files written
through the command line and through agrobot.api alike, and ``agrobot.load_result(folder)`` giving
back the typed result that wrote the folder (its data equal to the one in memory)."""
from __future__ import annotations

import math
import os
from pathlib import Path

import pandas as pd
import pytest

import agrobot
from agrobot.orchestrator.errors import InputError
from harness.truth_tractor import make_log
from tests.test_two_doors import same_files

SWEEP = "speed_sweep"
SHORT = {"study.stop_time": 20}


def _same_values(a: dict, b: dict) -> None:
    assert a.keys() == b.keys()
    for k in a:
        both_nan = isinstance(a[k], float) and math.isnan(a[k]) and math.isnan(b[k])
        assert both_nan or a[k] == b[k], k


def _log(tmp_path: Path) -> Path:
    path = tmp_path / "drive.csv"
    make_log(3, None, duration=60.0)[0].to_csv(path, index=False)
    return path


@pytest.mark.slow
def test_identify_writes_alike_through_both_doors_and_loads_back(cli, tmp_path):
    log = _log(tmp_path)
    proc = cli("identify", log, "--method", "driving", "--out", tmp_path / "cli", "--no-plots")
    assert proc.returncode == 0, proc.stderr
    found = agrobot.identify(log, method="driving", out=tmp_path / "api", plots=False)
    same_files(tmp_path / "cli", tmp_path / "api")
    loaded = agrobot.load_result(tmp_path / "api")
    assert isinstance(loaded, agrobot.Identification) and loaded.method == "driving"
    assert loaded.summary() == found.summary()


def test_a_run_loads_back_as_it_ran(tmp_path):
    ran = agrobot.run("figure8", SHORT, out=tmp_path / "run", plots=False)
    loaded = agrobot.load_result(tmp_path / "run")
    assert isinstance(loaded, agrobot.RunResult)
    pd.testing.assert_frame_equal(loaded.signals, ran.signals, check_dtype=False)
    _same_values(loaded.values, ran.values)
    assert loaded.failed == ran.failed and loaded.study.study.stop_time == 20


@pytest.mark.slow
def test_sweep_runs_on_every_core_by_default_and_alike_through_both_doors(cli, tmp_path, monkeypatch):
    seen = []
    from agrobot.orchestrator import sweep as sweep_module

    real = sweep_module.SweepRun.run
    monkeypatch.setattr(sweep_module.SweepRun, "run", lambda self, workers, *a, **k: seen.append(workers)
                        or real(self, workers, *a, **k))
    found = agrobot.sweep(SWEEP, SHORT, out=tmp_path / "api")
    assert seen == [os.cpu_count()]
    proc = cli("sweep", "studies/speed_sweep.toml", "--set", "study.stop_time=20", "--out", tmp_path / "cli",
               "--no-progress")
    assert proc.returncode == 0, proc.stderr
    api, cmd = (pd.read_parquet(tmp_path / side / "results.parquet") for side in ("api", "cli"))
    volatile = [c for c in api.columns if "wall" in c]
    pd.testing.assert_frame_equal(api.drop(columns=volatile), cmd.drop(columns=volatile), check_dtype=False)
    assert found.folder == tmp_path / "api"


def test_a_sweep_in_memory_saves_and_loads_back(tmp_path):
    found = agrobot.sweep(SWEEP, SHORT, workers=2, engine="compiled")
    folder = found.save(tmp_path / "kept")
    loaded = agrobot.load_result(folder)
    assert isinstance(loaded, agrobot.SweepResult) and loaded.engine == "compiled"
    pd.testing.assert_frame_equal(loaded.table, found.table, check_dtype=False)
    assert loaded.summary == found.summary


def test_a_folder_of_no_result_is_refused_by_name(tmp_path):
    (tmp_path / "notes").mkdir()
    (tmp_path / "notes" / "a.txt").write_text("x")
    with pytest.raises(InputError, match="holds none of run.json, sweep.json"):
        agrobot.load_result(tmp_path / "notes")
    with pytest.raises(InputError, match="no such folder"):
        agrobot.load_result(tmp_path / "absent")
    (tmp_path / "half").mkdir()
    (tmp_path / "half" / "run.json").write_text("{}")
    with pytest.raises(InputError, match="metrics.json: missing"):
        agrobot.load_result(tmp_path / "half")
