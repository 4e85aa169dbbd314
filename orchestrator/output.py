"""The output folder of a run, protected.

- checked before any computation: ``--out`` must not be a file; an existing, non-empty folder must
  be a result folder of this project (it holds ``run.json`` or ``metrics.json``) unless
  ``overwrite``; the folder it would be created in must be writable;
- locked: a second run into the same ``--out`` is refused while the first holds the lock (an
  ``flock`` on ``.NAME.lock`` next to it, released by the kernel if the process dies);
- written aside: the run writes into a fresh folder ``.NAME.XXXX`` next to ``--out``. A complete
  run (status completed, or ended by a component) is swapped into place in one step; a run that
  is interrupted or fails never replaces what ``--out`` holds unless that is itself an unfinished
  result (or nothing): it is moved beside it, to ``NAME.interrupted`` or ``NAME.failed``, and the
  message says where.
"""
from __future__ import annotations

import fcntl
import json
import os
import shutil
import tempfile
from pathlib import Path

from .errors import InputError, critical
from .results import UMASK

MARKERS = ("run.json", "metrics.json")


class OutputError(InputError):
    """``--out`` cannot be used (the message says why and what to do)."""


def _nearest_existing(path: Path) -> Path:
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def check_output(out: Path, overwrite: bool = False) -> None:
    """Every problem with ``out`` that can be found before computing anything."""
    if out.exists() and not out.is_dir():
        raise OutputError(f"--out {out}: is a file, not a folder")
    if out.is_dir():
        if any(out.iterdir()) and not any((out / m).exists() for m in MARKERS) and not overwrite:
            raise OutputError(f"--out {out}: the folder holds files that are not results of a run "
                              f"(no {' or '.join(MARKERS)}); choose another folder or pass --overwrite")
        if not os.access(out, os.W_OK | os.X_OK):
            raise OutputError(f"--out {out}: the folder is not writable")
    base = _nearest_existing(out.parent.resolve())
    if not base.is_dir():
        raise OutputError(f"--out {out}: {base} is not a folder")
    if not os.access(base, os.W_OK | os.X_OK):
        raise OutputError(f"--out {out}: cannot create it, {base} is not writable")
    try:                    # permissions are not the whole story (/proc, a read-only mount, a full disk)
        os.rmdir(tempfile.mkdtemp(prefix=".probe.", dir=base))
    except OSError as exc:
        raise OutputError(f"--out {out}: cannot create folders in {base}: {exc.strerror or exc}") from None


COMPLETE = ("completed", "ended")          # statuses of a whole result (ended: a component ended the run)


def status_of(folder: Path) -> str | None:
    """The status in a result folder's metrics.json (or run.json); None when it holds neither."""
    for name in MARKERS[::-1]:
        try:
            status = json.loads((folder / name).read_text()).get("status")
        except (OSError, ValueError, AttributeError):
            continue
        if isinstance(status, str):
            return status
    return None


def _holds_something_else(out: Path) -> bool:
    """True when ``out`` holds what an unfinished run must not replace: a complete result, or
    files that are not a result of a run at all."""
    if not out.is_dir() or not any(out.iterdir()):
        return False
    if not any((out / m).exists() for m in MARKERS):
        return True
    return status_of(out) in COMPLETE


def swap_folder(new: Path, target: Path) -> Path | None:
    """Move folder ``new`` to ``target``; an existing ``target`` is exchanged with it in one step
    (Linux renameat2 RENAME_EXCHANGE; elsewhere two renames) and its old content is returned
    (at ``new``'s path) for the caller to remove."""
    if not target.exists():
        os.replace(new, target)
        return None
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        if libc.renameat2(-100, os.fsencode(new), -100, os.fsencode(target), 2) == 0:   # AT_FDCWD, RENAME_EXCHANGE
            return new
    except (OSError, AttributeError):
        pass
    old = Path(tempfile.mkdtemp(prefix=f".{target.name}.old.", dir=target.parent))
    os.rmdir(old)
    os.replace(target, old)
    os.replace(new, target)
    return old


def _beside(out: Path, status: str) -> Path:
    """Where an unfinished run goes when ``out`` must stay as it is: ``OUT.interrupted`` or
    ``OUT.failed`` (replacing an earlier one of ours), or the first ``OUT.failed-N`` that is free
    or ours when that name holds something else."""
    kind = "interrupted" if status == "interrupted" else "failed"
    for n in range(1, 1000):
        candidate = out.with_name(f"{out.name}.{kind}" + (f"-{n}" if n > 1 else ""))
        if not candidate.exists() or (candidate.is_dir() and any((candidate / m).exists() for m in MARKERS)):
            return candidate
    raise OutputError(f"--out {out}: no free name beside it for the {kind} run's folder")


class ResultFolder:
    """``with ResultFolder(out) as folder:`` write into ``folder.tmp``, then ``folder.commit(status)``
    with status completed / interrupted / failed; leaving the block without a commit discards the
    temporary folder."""

    def __init__(self, out: Path, overwrite: bool = False) -> None:
        self.out = Path(out)
        check_output(self.out, overwrite)
        self.where = self.out
        self._lock = None
        self.tmp: Path | None = None

    def __enter__(self) -> "ResultFolder":
        parent = self.out.parent
        try:
            parent.mkdir(parents=True, exist_ok=True)
            self._lock = open(parent / f".{self.out.name}.lock", "w")
        except OSError as exc:
            raise OutputError(f"--out {self.out}: cannot create {parent}: {exc.strerror or exc}") from None
        try:
            fcntl.flock(self._lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            self._lock.close()
            raise OutputError(f"--out {self.out}: another run is writing to this folder; wait for it or "
                              f"choose another folder") from None
        self.tmp = Path(tempfile.mkdtemp(prefix=f".{self.out.name}.", dir=parent))
        os.chmod(self.tmp, 0o777 & ~UMASK)
        return self

    def commit(self, status: str) -> Path:
        """Move the run's folder into place (``status`` completed or ended) or beside ``--out``
        (interrupted, failed, analysis_failed: see the module docstring); returns where it went.
        Not cut in half by SIGINT/SIGTERM (errors.critical)."""
        target = self.out
        if status not in COMPLETE and _holds_something_else(self.out):
            target = _beside(self.out, status)
        with critical():
            old = swap_folder(self.tmp, target)
            self.tmp = None
            self.where = target
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        return target

    def __exit__(self, *exc) -> None:
        if self.tmp is not None:
            shutil.rmtree(self.tmp, ignore_errors=True)
        if self._lock is not None:
            fcntl.flock(self._lock, fcntl.LOCK_UN)      # the lock file stays: unlinking it would race
            self._lock.close()
