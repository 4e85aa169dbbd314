"""Where a command writes, one rule for every command.

- ``--out`` names a folder (or, for a command that writes one file, that file). A new or empty
  folder is written. A folder this command wrote before (it holds the command's *signature*
  file: ``run.json`` for a run, ``plan.json`` for a plan ...) is replaced only with
  ``--overwrite``, in one step. Anything else is refused, naming what is there.
- An ``--out`` that is, contains or lies inside one of the command's inputs (the study file and
  the files it extends, a log, a field) is refused: no command writes over what it reads.
- One writer at a time: an ``flock`` on ``.NAME.lock`` next to ``--out``, taken before any work
  and removed by its holder when the command ends (a lock file left by a killed command holds no
  lock and is reused). Sweeps take the same lock as runs.
- Written aside: a folder is written into ``.NAME.staging-XXXX`` next to ``--out`` and swapped
  into place when complete. A run that is interrupted or fails never replaces what ``--out``
  holds unless that is itself an unfinished result (or nothing): it goes beside it, to
  ``NAME.interrupted`` or ``NAME.failed``, and the message says where. Staging folders left by a
  killed command are removed (and named) by the next command into the same ``--out``.
- A full disk (ENOSPC, EDQUOT), or a file past the largest size the file system or the process
  allows (EFBIG), is an ``OutputError`` naming the file; the staging folder is removed, so
  ``--out`` holds what it held before.
"""
from __future__ import annotations

import ctypes
import errno
import fcntl
import json
import os
import re
import shutil
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Iterable

from .errors import InputError, critical
from .atomic_files import UMASK
from .study_files import study_chain

MARKERS = ("run.json", "metrics.json")          # a run's signature files
STAGING = "staging-"
DISK_FULL = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)      # no room: the disk, the quota, a file's size limit


class OutputError(InputError):
    """``--out`` cannot be used (the message says why and what to do)."""


def _nearest_existing(path: Path) -> Path:
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def _listing(folder: Path, limit: int = 4) -> str:
    names = sorted(p.name + ("/" if p.is_dir() else "") for p in folder.iterdir())
    return ", ".join(names[:limit]) + (f" and {len(names) - limit} more" if len(names) > limit else "")


def _inside(path: Path, folder: Path) -> bool:
    return path == folder or folder in path.parents


def check_inputs(out: Path, inputs: Iterable[Path | str | None], flag: str = "--out") -> None:
    """Refuse an output that is, contains or lies inside one of ``inputs``."""
    target = Path(out).resolve()
    for given in inputs:
        if given is None:
            continue
        try:
            source = Path(given).resolve()
        except (RuntimeError, OSError):       # a symlink loop: the reader names it, it is no output's place
            continue
        if target == source:
            raise OutputError(f"{flag} {out}: is the input {given}; choose another {flag}")
        if _inside(source, target):
            raise OutputError(f"{flag} {out}: holds the input {given}, which writing there would replace; "
                              f"choose another {flag}")
        if source.is_dir() and _inside(target, source):
            raise OutputError(f"{flag} {out}: lies inside the input {given}; choose a {flag} outside it")


DERIVED_NAME = len(f"..{STAGING}") + 8      # the longest name made from --out's: .NAME.staging-XXXXXXXX


def check_name(out: Path, flag: str = "--out") -> None:
    """Every part of ``out`` a name the file system takes (255 bytes on most), its last part short
    enough for the names made from it (its lock, its staging folder)."""
    base = _nearest_existing(Path(out).absolute().parent)
    try:
        limit = os.pathconf(base, "PC_NAME_MAX")
    except (OSError, ValueError):
        limit = 255
    parts = Path(out).parts
    for i, part in enumerate(parts):
        size = len(os.fsencode(part)) + (DERIVED_NAME if i == len(parts) - 1 else 0)
        if size > limit:
            raise OutputError(f"{flag} {out}: the name {part[:40]}... is {len(os.fsencode(part))} bytes; the file system "
                              f"takes at most {limit - (DERIVED_NAME if i == len(parts) - 1 else 0)} here (its last "
                              f"part leaves room for the names made from it); choose a shorter name")


def _check_parent(out: Path, flag: str = "--out") -> None:
    base = _nearest_existing(out.parent.resolve())
    if not base.is_dir():
        raise OutputError(f"{flag} {out}: cannot write there ({base} is not a folder)")
    if not os.access(base, os.W_OK | os.X_OK):
        raise OutputError(f"{flag} {out}: cannot create it, {base} is not writable")
    try:                    # permissions are not the whole story (/proc, a read-only mount, a full disk)
        os.rmdir(tempfile.mkdtemp(prefix=".probe.", dir=base))
    except OSError as exc:
        raise OutputError(f"{flag} {out}: cannot create folders in {base}: {exc.strerror or exc}") from None


def check_output(out: Path, overwrite: bool = False, signature: tuple[str, ...] = MARKERS, what: str = "run",
                 inputs: Iterable[Path | str | None] = (), resume: bool = False) -> None:
    """Every problem with the output folder ``out`` that can be found before computing anything
    (the module's rule). ``signature``: the files that mark a folder as this command's result;
    ``resume``: such a folder is written into again without ``--overwrite`` (a sweep resumes)."""
    out = Path(out)
    check_name(out)
    check_inputs(out, inputs)
    here = Path.cwd().resolve()
    if out.resolve() == here or out.resolve() in here.parents:
        raise OutputError(f"--out {str(out)!r}: is the working folder{'' if out.resolve() == here else ' or holds it'}; a "
                          f"result folder is replaced whole when the command ends: name a new folder, e.g. --out results")
    if out.exists() and not out.is_dir():
        raise OutputError(f"--out {out}: is a file, not a folder")
    if out.is_dir() and any(out.iterdir()):
        ours = [m for m in signature if (out / m).exists()]
        if not ours:
            raise OutputError(f"--out {out}: holds {_listing(out)}, which is not a {what} result (no "
                              f"{' or '.join(signature)}); choose a new or empty folder")
        if not (overwrite or resume):
            raise OutputError(f"--out {out}: holds an earlier {what} result ({ours[0]}); pass --overwrite to "
                              f"replace it, or choose another folder")
    if out.is_dir() and not os.access(out, os.W_OK | os.X_OK):
        raise OutputError(f"--out {out}: the folder is not writable")
    _check_parent(out)


def check_output_file(out: Path, overwrite: bool = False, inputs: Iterable[Path | str | None] = (),
                      suffixes: tuple[str, ...] = (), flag: str = "--out") -> None:
    """The rule for every single file a command writes (``--out``, ``--mcap``, a recording): a new
    file is written, an existing one is replaced only with ``--overwrite``, an input never.
    ``flag``: the option (or study key) that named the file, for the message."""
    out = Path(out)
    check_name(out, flag)
    if suffixes and out.suffix.lower() not in suffixes:
        raise OutputError(f"{flag} {out}: expected a path ending in {' or '.join(suffixes)}")
    check_inputs(out, inputs, flag)
    if out.is_dir():
        raise OutputError(f"{flag} {out}: is a folder, expected the {out.suffix or ''} file to write".replace("  ", " "))
    if out.exists() and not overwrite:
        raise OutputError(f"{flag} {out}: exists; pass --overwrite to replace it, or choose another name")
    if out.exists() and not os.access(out.parent, os.W_OK | os.X_OK):
        raise OutputError(f"{flag} {out}: its folder is not writable")
    _check_parent(out, flag)


def disk_full(exc: BaseException) -> bool:
    return isinstance(exc, OSError) and exc.errno in DISK_FULL


def full_reason(exc: OSError) -> tuple[str, str]:
    """(what happened, what to do) for a write refused by a full disk or a file-size limit."""
    return ("a file grew past the largest size allowed here", "write it where larger files are allowed") \
        if exc.errno == errno.EFBIG else ("the disk is full", "free some space")


def disk_full_error(out: Path, exc: OSError, kept: str, flag: str = "--out") -> OutputError:
    where = f" while writing {Path(exc.filename).name}" if getattr(exc, "filename", None) else ""
    what, then = full_reason(exc)
    return OutputError(f"{flag} {out}: {what} ({exc.strerror or os.strerror(exc.errno)}){where}; "
                       f"nothing was written to {out} ({kept}); {then} and run the command again")


class OutputLock:
    """One writer per ``--out``: an ``flock`` on ``.NAME.lock`` beside it. The holder removes the
    file before it lets go; whoever locks a file that was removed meanwhile tries again, so two
    writers never hold locks on two files of one name."""

    def __init__(self, out: Path, flag: str = "--out") -> None:
        self.out = Path(out)
        self.flag = flag
        self.path = self.out.parent / f".{self.out.name}.lock"
        self._fd: int | None = None

    def acquire(self) -> "OutputLock":
        try:
            self.out.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise OutputError(f"{self.flag} {self.out}: cannot create {self.out.parent}: {exc.strerror or exc}") from None
        for _ in range(100):
            try:
                fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o666 & ~UMASK)
            except OSError as exc:
                raise OutputError(f"{self.flag} {self.out}: cannot create its lock {self.path}: {exc.strerror or exc}") from None
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = os.pread(fd, 32, 0).decode(errors="replace").strip()
                os.close(fd)
                raise OutputError(f"{self.flag} {self.out}: another run or command{f' (process {holder})' if holder else ''} "
                                  f"is writing to it; wait for it or choose another name") from None
            try:
                same = os.stat(self.path).st_ino == os.fstat(fd).st_ino
            except FileNotFoundError:
                same = False
            if same:
                os.ftruncate(fd, 0)
                os.pwrite(fd, str(os.getpid()).encode(), 0)
                self._fd = fd
                return self
            os.close(fd)                 # its holder removed it while we waited: take the new one
        raise OutputError(f"{self.flag} {self.out}: could not take its lock {self.path}")

    def release(self) -> None:
        if self._fd is None:
            return
        try:
            self.path.unlink()
        except FileNotFoundError:
            pass
        os.close(self._fd)              # closing lets go of the flock
        self._fd = None

    def __enter__(self) -> "OutputLock":
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()


def remove_stale_staging(out: Path) -> list[Path]:
    """Staging folders of earlier commands into ``out`` that were killed (only called by the
    lock's holder: no live writer owns them); removed, and returned for a message. One that holds
    the signals a run recorded until a crash killed it (``*.partial.arrows``) is moved beside
    ``out`` as a failed result instead."""
    pattern = re.compile(rf"^\.{re.escape(out.name)}\.(?:{STAGING}|old\.)[A-Za-z0-9_]+$")
    found = [p for p in out.parent.iterdir() if pattern.match(p.name) and p.is_dir()] if out.parent.is_dir() else []
    for path in [p for p in found if any(p.glob("*.partial.arrows"))]:
        kept = _beside(out, "failed", MARKERS + ("signals.partial.arrows",))
        shutil.rmtree(kept, ignore_errors=True)
        os.replace(path, kept)
        found.remove(path)
        print(f"note: the signals recorded until an earlier run crashed are kept in {kept}", file=sys.stderr)
    for path in found:
        shutil.rmtree(path, ignore_errors=True)
    if found:
        print(f"note: removed {len(found)} staging folder(s) left by an earlier command that was killed: "
              f"{', '.join(p.name for p in found)}", file=sys.stderr)
    return found


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


def _holds_something_else(out: Path, signature: tuple[str, ...]) -> bool:
    """True when ``out`` holds what an unfinished result must not replace: a complete result, or
    files that are not a result of this command at all."""
    if not out.is_dir() or not any(out.iterdir()):
        return False
    if not any((out / m).exists() for m in signature):
        return True
    return status_of(out) in COMPLETE or not any((out / m).exists() for m in MARKERS)


def swap_folder(new: Path, target: Path) -> Path | None:
    """Move folder ``new`` to ``target``; an existing ``target`` is exchanged with it in one step
    (Linux renameat2 RENAME_EXCHANGE; elsewhere two renames) and its old content is returned
    (at ``new``'s path) for the caller to remove."""
    if not target.exists():
        os.replace(new, target)
        return None
    try:
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


def _beside(out: Path, status: str, signature: tuple[str, ...]) -> Path:
    """Where an unfinished result goes when ``out`` must stay as it is: ``OUT.interrupted`` or
    ``OUT.failed`` (replacing an earlier one of ours), or the first ``OUT.failed-N`` that is free
    or ours when that name holds something else."""
    kind = "interrupted" if status == "interrupted" else "failed"
    for n in range(1, 1000):
        candidate = out.with_name(f"{out.name}.{kind}" + (f"-{n}" if n > 1 else ""))
        if not candidate.exists() or (candidate.is_dir() and any((candidate / m).exists() for m in signature)):
            return candidate
    raise OutputError(f"--out {out}: no free name beside it for the {kind} result's folder")


class ResultFolder:
    """``with ResultFolder(out, ...) as folder:`` write into ``folder.tmp``, then
    ``folder.commit(status)`` with status completed / interrupted / failed; leaving the block
    without a commit discards the staging folder. The rule of the module docstring is checked when
    the object is made (before any work); the lock is taken on entering the block."""

    def __init__(self, out: Path, overwrite: bool = False, signature: tuple[str, ...] = MARKERS,
                 what: str = "run", inputs: Iterable[Path | str | None] = ()) -> None:
        self.out = Path(out)
        self.signature = tuple(signature)
        self.inputs = list(inputs)
        check_output(self.out, overwrite, self.signature, what, self.inputs)
        self.where = self.out
        self._lock = OutputLock(self.out)
        self.tmp: Path | None = None

    def __enter__(self) -> "ResultFolder":
        self._lock.acquire()
        try:
            remove_stale_staging(self.out)
            self.tmp = Path(tempfile.mkdtemp(prefix=f".{self.out.name}.{STAGING}", dir=self.out.parent))
            os.chmod(self.tmp, 0o777 & ~UMASK)
        except BaseException:
            self._lock.release()
            raise
        return self

    def commit(self, status: str = "completed") -> Path:
        """Move the staging folder into place (``status`` completed or ended) or beside ``--out``
        (interrupted, failed, analysis_failed: see the module docstring); returns where it went.
        Not cut in half by SIGINT/SIGTERM (errors.critical)."""
        target = self.out
        if status not in COMPLETE and _holds_something_else(self.out, self.signature):
            target = _beside(self.out, status, self.signature)
        with critical():
            old = swap_folder(self.tmp, target)
            self.tmp = None
            self.where = target
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        return target

    def __exit__(self, kind, exc, tb) -> None:
        try:
            if self.tmp is not None:
                shutil.rmtree(self.tmp, ignore_errors=True)
                self.tmp = None
        finally:
            self._lock.release()
        if exc is not None and disk_full(exc):
            raise disk_full_error(self.out, exc, "it holds what it held before") from None


class ResultFile:
    """``with ResultFile(out, ...) as f:`` the rule for a command that writes one file (and
    companions beside it, each written by ``results.atomic_write``): checked when made, locked in
    the block, a full disk named."""

    def __init__(self, out: Path, overwrite: bool = False, inputs: Iterable[Path | str | None] = (),
                 suffixes: tuple[str, ...] = (), flag: str = "--out") -> None:
        self.out = Path(out)
        self.flag = flag
        check_output_file(self.out, overwrite, inputs, suffixes, flag)
        self._lock = OutputLock(self.out, flag)

    def __enter__(self) -> "ResultFile":
        self._lock.acquire()
        return self

    def __exit__(self, kind, exc, tb) -> None:
        self._lock.release()
        if exc is not None and disk_full(exc):
            raise disk_full_error(self.out, exc, "an earlier file of that name is as it was", self.flag) from None


def study_inputs(study) -> list[Path]:
    """The files a study was read from: its file and the files it extends."""
    return list(study_chain(study.path)) if study is not None and study.path is not None else []


OUTPUT_PARAMETER = re.compile(r"(^|_)record_file$")


def output_parameters(study) -> list[tuple[str, str, Path]]:
    """(dotted key, field, path) of every parameter of the study that names a file it writes
    (``record_file``, ``*_record_file``), set to a path."""
    found = []
    for name, spec in study.components.items():
        for param, value in (spec.parameters or {}).items():
            if OUTPUT_PARAMETER.search(param) and isinstance(value, str) and value:
                found.append((f"{name}.{param}", f"components.{name}.parameters.{param}", Path(value)))
    return found


class WrittenAside:
    """The files a run writes outside ``--out`` (output parameters), each locked (OutputLock) and under a
    unique temporary name beside its target while the run goes; ``finish(keep)`` renames each over its
    target (the recording up to where the run stopped) or, ``keep`` false (a full disk), removes them
    all, and lets go of the locks."""

    def __init__(self) -> None:
        self.files: list[tuple[Path, Path, str]] = []     # (temporary, target, the option that named it)
        self.locks: list[OutputLock] = []

    def add(self, target: Path, flag: str = "--out") -> Path:
        self.locks.append(OutputLock(target, flag).acquire())
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=f".writing{target.suffix}", dir=target.parent)
        os.close(fd)
        self.files.append((Path(tmp), target, flag))
        return Path(tmp)

    def finish(self, keep: bool = True) -> list[Path]:
        done = []
        with critical():
            for tmp, target, _ in self.files:
                if keep and tmp.exists():
                    os.chmod(tmp, 0o666 & ~UMASK)
                    os.replace(tmp, target)
                    done.append(target)
                else:
                    tmp.unlink(missing_ok=True)
            for lock in self.locks:
                lock.release()
        self.files, self.locks = [], []
        return done

    @contextmanager
    def kept(self):
        """``with aside.kept():`` the run writing these files; when it ends, stopped or not, each is
        renamed over its target (what was written until then), but a full disk (the error or its cause)
        removes them all and is an OutputError naming the file it filled."""
        try:
            yield self
        except BaseException as exc:
            cause = exc if disk_full(exc) else exc.__cause__
            if not disk_full(cause) or not self.files:
                self.finish(keep=True)
                raise
            tmp, target, flag = next((f for f in self.files if str(f[0]) == str(cause.filename)), self.files[0])
            self.finish(keep=False)
            raise disk_full_error(target, OSError(cause.errno, cause.strerror, str(target)), "none of its files was "
                                  "kept", flag) from None
        self.finish(keep=True)


def write_aside(study, overwrite: bool, inputs: Iterable[Path], place=None, flag_of=None):
    """(the study with its output parameters placed, a WrittenAside): each file the study writes
    (``output_parameters``) is placed by ``place(key, field, path)`` when it returns a path (the
    caller's own folder), else written aside under the rule of every written file (check_output_file:
    an existing file replaced only with ``overwrite``, an input never; locked while written; a unique
    temporary name renamed over it when the run ends). ``flag_of(field, path)``: the option that named
    the file, for the messages (by default where the study set it)."""
    moved: dict[str, str] = {}
    aside = WrittenAside()
    try:
        for key, field, path in output_parameters(study):
            full = path.resolve()
            flag = flag_of(field, full) if flag_of is not None else f"{study.origin(field)}:"
            check_inputs(full, inputs, flag=flag)
            there = place(key, field, full) if place is not None else None
            if there is None:
                check_output_file(full, overwrite, inputs, flag=flag)
                full.parent.mkdir(parents=True, exist_ok=True)
                there = aside.add(full, flag)
            moved[key] = str(there)
    except BaseException:
        aside.finish(keep=False)
        raise
    return (study.with_values(moved) if moved else study), aside


def place_output_parameters(study, out: Path, staging: Path, named: Iterable[Path] = (),
                            inputs: Iterable[Path] = (), overwrite: bool = False):
    """(the study with its output parameters placed, a WrittenAside): a path inside ``--out`` is
    written into the staging folder (and so moves with the result); a path outside it only when the
    user named it on the command line (``--set``, or one of ``named``, a file or a folder that holds
    it), written aside (``write_aside``); an input never."""
    out = Path(out).resolve()
    named = {Path(p).resolve() for p in named}

    def place(key: str, field: str, full: Path) -> Path | None:
        if _inside(full, out):
            inside = Path(staging) / full.relative_to(out)
            inside.parent.mkdir(parents=True, exist_ok=True)
            return inside
        if not any(_inside(full, n) for n in named) and not study.origin(field).startswith("--set"):
            raise OutputError(f"{study.origin(field)} = {str(full)!r}: writes outside --out {out}; name it on "
                              f"the command line (--set {key}={full}) or give a path inside --out")
        return None
    return write_aside(study, overwrite, list(inputs), place)
