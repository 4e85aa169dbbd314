"""Unpacking FMUs and SSPs: only the entries a run uses, under a size cap, and always removed.

An FMU is a zip archive; a run needs its ``modelDescription.xml``, the binaries for this platform
and its ``resources/`` folder (FMI 2.0 section 2.3, FMI 3.0 section 2.5), never the sources or the
binaries of other platforms. An SSP needs its ``SystemStructure.ssd`` and the FMUs its components
name. Entries are streamed out with their sizes counted as they are written (a zip bomb whose
headers lie is stopped at the cap too), names that would leave the folder are refused, and each
folder is removed when its user is done with it, at exit (``atexit``, and the finalisers of a
worker process) and so on SIGINT/SIGTERM, which end the command through its normal exit.
"""
from __future__ import annotations

import atexit
import os
import shutil
import tempfile
import zipfile
from pathlib import Path, PurePosixPath
from typing import Callable, Iterable

from .errors import InputError

UNPACK_LIMIT = int(os.environ.get("FMU_UNPACK_LIMIT_MB", "1024")) * 1024 ** 2
_FOLDERS: set[Path] = set()


class UnpackError(InputError):
    """An archive cannot be unpacked (too large, an entry outside it, not a zip file)."""


def remove(folder: Path | None) -> None:
    if folder is not None:
        shutil.rmtree(folder, ignore_errors=True)
        _FOLDERS.discard(folder)


def remove_all() -> None:
    for folder in list(_FOLDERS):
        remove(folder)


atexit.register(remove_all)
try:                       # a worker process of a pool ends through os._exit: its finalisers still run
    from multiprocessing import util as _mp_util

    _mp_util.Finalize(None, remove_all, exitpriority=100)
except ImportError:        # pragma: no cover
    pass


def _safe_name(name: str) -> PurePosixPath | None:
    path = PurePosixPath(name)
    if path.is_absolute() or ".." in path.parts or not path.parts:
        return None
    return path


def unpack(archive: Path, wanted: Callable[[str], bool], what: str, limit: int | None = None) -> Path:
    """Stream the entries of ``archive`` that ``wanted`` accepts into a new temporary folder
    (removed at exit, or earlier by ``remove``); refuses past ``limit`` bytes."""
    limit = UNPACK_LIMIT if limit is None else limit
    archive = Path(archive)
    if not zipfile.is_zipfile(archive):
        raise UnpackError(f"{archive}: not a zip archive, so not an {what}")
    folder = Path(tempfile.mkdtemp(prefix=f"{what.lower()}-"))
    _FOLDERS.add(folder)
    written = 0

    def too_large(size: int) -> UnpackError:
        return UnpackError(f"{archive}: unpacking the entries a run uses takes more than {limit / 1024 ** 2:.0f} MB "
                           f"({size / 1024 ** 2:.0f} MB and more); the cap is FMU_UNPACK_LIMIT_MB="
                           f"{limit // 1024 ** 2} (set it higher for an {what} that is this large)")

    try:
        with zipfile.ZipFile(archive) as zf:
            infos = [i for i in zf.infolist() if not i.is_dir() and wanted(i.filename)]
            declared = sum(i.file_size for i in infos)
            if declared > limit:
                raise too_large(declared)
            for info in infos:
                name = _safe_name(info.filename)
                if name is None:
                    raise UnpackError(f"{archive}: entry {info.filename!r} would be written outside the {what}'s "
                                      f"folder; refused")
                target = folder.joinpath(*name.parts)
                target.parent.mkdir(parents=True, exist_ok=True)
                with zf.open(info) as src, open(target, "wb") as dst:
                    while chunk := src.read(1 << 20):
                        written += len(chunk)
                        if written > limit:
                            raise too_large(written)
                        dst.write(chunk)
    except BaseException:
        remove(folder)
        raise
    return folder


def fmu_entries(platforms: Iterable[str]) -> Callable[[str], bool]:
    """The entries of an FMU a run uses: its description, this platform's binaries, its resources."""
    prefixes = tuple(f"binaries/{p}/" for p in platforms) + ("resources/",)
    return lambda name: name == "modelDescription.xml" or name.startswith(prefixes)
