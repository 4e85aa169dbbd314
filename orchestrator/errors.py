"""Error kinds and the one table that maps them to exit codes and messages.

Tools raise an ``InputError`` (a subclass) for anything the user can fix: a bad study, log, option
or output path. The command line turns each kind into an exit code and a one-line ``error: ...``
message; nothing prints a traceback for a user's mistake.
"""
from __future__ import annotations

import difflib
import signal
import threading
from typing import Iterable


def did_you_mean(name: str, known: Iterable[str], n: int = 3, form: str = "; did you mean {}?") -> str:
    """The hint a message about an unknown name ends with: up to ``n`` of the ``known`` names
    closest to it, joined by "or", in ``form``; empty when none is close."""
    close = difflib.get_close_matches(str(name), list(known), n=n)
    return form.format(" or ".join(map(repr, close))) if close else ""


class InputError(Exception):
    """Something the user gave cannot be used (a file, a field, an option); the message names it."""


class ComputationError(Exception):
    """A computation failed after its inputs were accepted (the message says what was kept)."""


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread like Ctrl-C's KeyboardInterrupt (exit 143)."""


class Interrupted(Exception):
    """A run stopped by SIGINT or SIGTERM after saving what it had; ``exit_status`` 130 or 143."""

    def __init__(self, message: str, exit_status: int) -> None:
        super().__init__(message)
        self.exit_status = exit_status


_CRITICAL = {"depth": 0, "pending": None}
RETRY_S = 0.05          # a signal deferred while a module is imported is raised this soon after


def _importing(frame) -> bool:
    """True while the main thread is importing a module: an exception raised there can leave a
    C extension half initialised (a later ImportError) or be swallowed by a library's guarded import."""
    while frame is not None:
        if frame.f_code.co_filename.startswith("<frozen importlib"):
            return True
        frame = frame.f_back
    return False


def _defer(kind, frame) -> bool:
    """Keep the signal pending when it cannot be raised here; look again RETRY_S later (SIGALRM)
    when only an import stands in the way."""
    if _CRITICAL["depth"]:
        _CRITICAL["pending"] = kind          # raised when the critical section ends
        return True
    if _importing(frame):
        _CRITICAL["pending"] = kind
        signal.setitimer(signal.ITIMER_REAL, RETRY_S)
        return True
    return False


def _handler(signum, frame):
    kind = Terminated if signum == 15 else KeyboardInterrupt
    if not _defer(kind, frame):
        raise kind()


def _retry(signum, frame):
    """SIGALRM: raise a signal kept pending while a module was imported, once the import is over."""
    kind = _CRITICAL["pending"]
    if kind is None or _defer(kind, frame):
        return
    _CRITICAL["pending"] = None
    raise kind()


class critical:
    """``with critical():`` a block that a SIGINT/SIGTERM must not cut in half (draining the
    recorders into the signal file): the signal is raised when the block ends."""

    def __enter__(self) -> None:
        _CRITICAL["depth"] += 1

    def __exit__(self, *exc) -> None:
        _CRITICAL["depth"] -= 1
        pending = _CRITICAL["pending"]
        if pending is not None and not _CRITICAL["depth"]:
            _CRITICAL["pending"] = None
            raise pending()


def install_signal_handlers() -> None:
    """SIGINT and SIGTERM end the main thread's work as KeyboardInterrupt / Terminated (deferred
    past a ``critical`` block, and past the import of a module), so that every run saves its
    partial results on either signal and no half-imported module is left behind."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, _handler)
        signal.signal(signal.SIGINT, _handler)
        signal.signal(signal.SIGALRM, _retry)


# (error kind, exit code, message template); first match wins, so subclasses come first.
# ``{exc}`` is the error's text.
EXIT_TABLE: list[tuple[type[BaseException], int, str]] = [
    (InputError, 2, "error: {exc}"),
    (ComputationError, 1, "error: {exc}"),
    (Interrupted, 130, "interrupted: {exc}"),
    (Terminated, 143, "terminated"),
    (KeyboardInterrupt, 130, "interrupted"),
]


MESSAGE_LINE_LIMIT = 2000     # characters of one line of an error message; a longer line is cut in its middle


def bounded(message: str, limit: int = MESSAGE_LINE_LIMIT) -> str:
    """``message`` with every line longer than ``limit`` cut in its middle, saying how much was cut
    (a list of every value a nested study offered is no message)."""
    def cut(line: str) -> str:
        if len(line) <= limit:
            return line
        keep = limit // 2
        return f"{line[:keep]} [... {len(line) - 2 * keep} characters cut ...] {line[-keep:]}"
    return "\n".join(cut(line) for line in message.split("\n"))


def exit_code(exc: BaseException) -> tuple[int, str] | None:
    """(exit code, message) for a known error kind, None for a bug (let it raise); the message's
    lines bounded (``bounded``)."""
    for kind, code, template in EXIT_TABLE:
        if isinstance(exc, kind):
            return getattr(exc, "exit_status", code), bounded(template.format(exc=exc))
    return None
