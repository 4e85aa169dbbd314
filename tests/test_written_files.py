"""Every single file a run writes is under the rule of ``--out`` (orchestrator.output): ``--mcap FILE`` and
the recordings of ``--record`` (output parameters) are refused over an existing file without
``--overwrite``, written under a unique temporary name and renamed, one writer at a time; a full disk is a
named error that leaves nothing behind; the MCAP is streamed from the signal table in bounded memory."""
from __future__ import annotations

import errno
import json
import resource
import signal
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tests.commands import in_process as _cli
from agrobot.orchestrator.output import OutputError, OutputLock

pytest.importorskip("foxglove")
mcap_reader = pytest.importorskip("mcap.reader")
ROOT = Path(__file__).resolve().parent.parent

TOY = """[study]
name = "toy"
stop_time = {stop}
base_step = 0.01
seed = 1

[components.clock]
type = "tests.toy_components:Clock"
{extra}"""

RECORDER = """
[components.r]
type = "tests.test_command_rules:Recorder"
"""


def _study(tmp_path: Path, stop: float = 1.0, extra: str = "", name: str = "toy.toml") -> Path:
    path = tmp_path / name
    path.write_text(TOY.format(stop=stop, extra=extra))
    return path


def _messages(path: Path) -> list[float]:
    """The ``t`` of every message of an MCAP file, read to its end (a damaged file raises)."""
    with open(path, "rb") as f:
        return [json.loads(m.data)["t"] for _, _, m in mcap_reader.make_reader(f).iter_messages()]


def _hidden(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


def test_an_mcap_is_not_written_over_a_file_without_overwrite(tmp_path, capsys):
    study = _study(tmp_path)
    target = tmp_path / "run.mcap"
    target.write_bytes(b"someone's file")
    code, _, err = _cli(["run", study, "--out", tmp_path / "o1", "--mcap", target], capsys)
    assert code == 2 and "--mcap" in err and "exists" in err and "--overwrite" in err, err
    assert target.read_bytes() == b"someone's file" and not (tmp_path / "o1").exists()
    code, _, err = _cli(["run", study, "--out", tmp_path / "o2", "--mcap", target, "--overwrite"], capsys)
    assert code == 0, err
    assert _messages(target) == pytest.approx(np.arange(101) * 0.01)      # t = 0 .. 1 s, every base step
    assert _hidden(tmp_path) == []


def test_a_second_run_into_the_same_mcap_is_refused_while_the_first_writes(tmp_path, capsys):
    target = tmp_path / "run.mcap"
    with OutputLock(target, "--mcap"):
        code, _, err = _cli(["run", _study(tmp_path), "--out", tmp_path / "o", "--mcap", target], capsys)
    assert code == 2 and "--mcap" in err and "another run" in err, err
    assert not target.exists()


def test_two_writers_of_one_mcap_never_share_a_temporary_file(tmp_path):
    from agrobot.orchestrator.mcap_out import write_run_mcap

    rows = 20_000
    frame = pd.DataFrame({"t": np.arange(rows) * 1e-3, "a.x": np.arange(rows, dtype=float)})
    target, errors = tmp_path / "both.mcap", []

    def write():
        try:
            write_run_mcap(target, frame, ratios={}, units={}, descriptions={})
        except Exception as exc:      # noqa: BLE001 - collected for the assertion
            errors.append(exc)
    threads = [threading.Thread(target=write) for _ in range(2)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert errors == [] and len(_messages(target)) == rows
    assert _hidden(tmp_path) == []


def test_a_full_disk_while_writing_the_mcap_is_named_and_leaves_nothing(tmp_path, capsys):
    """The file size limit (RLIMIT_FSIZE) stands for a disk that fills: the writer's write fails with an
    OSError, as on a full disk."""
    from agrobot.orchestrator.mcap_out import write_run_mcap

    rows = 50_000
    frame = pd.DataFrame({"t": np.arange(rows) * 1e-3, "a.x": np.sin(np.arange(rows)), "a.y": np.arange(rows) * 1.0})
    target = tmp_path / "full.mcap"
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    before = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (200_000, hard))
    try:
        with pytest.raises(OutputError) as refused:
            write_run_mcap(target, frame, ratios={}, units={}, descriptions={})
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
        signal.signal(signal.SIGXFSZ, before)
    assert str(target) in str(refused.value) and "nothing was left" in str(refused.value)
    assert list(tmp_path.iterdir()) == []
    # ENOSPC itself, through the command: exit 2, the disk named, the run's results in place, no MCAP and no temp
    from agrobot.orchestrator import mcap_out

    def full(self, data):        # the file's write failing as on a full disk, kept as the sink keeps it
        self.error = self.error or OSError(errno.ENOSPC, "No space left on device")
        raise self.error
    study = _study(tmp_path)
    original = mcap_out._Sink.write
    mcap_out._Sink.write = full
    try:
        code, _, err = _cli(["run", study, "--out", tmp_path / "o", "--mcap", tmp_path / "m.mcap"], capsys)
    finally:
        mcap_out._Sink.write = original
    assert code == 2 and "disk is full" in err and "m.mcap" in err and "Traceback" not in err, err
    assert not (tmp_path / "m.mcap").exists() and (tmp_path / "o" / "run.json").exists()
    assert _hidden(tmp_path) == []


MEASURE = """
import resource, sys
import foxglove, pyarrow.parquet
from agrobot.orchestrator.mcap_out import write_run_mcap
from agrobot.orchestrator.signal_table import SignalTable
table = SignalTable(sys.argv[1])
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
write_run_mcap(sys.argv[2], table, ratios={c.partition('.')[0]: 500 for c in table.columns}, units={}, descriptions={})
print((resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) * 1024)
"""


@pytest.mark.slow
def test_the_mcap_of_a_long_run_is_streamed_in_bounded_memory(tmp_path):
    """A signal table written as a run writes it (row groups of 2,000 rows) of 192 MB: writing its MCAP
    holds a few row groups, not the table."""
    from agrobot.orchestrator.atomic_files import SignalWriter

    rows, width = 60_000, 400
    columns = [f"c{j // 50}.o{j}" for j in range(width)]
    writer = SignalWriter(tmp_path / "signals", columns, "parquet")
    rng = np.random.default_rng(0)
    for a in range(0, rows, 2000):
        block = np.column_stack([np.arange(a, a + 2000) * 1e-3, rng.normal(size=(2000, width))])
        writer.append(block)
    table_bytes = rows * (width + 1) * 8
    done = subprocess.run([sys.executable, "-c", MEASURE, str(writer.close()), str(tmp_path / "long.mcap")],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    grew = int(done.stdout.split()[-1])
    assert grew < 0.5 * table_bytes, f"writing the MCAP grew the process by {grew / 1e6:.0f} MB " \
                                     f"(table {table_bytes / 1e6:.0f} MB)"
    assert len(_messages(tmp_path / "long.mcap")) == 8 * rows // 500


def test_a_recording_outside_out_is_refused_over_a_file_and_written_aside(tmp_path, capsys):
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me\n")
    study = _study(tmp_path, extra=RECORDER)
    code, _, err = _cli(["run", study, "--out", tmp_path / "o1", "--set", f"r.record_file={victim}"], capsys)
    assert code == 2 and "exists" in err and "--overwrite" in err and str(victim) in err, err
    assert victim.read_text() == "keep me\n" and not (tmp_path / "o1").exists()
    code, _, err = _cli(["run", study, "--out", tmp_path / "o2", "--set", f"r.record_file={victim}", "--overwrite"],
                        capsys)
    assert code == 0, err
    assert [float(v) for v in victim.read_text().split()] == pytest.approx(np.arange(101) * 0.01)   # replaced whole
    assert _hidden(tmp_path) == []


def test_record_refuses_an_earlier_recording_without_overwrite(tmp_path, capsys):
    folder = tmp_path / "rec"
    folder.mkdir()
    (folder / "gps.nmea").write_text("an earlier drive\n")
    study = ROOT / "studies" / "field_test.toml"
    code, _, err = _cli(["run", study, "--out", tmp_path / "o", "--record", folder, "--set", "study.stop_time=0.5",
                         "--no-plots"], capsys)
    assert code == 2 and "gps.nmea" in err and "exists" in err, err
    assert (folder / "gps.nmea").read_text() == "an earlier drive\n" and not (tmp_path / "o").exists()
