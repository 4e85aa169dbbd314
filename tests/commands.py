"""The command line as the tests call it: ``cli("run", study, "--out", out)`` runs
``python -m agrobot`` from the repository root; ``refused(proc, *words)`` asserts a clean refusal
(exit 2, no traceback, the words in the message).

Each command runs in a process of its own, forked from an interpreter that has already imported the
command line (one per test process, started on first use with the same environment): the module run
as ``__main__`` with the same arguments, working folder, module search path and environment, its own
exit status, standard output and error, without the 1.5 CPU s an interpreter spends starting and
importing numpy, pandas and scipy on each call. ``AGROBOT_TEST_CLI=subprocess``, or an environment
changed since that interpreter started (a variable a module reads as it is imported), runs the real
``python -m agrobot``.

Imported where used: atexit, runpy and traceback (in the forked command only)."""
from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PRELOAD = ("agrobot.extras", "agrobot.orchestrator.cli",              # what agrobot.__main__ imports at the top
           "agrobot.analysis.margins", "agrobot.orchestrator.atomic_files", "agrobot.measurements.cli")  # and main()
_IGNORED = {"PYTEST_CURRENT_TEST"}          # pytest's per-test variable: read by no module as it loads
_zygote: dict = {}
forked_cpu_seconds = 0.0                    # the forked commands' CPU time (the zygote's children, not ours)


def cli(*args, timeout: float = 300, cwd: Path = ROOT) -> subprocess.CompletedProcess:
    command = [sys.executable, "-m", "agrobot", *map(str, args)]
    if os.environ.get("AGROBOT_TEST_CLI") == "subprocess" or not _zygote_matches():
        return subprocess.run(command, capture_output=True, text=True, cwd=cwd, timeout=timeout)
    return _forked(command, timeout, Path(cwd))


def in_process(argv, capsys) -> tuple[int, str, str]:
    """The command line's ``main`` called in this process: (exit code, stdout, stderr), for a test
    that patches the product (a failing write, a signal) where a forked command would not see it."""
    from agrobot.orchestrator.cli import main

    code = main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def refused(proc: subprocess.CompletedProcess, *words: str) -> str:
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    for w in words:
        assert w in proc.stderr, (w, proc.stderr)
    return proc.stderr


def _environment() -> dict:
    return {k: v for k, v in os.environ.items() if k not in _IGNORED}


def _zygote_matches() -> bool:
    """The zygote, started on first use (``python -c`` from the repository root, PRELOAD imported);
    False when the environment changed since."""
    if "process" not in _zygote or _zygote["process"].poll() is not None:
        process = subprocess.Popen([sys.executable, "-c", "from tests.commands import _serve; _serve()"],
                                   stdin=subprocess.PIPE, stdout=subprocess.PIPE, cwd=ROOT, text=True)
        _zygote.update(process=process, environment=_environment())
    return _zygote["environment"] == _environment()


def _forked(command: list[str], timeout: float, cwd: Path) -> subprocess.CompletedProcess:
    """One command through the zygote; interrupted (pytest-timeout, Ctrl-C), the zygote is ended with
    its child so that the next call starts a fresh one instead of reading this one's answer."""
    try:
        return _through_zygote(command, timeout, cwd)
    except BaseException:
        if "pid" in _zygote:
            with contextlib.suppress(ProcessLookupError):
                os.kill(_zygote.pop("pid"), signal.SIGKILL)
        _zygote.pop("process").kill()
        _zygote.clear()
        raise


def _through_zygote(command: list[str], timeout: float, cwd: Path) -> subprocess.CompletedProcess:
    global forked_cpu_seconds
    process = _zygote["process"]
    with tempfile.TemporaryDirectory() as folder:
        out, err, cpu = (Path(folder) / name for name in ("stdout", "stderr", "cpu"))
        request = dict(args=command[3:], cwd=str(cwd), out=str(out), err=str(err), cpu=str(cpu),
                       environment=dict(os.environ))
        process.stdin.write(json.dumps(request) + "\n")
        process.stdin.flush()
        pid = _zygote["pid"] = int(process.stdout.readline())
        expired = threading.Event()
        limit = threading.Timer(timeout, lambda: (expired.set(), os.kill(pid, signal.SIGKILL)))
        limit.start()
        status = int(process.stdout.readline())
        limit.cancel()
        del _zygote["pid"]
        output, errors = out.read_text(), err.read_text()
        if expired.is_set():
            raise subprocess.TimeoutExpired(command, timeout, output, errors)
        forked_cpu_seconds += float(cpu.read_text()) if cpu.exists() else 0.0
        return subprocess.CompletedProcess(command, status, output, errors)


def _serve():
    """The zygote: PRELOAD imported, then for each request line a forked ``python -m agrobot``; it
    answers the child's pid, then its exit status (negative: the signal that ended it)."""
    import importlib

    for name in PRELOAD:
        importlib.import_module(name)
    for line in sys.stdin:
        request = json.loads(line)
        pid = os.fork()
        if pid == 0:
            _run_agrobot(**request)
        print(pid, flush=True)
        _, status = os.waitpid(pid, 0)
        print(os.waitstatus_to_exitcode(status), flush=True)


def _run_agrobot(args, cwd, out, err, cpu, environment):
    """``python -m agrobot ARGS`` in the forked child: its output to the two files, the exit status
    as the interpreter gives it (SystemExit's code; 1 and the traceback for an exception)."""
    import atexit
    import runpy
    import traceback

    os.dup2(os.open(os.devnull, os.O_RDONLY), 0)
    os.dup2(os.open(out, os.O_WRONLY | os.O_CREAT), 1)
    os.dup2(os.open(err, os.O_WRONLY | os.O_CREAT), 2)
    os.chdir(cwd)
    os.environ.clear()
    os.environ.update(environment)
    sys.path[0] = cwd                       # python -m's first entry: the working folder
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
