"""A crashing FMU is always named: a co-simulation FMU from outside the project runs in its own process
by default (a segmentation fault is a named error and the signals up to it are kept); a study that keeps
it in this process for speed is told so, and a fatal signal there still prints which component and which
call it was in."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from agrobot.orchestrator.engine import RunError
from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.study import load_study
from tests.fmu_build import build_test_fmu
from tests.test_fmu_isolation import FAIL_TIME, STEP, STUDY

ROOT = Path(__file__).resolve().parent.parent


def _study(folder: Path, name: str, isolate: str) -> Path:
    """The misbehaving FMU crashing at FAIL_TIME (fail_mode 1), ``isolate``: the study's line for it (or none)."""
    path = folder / name
    path.write_text(STUDY.format(mode=1, timeout=60.0).replace("isolate_fmus = true\n", isolate))
    return path


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    where = tmp_path_factory.mktemp("crashing")
    build_test_fmu("misbehaving", where)
    return where


def test_a_foreign_fmu_runs_isolated_by_default_and_its_crash_is_named_with_the_signals_kept(folder, tmp_path):
    study = _study(folder, "default.toml", "")
    with pytest.raises(RunError) as err:
        run_study(load_study(study), tmp_path / "out", plots=False, progress=False)
    assert "crashed (signal SIGSEGV) in doStep at t = 0.5 s" in str(err.value), str(err.value)
    frame = pd.read_csv(err.value.where / "signals.csv")
    assert list(frame["t"].round(9)) == [round(k * STEP, 9) for k in range(round(FAIL_TIME / STEP))]


def test_in_process_a_fatal_signal_names_the_component_and_the_call(folder, tmp_path):
    study = _study(folder, "in_process.toml", "isolate_fmus = false\n")
    done = subprocess.run([sys.executable, "-m", "agrobot", "run", str(study), "--out", str(tmp_path / "out"),
                           "--no-progress", "--engine", "python"], capture_output=True, text=True, timeout=120,
                          cwd=ROOT)
    assert done.returncode != 0
    assert "runs in this process, for speed" in done.stderr and "isolate_fmus = false" in done.stderr, done.stderr
    assert "Segmentation fault" in done.stderr and "FMU component 'm' (misbehaving.fmu): doStep" in done.stderr, \
        done.stderr
