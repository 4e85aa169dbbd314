"""The output folder of a run, protected (issue 16, item 2).

- checked before any computation: ``--out`` must not be a file; an existing, non-empty folder must
  be a result folder of this project (it holds ``run.json`` or ``metrics.json``) unless
  ``overwrite``; the folder it would be created in must be writable;
- locked: a second run into the same ``--out`` is refused while the first holds the lock (an
  ``flock`` on ``.NAME.lock`` next to it, released by the kernel if the process dies);
- written aside: the run writes into a fresh folder ``.NAME.XXXX`` next to ``--out`` and moves it into
  place when it is complete or interrupted (marked so in its files). A failed run never replaces a
  complete earlier result: it is moved to ``NAME.failed`` instead, and the message says so.
"""
from __future__ import annotations

import fcntl
import json
import os
import shutil
import tempfile
from pathlib import Path

from .errors import InputError
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


def _completed(folder: Path) -> bool:
    try:
        return json.loads((folder / "metrics.json").read_text()).get("status") == "completed"
    except (OSError, ValueError, AttributeError):
        return False


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
        """Move the run's folder into place; returns where it went."""
        target = self.out
        if status != "completed" and status != "interrupted" and self.out.is_dir() and _completed(self.out):
            target = self.out.with_name(self.out.name + ".failed")
        if target.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{target.name}.old.", dir=target.parent))
            os.rmdir(old)
            os.replace(target, old)
            os.replace(self.tmp, target)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(self.tmp, target)
        self.tmp = None
        self.where = target
        return target

    def __exit__(self, *exc) -> None:
        if self.tmp is not None:
            shutil.rmtree(self.tmp, ignore_errors=True)
        if self._lock is not None:
            fcntl.flock(self._lock, fcntl.LOCK_UN)      # the lock file stays: unlinking it would race
            self._lock.close()
