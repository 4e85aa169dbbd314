"""The command line as the tests call it: ``cli("run", study, "--out", out)`` runs
``python -m agrobot`` from the repository root; ``refused(proc, *words)`` asserts a clean refusal
(exit 2, no traceback, the words in the message)."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def cli(*args, timeout: float = 300, cwd: Path = ROOT) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "agrobot", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=timeout)


def refused(proc: subprocess.CompletedProcess, *words: str) -> str:
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    for w in words:
        assert w in proc.stderr, (w, proc.stderr)
    return proc.stderr
