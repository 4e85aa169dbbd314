"""ASAM MDF4 recordings (``.mf4``, ``.mdf``: Vector CANape/CANoe, ETAS INCA, loggers) read with asammdf.

An MDF file holds channel groups, each sampled on its own time master channel. A file of signals
becomes one table per channel group (``MDFGroup``; measurements.tables makes each a Table), its channels as columns with their
units, values after the file's conversion rules (linear, rational, tabular: what asammdf applies for
a physical value); the groups are then joined on time as several tables are. A channel whose
conversion gives text (a value-to-text table) is left out and named. The table of a group is named
after its acquisition name when it has one (``TABLE.COLUMN`` in ``--signal``), else ``group<N>``.

Bus logging (ASAM MDF bus-logging groups of ``CAN_DataFrame`` channels) is a CAN log: its frames
are decoded with the DBC as a candump is (measurements.raw_can reads it through python-can, which
reads MDF4 bus logging with asammdf).

Times: the group's master channel in seconds from the file's start, plus the header's start time
(POSIX seconds) where it is a date, so that groups and other sources share one clock.

Imported where used: asammdf (the mdf extra).
"""
from __future__ import annotations

import contextlib
import gc
import io
import re
import sys
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from .log import LogError
from .mdf4_links import check_links

BUS_CHANNEL = "CAN_DataFrame"
MDF_IDS = (b"MDF ", b"UnFinMF ")     # a finalized file; one a logger left unfinalized (ASAM MDF 4.1, ID block)
_NAME = re.compile(r"[^A-Za-z0-9_]+")


def _open(path: Path):
    """The MDF object, or a LogError naming the file and what was expected."""
    try:
        from asammdf import MDF
    except ImportError:           # pragma: no cover - a dependency of the project
        raise LogError(f"{path}: reading MDF4 needs asammdf (pip install asammdf)") from None
    with open(path, "rb") as f:
        head = f.read(8)
    if not head.startswith(MDF_IDS):
        raise LogError(f"{path}: not an MDF file: an ASAM MDF file starts with 'MDF ' (or 'UnFinMF ' while "
                       f"not finalized; its identification block), this one with {head[:8]!r}")
    check_links(path)
    why = None
    try:
        # asammdf prints the traceback of a failed finalization to stdout before it raises
        with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
            warnings.simplefilter("ignore")
            return MDF(str(path))
    except Exception as exc:       # noqa: BLE001 - asammdf raises many kinds on a damaged file
        why = f"{type(exc).__name__}: {exc}"
    _collect_quietly()             # the half-built reader complains as it is collected: not the user's concern
    if head.startswith(b"UnFinMF "):
        raise LogError(f"{path}: an unfinalized MDF file (its logger did not close it) that asammdf cannot finalize "
                       f"({why}); finalize it with the logger maker's tool and convert the finalized file")
    raise LogError(f"{path}: a damaged MDF file: asammdf cannot read it ({why})")


def _collect_quietly() -> None:
    hook, sys.unraisablehook = sys.unraisablehook, lambda _: None
    try:
        gc.collect()
    finally:
        sys.unraisablehook = hook


def is_bus_logging(path: Path) -> bool:
    """A file whose channel groups log CAN frames (ASAM MDF bus logging) rather than signals."""
    mdf = _open(path)
    try:
        return any(ch.name.startswith(BUS_CHANNEL) for group in mdf.groups for ch in group.channels)
    finally:
        mdf.close()


def _start_posix(mdf) -> float:
    """The header's start time in POSIX seconds, or 0 where it is not a date after 1980."""
    try:
        start = pd.Timestamp(mdf.header.start_time)
        start = start.tz_localize("UTC") if start.tzinfo is None else start.tz_convert("UTC")
        seconds = start.timestamp()
    except (AttributeError, ValueError, TypeError):
        return 0.0
    return float(seconds) if seconds > 315532800.0 else 0.0


def _group_name(mdf, index: int, taken: set[str]) -> str:
    group = mdf.groups[index]
    label = getattr(group.channel_group, "acq_name", "") or ""
    name = _NAME.sub("_", str(label)).strip("_") or f"group{index}"
    while name in taken:
        name = f"{name}_{index}"
    taken.add(name)
    return name


@dataclass
class MDFGroup:
    """One channel group of signals: its name, channels (a column each), units, times [s], how the
    times were found, and notes (channels left out)."""

    name: str
    frame: pd.DataFrame
    units: dict
    t: np.ndarray
    time_how: str
    notes: list


def mdf_tables(path: Path) -> list[MDFGroup]:
    """One group per channel group of signals, with times (s) and units; the text-valued channels
    are named in its notes."""
    mdf = _open(path)
    try:
        start = _start_posix(mdf)
        tables, taken = [], set()
        for index, group in enumerate(mdf.groups):
            master = mdf.masters_db.get(index)
            names = [(ch.name, i) for i, ch in enumerate(group.channels) if i != master]
            if not names or any(n.startswith(BUS_CHANNEL) for n, _ in names):
                continue
            columns, units, notes, t = {}, {}, [], None
            for name, i in names:
                signal = mdf.get(name, group=index, index=i)
                values = np.asarray(signal.samples)
                if values.dtype.kind not in "biuf":
                    notes.append(f"channel {name} holds text ({values.dtype}): left out")
                    continue
                if values.ndim != 1:
                    notes.append(f"channel {name} is an array of shape {values.shape[1:]}: left out")
                    continue
                t = np.asarray(signal.timestamps, float) if t is None else t
                columns[name] = values.astype(float)
                if signal.unit:
                    units[name] = str(signal.unit)
            table_name = _group_name(mdf, index, taken)
            if not columns:
                continue
            if master is None or t is None:
                raise LogError(f"{path}: channel group {table_name} has no time channel (a master channel of "
                               f"type time): MDF signals need one to be put on a clock")
            tables.append(MDFGroup(table_name, pd.DataFrame(columns), units, t + start,
                                   f"the group's time channel{' + the header start time' if start else ''} "
                                   f"(MDF4 {path.name}, group {index})", notes))
    finally:
        mdf.close()
    if not tables:
        raise LogError(f"{path}: no channel group of numeric signals (the file holds bus logging only, or text)")
    return tables
