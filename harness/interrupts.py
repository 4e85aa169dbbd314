"""Interrupting a running command as a user at a terminal does: Ctrl-C twice (SIGINT to its whole
process group, 0.3 s apart) once its work is in flight."""
from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path


def ctrl_c_twice_in_flight(proc: subprocess.Popen, running: Path, wait_s: float = 90.0, gap_s: float = 0.3) -> bool:
    """Wait until ``running`` (a sweep's ``.running`` folder) holds a point, then send SIGINT twice to
    ``proc``'s process group (``proc`` started with ``start_new_session=True``). False when the command
    ended or ``wait_s`` passed first (nothing was in flight to interrupt)."""
    end = time.time() + wait_s
    while time.time() < end and proc.poll() is None and not list(running.glob("p*")):
        time.sleep(0.1)
    started = proc.poll() is None and bool(list(running.glob("p*")))
    time.sleep(1.0)
    os.killpg(proc.pid, signal.SIGINT)
    time.sleep(gap_s)
    os.killpg(proc.pid, signal.SIGINT)
    return started
