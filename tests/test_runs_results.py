"""Runs that lose nothing and keep memory flat: an unfinished run never replaces a complete result,
the signals are streamed and read back by column, signals land as the same numbers as in memory."""
from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from agrobot.orchestrator.component import EndRun
from agrobot.orchestrator.errors import Interrupted, Terminated
from agrobot.orchestrator.runner import RunError, run_study
from agrobot.orchestrator.signal_table import SignalTable
from agrobot.orchestrator.study import load_study, parse_study
from tests import toy_components

ROOT = Path(__file__).resolve().parent.parent
CMD = [sys.executable, "-m", "agrobot"]


class EndsAt(toy_components.FailAt):
    """Asks to end the run at ``fail_time`` (a route that is complete): a whole result."""

    def step(self, t, dt):
        if t >= self.p["fail_time"] - 1e-12:
            raise EndRun(self.name, "done")
        self.y["value"] = t


def _toy(tmp_path: Path, type_: str, at: float, fmt: str = "csv"):
    return parse_study({"study": {"name": "toy", "stop_time": 1.0, "base_step": 0.05, "seed": 1, "signals_format": fmt},
                        "components": {"f": {"type": f"tests.toy_components:{type_}", "parameters": {"fail_time": at}}}},
                       tmp_path / "toy.toml")


def _status(folder: Path) -> str:
    return json.loads((folder / "metrics.json").read_text())["status"]


@pytest.mark.slow
def test_an_interrupted_rerun_keeps_the_complete_result_and_its_figures(tmp_path):
    """Ctrl-C on a rerun into a complete result: the result and its figures stay in --out as
    they were, the partial run goes beside it, named, and the message says both."""
    out = tmp_path / "f8"
    first = subprocess.run(CMD + ["run", "studies/figure8.toml", "--set", "study.stop_time=20", "--out", str(out)],
                           cwd=ROOT, capture_output=True, text=True)
    assert first.returncode == 0, first.stderr
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert {"trajectory.png", "signals.parquet", "metrics.json"} <= set(before)
    proc = subprocess.Popen(CMD + ["run", "studies/figure8.toml", "--set", "study.stop_time=1e5", "--out", str(out),
                                   "--no-plots", "--overwrite"], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    end = time.time() + 120
    while time.time() < end and not any(p.stat().st_size > 100_000 for p in tmp_path.glob(".f8.*/signals.parquet")):
        time.sleep(0.2)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and "Traceback" not in err, err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before          # byte for byte, figures too
    beside = tmp_path / "f8.interrupted"
    assert str(beside) in err and f"earlier result in {out} is untouched" in err
    assert _status(beside) == "interrupted" and len(pd.read_parquet(beside / "signals.parquet")) >= 10_000
    assert not list(tmp_path.glob(".f8.*"))          # no staging folder left, no lock file


def test_a_run_stopped_in_its_analysis_keeps_its_signals_and_the_earlier_result(tmp_path, monkeypatch):
    """SIGTERM while the analysis runs (after the simulation): exit 143, the complete signals kept
    beside the earlier result, which stays; an ended run (a component asked to stop) counts as whole."""
    monkeypatch.setattr(toy_components, "EndsAt", EndsAt, raising=False)
    out = tmp_path / "out"
    run_study(_toy(tmp_path, "EndsAt", 0.5), out)
    assert _status(out) == "ended"
    kept = (out / "signals.csv").read_bytes()

    import agrobot.analysis.figure8 as module

    def stopped(frame, study):
        raise Terminated()

    monkeypatch.setattr(module, "metrics", stopped)
    study = _toy(tmp_path, "FailAt", 5.0).with_values({"study.analysis": "agrobot.analysis.figure8"})
    with pytest.raises(Interrupted) as err:
        run_study(study, out, overwrite=True)
    assert err.value.exit_status == 143 and "in the analysis" in str(err.value)
    assert (out / "signals.csv").read_bytes() == kept and _status(out) == "ended"
    beside = out.with_name("out.interrupted")
    assert _status(beside) == "interrupted" and len(pd.read_csv(beside / "signals.csv")) == 21   # t = 0 .. 1 whole
    # a failed run beside it too, and a later complete run replaces the earlier one in place
    with pytest.raises(RunError) as failed:
        run_study(_toy(tmp_path, "FailAt", 0.5), out, overwrite=True)
    assert failed.value.where == out.with_name("out.failed") and _status(out) == "ended"
    monkeypatch.undo()
    run_study(_toy(tmp_path, "FailAt", 5.0), out, overwrite=True)
    assert _status(out) == "completed" and len(pd.read_csv(out / "signals.csv")) == 21


def test_a_folder_that_is_not_a_result_is_kept_when_the_run_does_not_finish(tmp_path):
    """A folder of other files is never replaced, --overwrite or not; an unfinished run never
    replaces a complete one: it goes beside it, under a free name."""
    from agrobot.orchestrator.output import OutputError

    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("precious")
    with pytest.raises(OutputError, match="notes.txt"):
        run_study(_toy(tmp_path, "FailAt", 5.0), out, overwrite=True)
    (out / "notes.txt").unlink()
    run_study(_toy(tmp_path, "FailAt", 5.0), out)
    with pytest.raises(RunError) as err:
        run_study(_toy(tmp_path, "FailAt", 0.5), out, overwrite=True)
    assert _status(out) == "completed" and err.value.where == tmp_path / "mine.failed"
    (tmp_path / "mine.failed").rename(tmp_path / "other")
    (tmp_path / "mine.failed").mkdir()
    (tmp_path / "mine.failed" / "x.txt").write_text("not a result")
    with pytest.raises(RunError) as err:
        run_study(_toy(tmp_path, "FailAt", 0.5), out, overwrite=True)
    assert err.value.where == tmp_path / "mine.failed-2" and (tmp_path / "mine.failed" / "x.txt").exists()


def test_the_streamed_signals_read_by_column_are_the_numbers_of_the_run_in_memory(tmp_path):
    """figure-8, 60 s: the folder's signals and metrics are bit for bit those of the same run in
    memory, and the analysis read only the columns it uses."""
    study = load_study(ROOT / "studies" / "figure8.toml", ["study.stop_time=60"])
    memory = run_study(study, None, plots=False)
    folder = run_study(study, tmp_path / "f8", plots=False)
    whole = pd.read_parquet(tmp_path / "f8" / "signals.parquet")
    assert list(whole.columns) == list(memory.frame.columns) and len(whole) == len(memory.frame) == 6001
    for c in whole.columns:
        assert np.array_equal(whole[c].to_numpy(), memory.frame[c].to_numpy()), c
    same = lambda m: json.dumps({k: v for k, v in m.items() if k != "wall_time_s"}, sort_keys=True)  # noqa: E731
    assert np.isfinite(folder.metrics["euclid_max_straight"]) and same(folder.metrics) == same(memory.metrics)
    # the analysis of a fresh table reads a few columns, never the whole width
    table = SignalTable(tmp_path / "f8" / "signals.parquet")
    import agrobot.analysis.figure8 as module

    module.metrics(table, study)
    assert 5 <= len(table._columns.read) < len(whole.columns) / 2


@pytest.mark.parametrize("fmt", ["parquet", "csv"])
def test_a_signal_table_answers_as_the_data_frame_does(tmp_path, fmt):
    rng = np.random.default_rng(3)
    frame = pd.DataFrame({"t": np.arange(1000) * 0.01, "a.x": rng.normal(size=1000), "b.y": rng.normal(size=1000) * 1e-7})
    path = tmp_path / f"s.{fmt}"
    frame.to_parquet(path, index=False) if fmt == "parquet" else frame.to_csv(path, index=False)
    table = SignalTable(path)
    assert len(table) == 1000 and list(table.columns) == list(frame.columns) and "a.x" in table and "z" not in table
    pd.testing.assert_series_equal(table["a.x"], frame["a.x"])
    for rows in (slice(100, None), slice(None, None, 7), slice(10, 500, 3)):
        view, expected = table.iloc[rows], frame.iloc[rows]
        pd.testing.assert_series_equal(view["b.y"], expected["b.y"])
        assert len(view) == len(expected) and view["t"].iloc[0] == expected["t"].iloc[0]
        pd.testing.assert_series_equal(view.reset_index(drop=True)["t"], expected.reset_index(drop=True)["t"])
    pd.testing.assert_frame_equal(table.to_pandas(), frame)
    with pytest.raises(KeyError):
        table["nope"]


def test_the_recorders_hold_at_most_two_blocks_while_a_long_run_streams(tmp_path, monkeypatch):
    """Memory flat in the run's length: the rows in memory never exceed two blocks, whatever the
    number of steps; the file gets one row group per block."""
    import agrobot.orchestrator.runner as runner
    from agrobot.orchestrator.engine import Simulation

    monkeypatch.setattr(runner, "CHUNK_STEPS", 200)
    monkeypatch.setattr(runner, "CHUNK_BYTES", 0)
    held = []
    advance = Simulation.advance

    def watched(self, k_end, final=False):
        advance(self, k_end, final)
        held.append(max((len(b.buf) // b.width for b in self.recorder._buffers), default=0))

    monkeypatch.setattr(Simulation, "advance", watched)
    study = parse_study({"study": {"name": "long", "stop_time": 50.0, "base_step": 0.01, "seed": 1},
                         "components": {"g": {"type": "tests.toy_components:FailAt", "parameters": {"fail_time": 1e9}}}},
                        tmp_path / "long.toml")
    run_study(study, tmp_path / "out", plots=False)
    import pyarrow.parquet as pq

    meta = pq.ParquetFile(tmp_path / "out" / "signals.parquet").metadata
    assert meta.num_rows == 5001 and meta.num_row_groups >= 5001 // 400
    assert len(held) > 10 and max(held) <= 2 * 200
