"""A fatal signal in a foreign binary, named: an FMU's C code that crashes the process which loaded
it (a segmentation fault, an abort) leaves no Python exception to catch, so the call is named
before it is made. ``faulthandler`` prints the Python frames of the crashing thread on SIGSEGV,
SIGFPE, SIGABRT, SIGBUS and SIGILL; every call into a component's binary goes through a frame
whose function name says the component and the call (``named(label, fn, *args)``), so the dump
reads ``File ".../fatal_calls.py", line N in FMU component 'plant' (plant.fmu): doStep``. The run's
loop goes through such a frame too once a binary is loaded in-process (``watching``), named after
where the signals recorded until the crash are kept (orchestrator.runner); ``forget`` when the run
ends, so that a later run in the same process without such a binary writes no crash-readable file.
"""
from __future__ import annotations

import faulthandler
import functools
import sys
from typing import Any, Callable


_watched: list[bool] = []


def watch() -> None:
    """Print the crashing call on a fatal signal (faulthandler on stderr, once per process)."""
    _watched[:] = [True]
    if not faulthandler.is_enabled():
        try:
            faulthandler.enable(file=sys.__stderr__ or sys.stderr)
        except (AttributeError, ValueError, OSError):      # no real stderr (a notebook): nothing to print to
            pass


def _call(fn: Callable[..., Any], *args: Any) -> Any:
    return fn(*args)


@functools.lru_cache(maxsize=4096)
def caller(label: str) -> Callable[..., Any]:
    """``_call`` under a code object named ``label`` (what a fatal signal's dump prints)."""
    code = _call.__code__.replace(co_name=label, co_qualname=label)
    return type(_call)(code, _call.__globals__, label)


def named(label: str, fn: Callable[..., Any], *args: Any) -> Any:
    """``fn(*args)``, a fatal signal during which is printed with ``label``."""
    return caller(label)(fn, *args)


def forget() -> None:
    """The run that loaded a binary has ended (faulthandler stays on: it costs nothing)."""
    _watched.clear()


def watching() -> bool:
    """True once a component of the run going on has loaded a binary into this process (``watch``):
    a fatal signal in it would end the process with no Python code run after it."""
    return bool(_watched)
