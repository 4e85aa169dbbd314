"""The crash-readable copy of the signals (``signals.partial.arrows``, atomic_files.SignalWriter.spill)
is written by a run that loads a binary into this process, and by that run only: a later run in the
same process without one writes none. Truth: the calls to ``spill`` counted, and the rows of the
stream read back against x = t of the misbehaving FMU (fail_mode 0: it behaves)."""
from __future__ import annotations

import numpy as np

from agrobot.orchestrator import fatal_calls
from agrobot.orchestrator.atomic_files import SignalWriter, read_partial
from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.study import load_study
from tests.fmu_build import build_test_fmu

IN_PROCESS = """[study]
name = "in_process"
stop_time = 1.0
base_step = 0.1
seed = 1
isolate_fmus = false
[components.m]
type = "misbehaving.fmu"
parameters = { fail_time = 100.0, fail_mode = 0 }
"""
PYTHON_ONLY = """[study]
name = "python_only"
stop_time = 1.0
base_step = 0.1
seed = 1
[components.clock]
type = "tests.toy_components:Clock"
"""


def test_only_the_run_that_loads_a_binary_spills_and_the_next_run_does_not(tmp_path, monkeypatch):
    build_test_fmu("misbehaving", tmp_path)
    (tmp_path / "fmu.toml").write_text(IN_PROCESS)
    (tmp_path / "toy.toml").write_text(PYTHON_ONLY)
    spilled: list[str] = []
    real = SignalWriter.spill

    def counted(self):
        spilled.append(self.path.parent.name)
        return real(self)
    monkeypatch.setattr(SignalWriter, "spill", counted)
    run_study(load_study(tmp_path / "fmu.toml"), tmp_path / "first", plots=False, progress=False)
    assert len(spilled) == 1 and not fatal_calls.watching()
    run_study(load_study(tmp_path / "toy.toml"), tmp_path / "second", plots=False, progress=False)
    assert len(spilled) == 1, spilled
    assert not list(tmp_path.rglob("*.partial.arrows"))


def test_the_partial_stream_reads_back_its_rows_and_units(tmp_path):
    writer = SignalWriter(tmp_path / "signals", ["m.x"], "parquet", {"t": "s", "m.x": "m"})
    where = writer.spill()
    t = np.arange(5) * 0.1
    writer.append(np.column_stack([t, 2 * t]))
    frame = read_partial(where)
    assert frame.attrs["units"] == {"t": "s", "m.x": "m"}
    assert np.array_equal(frame["t"].to_numpy(), t) and np.array_equal(frame["m.x"].to_numpy(), 2 * t)
    writer.close()
    assert not where.exists()
