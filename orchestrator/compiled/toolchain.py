"""Compile a loop's sources into a shared library, once per shape: the cache folder is named by a
hash of everything the library fixes (every generated source, every file they include, the
compiler and its flags), and the library answers ``agc_token()`` with that hash, checked on load,
so a library of another shape is never used. The library is written aside and moved into place
(two processes compiling the same shape both end with a whole library).

The cache is trusted only when it is ours: its folders (and the library) owned by this user and
writable by no one else (a folder that is not is refused, named, before anything is loaded), and a
library is loaded only when the SHA-256 of its bytes is the one recorded when it was built
(``libloop.sha256`` beside it), checked before it is loaded, so no constructor of a planted or
damaged library runs (and, the folder being writable by this user alone, none can replace it between
the check and the load). A library that does not match (truncated, damaged, replaced) is built again."""
from __future__ import annotations

import ctypes
import functools
import hashlib
import os
import shutil
import stat
import subprocess
import tempfile
from pathlib import Path

from ..errors import ComputationError, InputError

FLAGS = ["-O2", "-std=gnu99", "-shared", "-fPIC", "-fno-fast-math"]
_LOADED: dict[str, ctypes.CDLL] = {}


class CompilerMissing(InputError):
    """No C compiler on this machine (the message names the package to install)."""


class CompileError(ComputationError):
    """The compiler refused the generated sources, or a cached library is not of its shape."""


class UntrustedCache(InputError):
    """The compiled engine's cache folder is not this user's alone (the message names it)."""


def compiler() -> str:
    """The C compiler: $CC, else cc or gcc on PATH."""
    for name in (os.environ.get("CC"), "cc", "gcc"):
        if name and shutil.which(name):
            return shutil.which(name)
    raise CompilerMissing("the compiled engine needs a C compiler and none was found ($CC, cc, gcc): install the "
                          "Debian package gcc (apt-get install gcc) or run with --engine python")


def cache_root() -> Path:
    """$AGROBOT_CACHE/compiled, else ~/.cache/agrobot/compiled."""
    base = os.environ.get("AGROBOT_CACHE") or os.path.join(os.path.expanduser("~"), ".cache", "agrobot")
    return Path(base) / "compiled"


@functools.lru_cache(maxsize=None)
def _version(cc: str) -> str:
    try:
        return subprocess.run([cc, "--version"], capture_output=True, text=True, timeout=30).stdout.splitlines()[0]
    except (OSError, subprocess.SubprocessError, IndexError):
        return cc


def shape_key(units: dict[str, str], include_dirs: list[Path], files: list[Path]) -> str:
    """The hash of a shape: sources, included files, compiler and flags."""
    cc = compiler()
    h = hashlib.sha256()
    for part in [_version(cc), " ".join(FLAGS), *sorted(str(d) for d in include_dirs)]:
        h.update(part.encode() + b"\0")
    for name in sorted(units):
        h.update(name.encode() + b"\0" + units[name].encode() + b"\0")
    for path in sorted(set(files)):
        h.update(path.name.encode() + b"\0" + _content(path, path.stat().st_mtime_ns) + b"\0")
    return h.hexdigest()[:32]


@functools.lru_cache(maxsize=256)
def _content(path: Path, mtime_ns: int) -> bytes:
    return path.read_bytes()


LIBRARY, DIGEST = "libloop.so", "libloop.sha256"


def untrusted(path: Path) -> str | None:
    """Why ``path`` (a cache folder or file) cannot be trusted, or None: owned by another user, or
    writable by its group or by others."""
    info = os.lstat(path)
    if stat.S_ISLNK(info.st_mode):
        return "is a symbolic link"
    if info.st_uid != os.getuid():
        return f"is owned by user {info.st_uid}, not by this user ({os.getuid()})"
    if info.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        return f"is writable by {'others' if info.st_mode & stat.S_IWOTH else 'its group'} (mode {info.st_mode & 0o777:o})"
    return None


def trusted_root() -> Path:
    """The cache folder (created 0700 when missing), refused by name when it is not ours alone."""
    root = cache_root()
    try:
        root.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        root.mkdir(exist_ok=True, mode=0o700)
    except OSError as exc:
        raise UntrustedCache(f"the compiled engine's cache {root}: cannot create it ({exc.strerror or exc}); set "
                             f"AGROBOT_CACHE to a folder of yours or run with --engine python") from None
    why = untrusted(root)
    if why is not None:
        raise UntrustedCache(f"the compiled engine's cache {root} {why}: a library there could be anyone's, so none "
                             f"is loaded; remove the folder (it is made again, private), or set AGROBOT_CACHE to a "
                             f"folder of yours, or run with --engine python")
    return root


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _verified(folder: Path) -> bool:
    """``folder``'s library may be loaded: the folder and the library are ours alone and the
    library's bytes hash to the digest recorded when it was built (else it is built again)."""
    try:
        if untrusted(folder) or untrusted(folder / LIBRARY) or untrusted(folder / DIGEST):
            return False
        recorded = (folder / DIGEST).read_text().strip()
        with open(folder / LIBRARY, "rb") as f:
            return _digest(f.read()) == recorded
    except (OSError, UnicodeError):
        return False


def _build(key: str, folder: Path, units: dict[str, str], include_dirs: list[Path]) -> None:
    """Compile the shape ``key`` into ``folder`` (its library and the library's digest), written aside
    and moved into place; a folder there that failed the check is removed first."""
    if folder.exists() or folder.is_symlink():
        if _verified(folder):            # another process placed the same shape meanwhile
            return
        _set_aside(folder)
    with tempfile.TemporaryDirectory(dir=folder.parent, prefix=f".{key}.", ignore_cleanup_errors=True) as tmp:
        work = Path(tmp)
        sources = {**units, "token.c": f'const char *agc_token(void) {{ return "{key}"; }}\n'}
        for name, text in sources.items():
            (work / name).write_text(text)
        cmd = [compiler(), *FLAGS, *[f"-I{d}" for d in include_dirs], "-o", str(work / LIBRARY),
               *[str(work / n) for n in sorted(sources)], "-lm"]
        done = subprocess.run(cmd, capture_output=True, text=True)
        if done.returncode != 0:
            raise CompileError(f"compiling the loop failed ({' '.join(cmd[:2])} ...):\n{done.stderr[-3000:]}")
        (work / DIGEST).write_text(_digest((work / LIBRARY).read_bytes()) + "\n")
        os.chmod(work, 0o700)
        try:
            os.replace(work, folder)
        except OSError:            # another process placed the same shape first: use its library
            pass


def _set_aside(folder: Path) -> None:
    """Remove a cache folder that failed the check: first renamed to a name of this process's own
    (one step: a process loading the shape sees the folder whole or not at all), then deleted."""
    aside = folder.with_name(f".{folder.name}.stale.{os.getpid()}.{os.urandom(4).hex()}")
    try:
        os.replace(folder, aside)
    except FileNotFoundError:            # another process set it aside first
        return
    if aside.is_dir() and not aside.is_symlink():
        shutil.rmtree(aside, ignore_errors=True)
    else:
        aside.unlink(missing_ok=True)


def library(units: dict[str, str], include_dirs: list[Path], files: list[Path]) -> tuple[ctypes.CDLL, str, bool]:
    """(the loaded library, its key, whether it was compiled now) for the sources ``units``
    ({file name: C text}); compiled only when no library of that key is cached and verified
    (the module's rule)."""
    key = shape_key(units, include_dirs, files)
    if key in _LOADED:
        return _LOADED[key], key, False
    folder = trusted_root() / key
    built = not _verified(folder)
    if built:
        _build(key, folder, units, include_dirs)
        if not _verified(folder):
            raise CompileError(f"{folder / LIBRARY}: the library just built does not match its recorded digest; "
                               f"remove {folder}")
    lib = ctypes.CDLL(str(folder / LIBRARY))      # checked in a folder only this user may write
    lib.agc_token.restype = ctypes.c_char_p
    if lib.agc_token().decode() != key:
        raise CompileError(f"{folder / LIBRARY}: the cached library answers another shape ({lib.agc_token().decode()}); "
                           f"remove {folder}")
    if hasattr(lib, "agc_run"):          # a loop's entry (another library binds its own functions)
        ptr = ctypes.POINTER(ctypes.c_double)
        lib.agc_run.argtypes = [ptr, ptr, ptr, ctypes.c_long, ptr]
        lib.agc_run.restype = ctypes.c_int
    _LOADED[key] = lib
    return lib, key, built
