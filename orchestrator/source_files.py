"""Input files opened safely (recordings, field files): only regular files, under a size limit that names itself.

A recording or field file is read only when it is a regular file (a symlink is followed to one;
a device such as /dev/zero, a pipe or a socket is refused before a byte is read, and a symlink
loop is named as such, not as a missing file). Files read whole into memory (a GeoJSON, an XML
document, a table, a time log's binary) are refused above ``WHOLE`` bytes, files read as a
stream (NMEA, CAN logs, ROS bags) above ``STREAMED``; ``--max-file-size`` sets both.
"""
from __future__ import annotations

import errno
import os
import re
import stat
from pathlib import Path

from .errors import InputError

WHOLE = 1 << 30           # bytes: 1 GiB read into memory
STREAMED = 16 << 30       # bytes: 16 GiB read a piece at a time (time is the only cost)
LIMITS = {"whole": WHOLE, "streamed": STREAMED}
UNITS = {"": 1, "B": 1, "K": 1 << 10, "KB": 1 << 10, "M": 1 << 20, "MB": 1 << 20, "G": 1 << 30, "GB": 1 << 30,
         "T": 1 << 40, "TB": 1 << 40}


def size_text(n: float) -> str:
    for unit, scale in (("GB", 1 << 30), ("MB", 1 << 20), ("kB", 1 << 10)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{int(n)} bytes"


def parse_size(text: str) -> int:
    """Bytes of '512M', '4G', '2.5GB', '1000000' (binary prefixes: 1K = 1024); InputError otherwise."""
    m = re.fullmatch(r"\s*([0-9]*\.?[0-9]+)\s*([KMGT]?B?)\s*", str(text), re.I)
    if m is None:
        raise InputError(f"--max-file-size {text!r}: expected a size such as 500M, 4G or 2.5GB")
    n = float(m.group(1)) * UNITS[m.group(2).upper()]
    if not n >= 1:
        raise InputError(f"--max-file-size {text!r}: expected a size of at least 1 byte")
    return int(n)


def set_limit(text: str | None) -> None:
    """``--max-file-size``: one limit for files read whole and streamed (None: the defaults)."""
    n = None if text is None else parse_size(text)
    LIMITS.update(whole=n or WHOLE, streamed=n or STREAMED)


def checked_path(path: str | Path, error: type[InputError] = InputError, what: str = "") -> Path:
    """``path`` when it exists (a file or a folder), with a symlink loop and a broken symlink
    named as such; the error names the path and ``what`` was looked for."""
    path = Path(path)
    try:
        os.stat(path)
    except OSError as exc:
        label = f"{path}{': ' + what if what else ''}"
        if exc.errno == errno.ELOOP:
            raise error(f"{label}: a symbolic link loop (the link leads back to itself); point it at a file") from None
        if path.is_symlink():
            raise error(f"{label}: a symbolic link to {os.readlink(path)}, which does not exist") from None
        if exc.errno == errno.ENOENT:
            raise error(f"{label}: no such file or folder") from None
        raise error(f"{label}: cannot read: {exc.strerror}") from None
    return path


def regular_file(path: str | Path, error: type[InputError] = InputError, how: str | None = "whole") -> Path:
    """``path`` when it is a regular file (a symlink to one counts) of at most the ``how``
    ('whole' or 'streamed'; None: no) limit; the error names the file, its kind or size and the limit."""
    path = checked_path(path, error)
    info = os.stat(path)
    if not stat.S_ISREG(info.st_mode):
        kind = ("a folder" if stat.S_ISDIR(info.st_mode) else "a character device" if stat.S_ISCHR(info.st_mode)
                else "a block device" if stat.S_ISBLK(info.st_mode) else "a pipe" if stat.S_ISFIFO(info.st_mode)
                else "a socket" if stat.S_ISSOCK(info.st_mode) else "not a regular file")
        target = f" (a link to {os.path.realpath(path)})" if path.is_symlink() else ""
        raise error(f"{path}: {kind}{target}, not a regular file: only files are read")
    limit = LIMITS[how] if how is not None else None
    if limit is not None and info.st_size > limit:
        raise error(f"{path}: {size_text(info.st_size)}, above the {size_text(limit)} limit for a file "
                    f"{'read whole into memory' if how == 'whole' else 'read as a stream'} "
                    f"(--max-file-size {size_text(info.st_size * 1.1).replace(' ', '')} raises it)")
    return path


def regular_files(folder: Path) -> list[Path]:
    """The regular files of a folder, sorted (devices, pipes and dangling links left out)."""
    out = []
    for p in sorted(folder.iterdir()):
        try:
            if stat.S_ISREG(os.stat(p).st_mode):
                out.append(p)
        except OSError:
            continue
    return out
