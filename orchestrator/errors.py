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


# (error kind, exit code, message template); first match wins, so subclasses come first.
# ``{exc}`` is the error's text. RunError and AnalysisError are registered by the modules that
# define them (engine, runner) through ``register_error``.
EXIT_TABLE: list[tuple[type[BaseException], int, str]] = [
    (InputError, 2, "error: {exc}"),
    (ComputationError, 1, "error: {exc}"),
    (KeyboardInterrupt, 130, "interrupted"),
]


def register_error(kind: type[BaseException], code: int, template: str) -> None:
    """Put ``kind`` in front of the table (more specific kinds are registered after their bases)."""
    EXIT_TABLE.insert(0, (kind, code, template))


def exit_code(exc: BaseException) -> tuple[int, str] | None:
    """(exit code, message) for a known error kind, None for a bug (let it raise)."""
    for kind, code, template in EXIT_TABLE:
        if isinstance(exc, kind):
            return code, template.format(exc=exc)
    return None
