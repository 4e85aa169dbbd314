"""Error kinds and the one table that maps them to exit codes and messages.

Tools raise an ``InputError`` (a subclass) for anything the user can fix: a bad study, log, option
or output path. The command line turns each kind into an exit code and a one-line ``error: ...``
message; nothing prints a traceback for a user's mistake.
"""
from __future__ import annotations


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


def _handler(signum, frame):
    kind = Terminated if signum == 15 else KeyboardInterrupt
    if _CRITICAL["depth"]:
        _CRITICAL["pending"] = kind          # raised when the critical section ends
        return
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
    past a ``critical`` block), so that every run saves its partial results on either signal."""
    import signal
    import threading

    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, _handler)
        signal.signal(signal.SIGINT, _handler)


# (error kind, exit code, message template); first match wins, so subclasses come first.
# ``{exc}`` is the error's text.
EXIT_TABLE: list[tuple[type[BaseException], int, str]] = [
    (InputError, 2, "error: {exc}"),
    (ComputationError, 1, "error: {exc}"),
    (Interrupted, 130, "interrupted: {exc}"),
    (Terminated, 143, "terminated"),
    (KeyboardInterrupt, 130, "interrupted"),
]


def exit_code(exc: BaseException) -> tuple[int, str] | None:
    """(exit code, message) for a known error kind, None for a bug (let it raise)."""
    for kind, code, template in EXIT_TABLE:
        if isinstance(exc, kind):
            return getattr(exc, "exit_status", code), template.format(exc=exc)
    return None
