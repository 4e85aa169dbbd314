"""A file past the largest size the file system or the process allows (EFBIG) is met as a full disk
is: a named error (exit 2, no traceback) saying so, nothing left in or beside ``--out``. The process's
file size limit (RLIMIT_FSIZE, SIGXFSZ ignored) makes the write fail with EFBIG, as a file system's
largest file does."""
from __future__ import annotations

import errno
import resource
import signal
import subprocess
import sys
from pathlib import Path

from agrobot.orchestrator.output import disk_full, disk_full_error

ROOT = Path(__file__).resolve().parent.parent
LIMIT = 50_000              # bytes: the signals of 60 s at 10 ms (6,001 rows of t and value) pass it
TOY = """[study]
name = "toy"
stop_time = 60.0
base_step = 0.01
seed = 1
signals_format = "csv"
[components.clock]
type = "tests.toy_components:Clock"
"""


def _limited() -> None:
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (LIMIT, LIMIT))


def test_efbig_is_taken_as_no_room_and_said_as_such(tmp_path):
    exc = OSError(errno.EFBIG, "File too large", str(tmp_path / "signals.csv"))
    assert disk_full(exc) and disk_full(OSError(errno.ENOSPC, "No space left on device"))
    text = str(disk_full_error(tmp_path / "out", exc, "it holds what it held before"))
    assert "a file grew past the largest size allowed here (File too large) while writing signals.csv" in text
    assert "disk is full" not in text


def test_a_run_whose_signals_pass_the_file_size_limit_is_a_named_error_with_nothing_left(tmp_path):
    study = tmp_path / "toy.toml"
    study.write_text(TOY)
    done = subprocess.run([sys.executable, "-m", "agrobot", "run", str(study), "--out", str(tmp_path / "out"),
                           "--no-progress", "--no-plots", "--engine", "python"], capture_output=True, text=True,
                          cwd=ROOT, timeout=120, preexec_fn=_limited)
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert f"--out {tmp_path / 'out'}: a file grew past the largest size allowed here" in done.stderr, done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["toy.toml"]
