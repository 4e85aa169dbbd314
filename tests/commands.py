"""The command line as the tests call it: ``cli("run", study, "--out", out)`` runs
``python -m agrobot`` from the repository root; ``refused(proc, *words)`` asserts a clean refusal
(exit 2, no traceback, the words in the message).

Each command runs in a process of its own, forked from one that has already imported the command
line (multiprocessing's forkserver, its modules loaded once per test process): the same module run
as ``__main__`` with the same arguments, working folder, module search path and environment, its own
exit code, standard output and error, without the 1.5 CPU s an interpreter spends starting and
importing numpy, pandas and scipy for each call. ``AGROBOT_TEST_CLI=subprocess``, or an environment
changed since the forkserver started (a variable a module reads as it is imported), runs the real
``python -m agrobot``.

Imported where used: atexit, runpy and traceback (in the forked command only)."""
from __future__ import annotations

import json
import multiprocessing
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PRELOAD = ["agrobot.extras", "agrobot.orchestrator.cli",         # what agrobot.__main__ imports at the top
           "agrobot.analysis.margins", "agrobot.orchestrator.atomic_files", "agrobot.measurements.cli"]  # and main()
_IGNORED = {"PYTEST_CURRENT_TEST"}      # pytest's per-test variable: read by no module as it loads
_server: dict = {}
forked_cpu_seconds = 0.0                # the forked commands' CPU time (a forkserver's child is not ours to wait)


def cli(*args, timeout: float = 300, cwd: Path = ROOT) -> subprocess.CompletedProcess:
    command = [sys.executable, "-m", "agrobot", *map(str, args)]
    if os.environ.get("AGROBOT_TEST_CLI") == "subprocess" or not _server_matches():
        return subprocess.run(command, capture_output=True, text=True, cwd=cwd, timeout=timeout)
    return _forked(command, timeout, Path(cwd))


def refused(proc: subprocess.CompletedProcess, *words: str) -> str:
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    for w in words:
        assert w in proc.stderr, (w, proc.stderr)
    return proc.stderr


def _environment() -> dict:
    return {k: v for k, v in os.environ.items() if k not in _IGNORED}


def _server_matches() -> bool:
    """The forkserver, started on first use with this environment and the module path a fresh
    ``python -m`` has (sys.path without the working folder); False when the environment changed."""
    if not _server:
        fresh = subprocess.run([sys.executable, "-c", "import json, sys; print(json.dumps(sys.path[1:]))"], capture_output=True,
                               text=True, cwd=ROOT, check=True)
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(PRELOAD)
        _server.update(context=context, environment=_environment(), sys_path=json.loads(fresh.stdout))
    return _server["environment"] == _environment()


def _forked(command: list[str], timeout: float, cwd: Path) -> subprocess.CompletedProcess:
    with tempfile.TemporaryDirectory() as folder:
        out, err, cpu = (Path(folder) / name for name in ("stdout", "stderr", "cpu"))
        out.touch()
        err.touch()
        process = _server["context"].Process(target=_run_agrobot, daemon=False,
                                             args=(command[3:], str(cwd), str(out), str(err), str(cpu),
                                                   _server["sys_path"], dict(os.environ)))
        process.start()
        process.join(timeout)
        if process.is_alive():
            process.kill()
            process.join()
            raise subprocess.TimeoutExpired(command, timeout, out.read_text(), err.read_text())
        global forked_cpu_seconds
        forked_cpu_seconds += float(cpu.read_text()) if cpu.exists() else 0.0
        return subprocess.CompletedProcess(command, process.exitcode, out.read_text(), err.read_text())


def _run_agrobot(args, cwd, out, err, cpu, sys_path, environment):
    """``python -m agrobot ARGS`` in a forked process: its output to the two files, the exit code
    as the interpreter gives it (SystemExit's code; 1 and the traceback for an exception)."""
    import atexit
    import runpy
    import traceback

    os.dup2(os.open(out, os.O_WRONLY), 1)
    os.dup2(os.open(err, os.O_WRONLY), 2)
    os.chdir(cwd)
    os.environ.clear()
    os.environ.update(environment)
    sys.path[:] = [cwd, *sys_path]
    sys.argv = ["agrobot", *args]
    code = 0
    try:
        runpy.run_module("agrobot", run_name="__main__", alter_sys=True)
    except SystemExit as stop:
        code = _exit_status(stop.code)
    except BaseException:
        traceback.print_exc()
        code = 1
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        stream.flush()
    t = os.times()
    Path(cpu).write_text(f"{t.user + t.system + t.children_user + t.children_system}")
    os._exit(code)


def _exit_status(code) -> int:
    if code is None:
        return 0
    if isinstance(code, int):
        return code & 0xFF
    print(code, file=sys.stderr)
    return 1
