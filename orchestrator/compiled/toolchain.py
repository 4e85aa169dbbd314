"""Compile a loop's sources into a shared library, once per shape: the cache folder is named by a
hash of everything the library fixes (every generated source, every file they include, the
compiler and its flags), and the library answers ``agc_token()`` with that hash, checked on load,
so a library of another shape is never used. The library is written aside and moved into place
(two processes compiling the same shape both end with a whole library)."""
from __future__ import annotations

import ctypes
import functools
import hashlib
import os
import shutil
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


def library(units: dict[str, str], include_dirs: list[Path], files: list[Path]) -> tuple[ctypes.CDLL, str, bool]:
    """(the loaded library, its key, whether it was compiled now) for the sources ``units``
    ({file name: C text}); compiled only when no library of that key is cached."""
    key = shape_key(units, include_dirs, files)
    if key in _LOADED:
        return _LOADED[key], key, False
    folder = cache_root() / key
    lib_path = folder / "libloop.so"
    built = False
    if not lib_path.exists():
        folder.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=folder.parent, prefix=f".{key}.", ignore_cleanup_errors=True) as tmp:
            work = Path(tmp)
            sources = {**units, "token.c": f'const char *agc_token(void) {{ return "{key}"; }}\n'}
            for name, text in sources.items():
                (work / name).write_text(text)
            cmd = [compiler(), *FLAGS, *[f"-I{d}" for d in include_dirs], "-o", str(work / "libloop.so"),
                   *[str(work / n) for n in sorted(sources)], "-lm"]
            done = subprocess.run(cmd, capture_output=True, text=True)
            if done.returncode != 0:
                raise CompileError(f"compiling the loop failed ({' '.join(cmd[:2])} ...):\n{done.stderr[-3000:]}")
            try:
                os.replace(work, folder)
            except OSError:            # another process placed the same shape first: use its library
                pass
        built = True
    lib = ctypes.CDLL(str(lib_path))
    lib.agc_token.restype = ctypes.c_char_p
    if lib.agc_token().decode() != key:
        raise CompileError(f"{lib_path}: the cached library answers another shape ({lib.agc_token().decode()}); "
                           f"remove {folder}")
    if hasattr(lib, "agc_run"):          # a loop's entry (another library binds its own functions)
        ptr = ctypes.POINTER(ctypes.c_double)
        lib.agc_run.argtypes = [ptr, ptr, ptr, ctypes.c_long, ptr]
        lib.agc_run.restype = ctypes.c_int
    _LOADED[key] = lib
    return lib, key, built
