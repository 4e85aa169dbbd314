"""An FMU instance in a child process (``study.isolate_fmus``, ``run --isolate-fmus``).

The FMU's binary runs C code the orchestrator cannot stop: a segmentation fault or an ``exit()``
ends the process that loaded it, an endless loop holds the thread that called it, and Python's
signal handlers only run between bytecodes, so Ctrl-C waits for a C call that never returns. In a
child process each of these becomes a named error in the parent, which keeps running, records
what it has and ends when asked:

- every call (``setReal``, ``doStep`` ...) is sent over a pipe and answered; the parent waits in
  short slices, so SIGINT/SIGTERM interrupt the wait at once and the child is killed;
- a child that dies answers nothing: the error names the call, the instant and how it ended
  (the signal, or the exit code);
- a call that takes longer than ``study.fmu_timeout`` seconds is a hang: the child is killed and
  the error says so.

The child ignores SIGINT (Ctrl-C reaches the whole process group: the parent decides) and ends
with its parent (PR_SET_PDEATHSIG on Linux).

Imported where used: fmpy (start-up: 0.06 s on every command, which loads this module through the FMU
component; the child process loads it).
"""
from __future__ import annotations

import ctypes
import multiprocessing
import signal
import time
from typing import Any

from .component import ComponentError

SLICE_S = 0.05              # the parent's wait on an answer is cut into slices this long
STARTUP_S = 300.0           # a child process to start Python and load the FMU's binary (not a call's time)


def _child(conn, cls_name: str, kwargs: dict[str, Any]) -> None:
    """The child's loop: make the fmpy instance, then answer (method, args, kwargs) until closed."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        ctypes.CDLL("libc.so.6").prctl(1, int(signal.SIGKILL))     # PR_SET_PDEATHSIG: end with the parent
    except (OSError, AttributeError):
        pass
    import fmpy.fmi2 as fmi2
    import fmpy.fmi3 as fmi3
    from fmpy.fmi1 import FMICallException

    cls = getattr(fmi2, cls_name, None) or getattr(fmi3, cls_name)
    try:
        slave = cls(**kwargs)
    except Exception as exc:  # noqa: BLE001 - a binary that cannot be loaded, by name
        conn.send(("error", f"{type(exc).__name__}: {exc}"))
        return
    conn.send(("ok", "ready"))
    while True:
        try:
            name, args, kw = conn.recv()
        except EOFError:
            return
        try:
            if name == "doStep3":
                result = _do_step3(slave, *args)
            else:
                result = getattr(slave, name)(*args, **kw)
            conn.send(("ok", result))
        except FMICallException as exc:
            conn.send(("fmi", (exc.function, exc.status)))
        except Exception as exc:  # noqa: BLE001 - every failure goes back to the parent by name
            conn.send(("error", f"{type(exc).__name__}: {exc}"))


def _do_step3(slave, t: float, dt: float):
    """fmi3DoStep with its output arguments, as values: (status exception, event, terminate, early, last)."""
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi3 import fmi3Boolean, fmi3Float64

    event, terminate, early, last = fmi3Boolean(), fmi3Boolean(), fmi3Boolean(), fmi3Float64()
    failed = None
    try:
        slave.fmi3DoStep(slave.component, t, dt, fmi3Boolean(True), ctypes.byref(event), ctypes.byref(terminate),
                         ctypes.byref(early), ctypes.byref(last))
    except FMICallException as exc:
        failed = (exc.function, exc.status)
    return failed, bool(event.value), bool(terminate.value), bool(early.value), float(last.value)


class RemoteSlave:
    """The fmpy instance of an FMU in a child process: attribute calls are forwarded."""

    def __init__(self, cls_name: str, kwargs: dict[str, Any], who: str, timeout: float) -> None:
        ctx = multiprocessing.get_context("spawn")
        self._conn, child_conn = ctx.Pipe()
        self._who, self._timeout = who, timeout
        self._proc = ctx.Process(target=_child, args=(child_conn, cls_name, kwargs), daemon=True,
                                 name=f"fmu {who}")
        self._proc.start()
        child_conn.close()
        self.at = ""              # the instant of the current call, for the message
        self._answer("loading the FMU's binary", STARTUP_S)

    def _ended(self) -> str:
        self._proc.join(1.0)
        code = self._proc.exitcode
        if code is None:
            return "stopped answering"
        if code < 0:
            try:
                return f"crashed (signal {signal.Signals(-code).name})"
            except ValueError:
                return f"crashed (signal {-code})"
        return f"ended its process (exit code {code})"

    def call(self, name: str, *args, **kw):
        if not self._proc.is_alive():
            raise ComponentError(f"{self._who}: {name}: the FMU's process has ended ({self._ended()})")
        try:
            self._conn.send((name, args, kw))
        except (BrokenPipeError, ConnectionResetError):
            raise ComponentError(f"{self._who}: the FMU {self._ended()} in {name}{self.at}") from None
        return self._answer(name, self._timeout)

    def _answer(self, name: str, timeout: float):
        from fmpy.fmi1 import FMICallException

        try:
            deadline = time.monotonic() + timeout
            while not self._conn.poll(SLICE_S):          # a signal lands between two slices
                if not self._proc.is_alive():
                    break
                if time.monotonic() > deadline:
                    self.kill()
                    raise ComponentError(f"{self._who}: {name}{self.at} did not return within {timeout:g} s "
                                         f"(study.fmu_timeout): the FMU hangs; its process was stopped")
            kind, value = self._conn.recv()
        except (EOFError, BrokenPipeError, ConnectionResetError):
            raise ComponentError(f"{self._who}: the FMU {self._ended()} in {name}{self.at}") from None
        except KeyboardInterrupt:
            self.kill()
            raise
        if kind == "ok":
            return value
        if kind == "fmi":
            raise FMICallException(*value)
        raise ComponentError(f"{self._who}: {name}{self.at}: {value}")

    def __getattr__(self, name: str):
        if name.startswith("_"):
            raise AttributeError(name)
        return lambda *args, **kw: self.call(name, *args, **kw)

    def alive(self) -> bool:
        return self._proc.is_alive()

    def kill(self) -> None:
        if self._proc.is_alive():
            self._proc.kill()
            self._proc.join(5.0)

    def close(self) -> None:
        try:
            self._conn.close()
        finally:
            self._proc.join(2.0)
            self.kill()
