"""Folders of numpy channels as a recording: one folder per signal holding two arrays written by
``numpy.save``, ``t`` (its times, seconds) and ``value`` (one column, or several), with or without
the ``.npy`` suffix, at any depth of the recording's folder (comma2k19's ``processed_log/CAN/speed``,
``processed_log/IMU/gyro`` ...). Each channel is a table of its own on its own times, named by its
folders below the recording joined with ``_`` (``CAN_speed``); a one-column value is the column
``value``, a value of several columns ``value0``, ``value1`` ... (the publisher's order). The
times are taken as written, in seconds; a clock whose origin is not POSIX (a device's boot time)
is shared by every channel of the recording. A folder holding a ``t`` and a ``value`` is a channel by
their names: a file of them that is not a numpy array (a text export, a pickle, a truncated copy) is
refused naming the file and its first bytes, as is an array that is not numeric, a ``t`` that is not
one-dimensional or whose length is not the value's."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from .log import LogError

NPY_MAGIC = b"\x93NUMPY"
VALUE_NAMES = ("value", "value.npy")
TIME_NAMES = ("t", "t.npy")
MAX_DEPTH = 5              # folders below the recording searched for channels


@dataclass
class Channel:
    """One channel folder read: its table name, its columns, its times [s] and how they were read."""

    name: str
    frame: pd.DataFrame
    t: np.ndarray
    time_how: str


ROLES = {"t": "the times in seconds, one per sample", "value": "the samples, one row per time"}


def _head(path: Path) -> bytes:
    """The file's first bytes (empty when it cannot be read)."""
    try:
        with open(path, "rb") as f:
            return f.read(16)
    except OSError:
        return b""


def _is_npy(path: Path) -> bool:
    return _head(path).startswith(NPY_MAGIC)


def _checked_npy(path: Path) -> None:
    """A LogError naming ``path`` when it is not a numpy array file, with what it begins with."""
    head = _head(path)
    if not head.startswith(NPY_MAGIC):
        role = ROLES[path.name.removesuffix(".npy")]
        begins = f"begins {head!r}" if head else "is empty or unreadable"
        raise LogError(f"{path}: not a numpy array (it {begins}); expected a numpy.save array of {role} "
                       f"(a file starting {NPY_MAGIC!r})")


def _times_beside(value: Path) -> Path | None:
    return next((value.parent / n for n in TIME_NAMES if (value.parent / n).is_file()), None)


def is_channel_folder(folder: Path) -> bool:
    """A folder holding a ``value`` and a ``t`` beside it, either of them a numpy array (read_channel
    refuses the other by name when it is not one)."""
    value = next((folder / n for n in VALUE_NAMES if (folder / n).is_file()), None)
    times = None if value is None else _times_beside(value)
    return times is not None and (_is_npy(value) or _is_npy(times))


def channel_folders(root: Path) -> list[Path]:
    """The channel folders at or below ``root`` (at most MAX_DEPTH folders down), sorted."""
    found, level = [], [root]
    for _ in range(MAX_DEPTH + 1):
        found += [d for d in level if is_channel_folder(d)]
        level = [c for d in level for c in sorted(d.iterdir()) if c.is_dir() and not c.is_symlink()]
        if not level:
            break
    return sorted(found)


def read_channel(folder: Path, root: Path) -> Channel:
    """The channel of ``folder``; a LogError names the file that is not a channel's array."""
    value = next(folder / n for n in VALUE_NAMES if (folder / n).is_file())
    times = _times_beside(value)
    _checked_npy(times)
    _checked_npy(value)
    try:
        t, v = np.load(times, allow_pickle=False), np.load(value, allow_pickle=False)
    except (ValueError, OSError) as exc:
        raise LogError(f"{folder}: not a numpy channel: {type(exc).__name__}: {exc}; expected arrays written by "
                       f"numpy.save (t: times in s, value: the samples)") from None
    if t.ndim != 1 or t.dtype.kind not in "iuf":
        raise LogError(f"{times}: times of shape {t.shape} ({t.dtype}); expected one number per sample (seconds)")
    if v.dtype.kind not in "biuf" or v.ndim == 0 or len(v) != len(t):
        raise LogError(f"{value}: values of shape {v.shape} ({v.dtype}) beside {len(t)} times; expected numbers, "
                       f"one row per time")
    v = v.reshape(len(v), -1).astype(float)
    columns = {"value": v[:, 0]} if v.shape[1] == 1 else {f"value{k}": v[:, k] for k in range(v.shape[1])}
    parts = folder.relative_to(root).parts if folder != root else (folder.name,)
    return Channel("_".join(parts), pd.DataFrame(columns), t.astype(float),
                   f"the channel's own times ({times.name}, seconds as written)")
