"""MATLAB ``.mat`` recordings as tables: each struct a group on its own clock, each field a channel.

Versions 4, 5, 6 and 7 are read with scipy.io.loadmat; version 7.3 (an HDF5 file behind a
128-byte MATLAB header) with h5py, the ``matlab`` extra (without it the file is refused, named,
saying so). A struct (``odometry.Ticks``, ``odometry.Time``) becomes one table named after it
(``TABLE.COLUMN`` in ``--signal``: ``odometry.Ticks[0]``); a struct inside a struct one named
``outer_inner``; the numeric arrays at the top level of the file one table named after the file.
Of a group's fields:

- the time field is the first whose name, in any letter case, is a time's (measurements.tables.
  TIME_NAMES: ``t``, ``time``, ``timestamp`` ...) and which holds one number per row; it is the
  group's clock, read as a table's time column is (POSIX ns, us, ms or s from its size, else
  seconds from its own start; ``--time`` declares its unit). A time in MATLAB datenum days
  (between the years 1900 and 2100, days since year 0, stepping by less than DATENUM_STEP days) is
  turned into POSIX seconds,
  ``t = (datenum - 719529) x 86400``, and said so;
- a field of one column is a channel named as the field; one of K columns K channels
  ``field[0]`` .. ``field[K-1]``, or named by the group's column-name field (``names``, ``labels``,
  ``columns``, ``<field>Names`` ..., K texts) where it has one; an array stored as K rows of the
  time's length (a row per channel) is read by its columns, said so;
- scalars and texts are named in the notes (not channels), as are the fields left out (more than
  two dimensions, complex, MATLAB objects such as table or string that scipy cannot read, arrays
  far from the time's length).

Rows: a field's rows are matched to the times from the first: where their counts differ (a time
vector one longer than its data, as a logger writes the stamp of an interval's end), the rows
beyond the shorter are left out and named in the notes with the times they held, never silently;
matching from the last instead (each value at the next time) is the choice passed over.

Clocks: each group is a clock of its own (Streams.groups); a group whose times count from its own
start is named so beside the groups on POSIX dates (streams.is_boot_clock), in ``--list`` and in
the report, and the audit checks the lags between the groups' clocks as it does for any tables.

Imported where used: h5py (the matlab extra, for v7.3 files only).
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.io import loadmat
from scipy.io.matlab import mat_struct, matfile_version

from .log import LogError
from .streams import is_boot_clock
from .tables import GROUPED_FILES, TIME_NAMES, Table, TableReader, list_tables, table_streams

SUFFIX = ".mat"
HDF5_MAGIC = b"\x89HDF\r\n\x1a\n"
HDF5_AT = 512                      # a v7.3 file: the 128-byte MATLAB text header in a 512-byte user block
DATENUM_1970 = 719529.0            # MATLAB datenum of 1970-01-01 (days since year 0)
DATENUM_SPAN = (693962.0, 767011.0)  # datenums of 1900-01-01 and 2100-01-01: a time there is in days
DATENUM_STEP = 1e-3                # days (86 s): a datenum's steps are below; a seconds clock 8 days from its
                                   # start (in DATENUM_SPAN too) steps by less only above 1 kHz
_LABELS = re.compile(r"^(?:col(?:umn)?_?names?|names|labels|headers?|columns|variable_?names|channel_?names)$", re.I)
_NAME = re.compile(r"[^A-Za-z0-9_]+")


@dataclass
class Skipped:
    """A variable or field that is not an array of numbers, with why."""

    why: str


@dataclass
class _Fields:
    """One group's fields read: the columns, the notes, the time field's name."""

    columns: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)
    time: str | None = None
    rows: dict = field(default_factory=dict)      # field -> its rows (a channel's field: its name before [k])


def mat_version(path: Path) -> str:
    """'4', '5' (MATLAB 5, 6 and 7) or '7.3'; a LogError naming the file when it is no MAT-file."""
    with open(path, "rb") as f:
        head = f.read(HDF5_AT + len(HDF5_MAGIC))
    if head[HDF5_AT:].startswith(HDF5_MAGIC) or head.startswith(HDF5_MAGIC):
        return "7.3"
    try:
        major, _ = matfile_version(str(path))
    except Exception as exc:        # noqa: BLE001 - scipy raises several kinds on a file that is none
        raise LogError(f"{path}: not a MATLAB MAT-file ({type(exc).__name__}: {exc}); expected a file written by "
                       f"MATLAB's save (v4, v6, v7 or v7.3) or scipy.io.savemat; it begins {head[:20]!r}") from None
    return "4" if major == 0 else "5"


def mat_variables(path: Path) -> tuple[str, dict]:
    """(the MAT-file's version, its variables: name -> array, dict of fields (a struct), str,
    list of str, or Skipped)."""
    version = mat_version(path)
    if version == "7.3":
        return version, _hdf5_variables(path)
    try:
        raw = loadmat(str(path), squeeze_me=True, struct_as_record=False, chars_as_strings=True)
    except Exception as exc:        # noqa: BLE001 - a damaged file raises several kinds
        raise LogError(f"{path}: a damaged MAT-file: scipy.io.loadmat cannot read it ({type(exc).__name__}: "
                       f"{exc})") from None
    return version, {k: _plain(v) for k, v in raw.items() if not k.startswith("__")}


def _plain(value):
    """A loadmat value as an array, a dict of fields, a str, a list of str, or Skipped."""
    if isinstance(value, mat_struct):
        return {f: _plain(getattr(value, f)) for f in value._fieldnames}
    if isinstance(value, str):
        return value
    if isinstance(value, np.ndarray) and value.dtype == object:
        items = list(value.ravel())
        if items and all(isinstance(x, str) for x in items):
            return [str(x) for x in items]
        if items and all(isinstance(x, mat_struct) for x in items):
            return Skipped(f"an array of {len(items)} structs (read a struct of arrays, or one element)")
        return Skipped(f"a cell array of {value.shape} (cells are not channels)")
    if isinstance(value, np.ndarray) or np.isscalar(value):
        return np.asarray(value)
    return Skipped(f"a MATLAB object ({type(value).__name__}: a table, timetable, string or class instance, "
                   f"which scipy cannot read; save it as a struct of arrays, e.g. table2struct(T, 'ToScalar', true))")


def _hdf5_variables(path: Path) -> dict:
    """A v7.3 file's variables (h5py: its datasets are MATLAB's arrays transposed)."""
    try:
        import h5py
    except ImportError:
        raise LogError(f"{path}: a MATLAB v7.3 MAT-file (HDF5): reading it needs h5py, which is not installed "
                       f"(pip install 'agrobot-guidance[matlab]', or pip install h5py); or save it from MATLAB as "
                       f"v7: save(FILE, '-v7')") from None
    try:
        with h5py.File(path, "r") as f:
            return {k: _h5_plain(f, f[k]) for k in f if not k.startswith("#")}
    except OSError as exc:
        raise LogError(f"{path}: a damaged MATLAB v7.3 file: h5py cannot read it ({exc})") from None


def _h5_plain(f, node):
    """An HDF5 node of a v7.3 file as _plain gives a loadmat value."""
    import h5py

    kind = node.attrs.get("MATLAB_class", b"")
    kind = kind.decode() if isinstance(kind, bytes) else str(kind)
    if isinstance(node, h5py.Group):
        if kind not in ("struct", ""):
            return Skipped(f"a MATLAB object of class {kind} (save it as a struct of arrays)")
        return {k: _h5_plain(f, node[k]) for k in node}
    if node.attrs.get("MATLAB_empty", 0):
        return np.zeros(0)
    data = node[()]
    if kind == "char":
        return "".join(map(chr, np.asarray(data).T.ravel()))
    if kind == "cell":
        items = [_h5_plain(f, f[ref]) for ref in np.asarray(data).T.ravel()]
        return items if all(isinstance(x, str) for x in items) else Skipped(f"a cell array of {len(items)} cells")
    if np.asarray(data).dtype.kind not in "biufc":
        return Skipped(f"a MATLAB {kind or 'value'} of {np.asarray(data).dtype} (not numbers)")
    return np.squeeze(np.asarray(data).T)


def _time_field(fields: dict) -> str | None:
    """The group's time field: the first time name (TIME_NAMES, any letter case) holding one
    number per row."""
    lower = {k.lower(): k for k, v in fields.items() if isinstance(v, np.ndarray) and v.ndim == 1
             and v.dtype.kind in "iuf" and len(v) > 1}
    return next((lower[n] for n in TIME_NAMES if n in lower), None)


def _labels(fields: dict, name: str, width: int) -> list[str] | None:
    """The column names a group gives the K columns of field ``name``: a field ``<name>Names`` (or
    ``<name>_names``, ``<name>Labels``) or one named as column names (names, labels, columns ...),
    holding K texts."""
    own = [k for k in fields if k.lower() in (f"{name.lower()}names", f"{name.lower()}_names",
                                              f"{name.lower()}labels", f"{name.lower()}_labels")]
    for k in own + [k for k in fields if _LABELS.match(k)]:
        v = fields[k]
        if isinstance(v, list) and len(v) == width and len(set(v)) == width:
            return [str(x) for x in v]
    return None


def _rows(name: str, a: np.ndarray, n_time: int, notes: list) -> np.ndarray | None:
    """``a`` as rows x columns, or None (left out, said in ``notes``): a K x N array stored a
    row per channel, N the time's length, is read by its columns."""
    if a.dtype.kind not in "biuf":
        notes.append(f"{name}: {a.dtype} values ({'complex' if a.dtype.kind == 'c' else 'not numbers'}): left out")
        return None
    if a.ndim > 2:
        notes.append(f"{name}: an array of {a.ndim} dimensions {a.shape}: left out")
        return None
    a = a.reshape(len(a), -1)
    if n_time and a.shape[0] != n_time and a.shape[1] == n_time:
        notes.append(f"{name}: stored as {a.shape[0]} x {a.shape[1]} (a row per channel): read by its columns")
        a = a.T
    if n_time and not n_time / 2 <= a.shape[0] <= 2 * n_time:
        notes.append(f"{name}: {a.shape[0]} rows beside {n_time} times: not sampled on this clock, left out")
        return None
    return a


def _read_fields(group: str, fields: dict) -> _Fields:
    """The group's time and channels (each field's rows, not yet matched), with notes."""
    out = _Fields(time=_time_field(fields))
    n_time = len(fields[out.time]) if out.time else 0
    for name, v in fields.items():
        if name == out.time or isinstance(v, dict):
            continue
        if isinstance(v, Skipped):
            out.notes.append(f"{name}: {v.why}: left out")
        elif isinstance(v, (str, list)):
            if not (isinstance(v, list) and _is_label_field(fields, name, v)):
                out.notes.append(f"{name}: text {str(v)[:60]!r} (not a channel)")
        elif v.size == 1:
            out.notes.append(f"{name} = {v.item()!r} (a scalar: not a channel)")
        elif v.size > 1:
            a = _rows(name, v, n_time, out.notes)
            if a is None:
                continue
            out.rows[name] = a.shape[0]
            names = _labels(fields, name, a.shape[1]) if a.ndim == 2 and a.shape[1] > 1 else None
            if a.shape[1] == 1:
                out.columns[name] = a[:, 0]
            else:
                for k in range(a.shape[1]):
                    out.columns[names[k] if names else f"{name}[{k}]"] = a[:, k]
                if names:
                    out.notes.append(f"{name}: its {a.shape[1]} columns named by the group's column names "
                                     f"({', '.join(names)})")
    return out


def _is_label_field(fields: dict, name: str, v: list) -> bool:
    return any(_labels(fields, k, len(v)) == v for k, a in fields.items()
               if isinstance(a, np.ndarray) and a.ndim == 2 and a.shape[1] == len(v))


def _matched(read: _Fields, time: np.ndarray | None) -> pd.DataFrame:
    """The time and the channels matched row by row from the first; the rows beyond the shortest
    named in ``read.notes`` with the times they held (MATLAB's numbering, from 1)."""
    lengths = [len(c) for c in read.columns.values()]
    if time is None:                          # no clock: the channels of the commonest length
        n = max(set(lengths), key=lengths.count)
        for name in [c for c, x in read.columns.items() if len(x) != n]:
            read.notes.append(f"{name}: {len(read.columns.pop(name))} rows beside {n} of the others: left out")
        return pd.DataFrame(read.columns)
    n = min([len(time)] + lengths)
    rows = {read.time: len(time)} | read.rows
    shortest = next(c for c, k in rows.items() if k == n)
    for name, k in rows.items():
        if k > n:
            span = f"row {n + 1}" if k == n + 1 else f"rows {n + 1} to {k}"
            held = time[n:min(k, len(time))]
            at = f" (time {held[0]:.6f})" if len(held) == 1 else f" (times {held[0]:.6f} to {held[-1]:.6f})"
            read.notes.append(f"{name} holds {k} rows, {shortest} {n}: matched row by row from the first, {name}'s "
                              f"{span}{at if len(held) else ''} left out"
                              + (_passed_over(time, n) if name == read.time else ""))
    return pd.DataFrame({read.time: time[:n], **{c: x[:n] for c, x in read.columns.items()}})


def _passed_over(time: np.ndarray, n: int) -> str:
    """What matching from the last instead would have done: every value one time later."""
    step = float(np.median(np.diff(time[: n + 1]))) if n > 1 else float("nan")
    return (f"; passed over: matching from the last (each value at the end of its interval: {len(time) - n} "
            f"time(s) later, {step:.4g} s each)")


def _datenum(group: str, name: str, time: np.ndarray, units: dict, notes: list) -> np.ndarray:
    """A time in MATLAB datenum days as POSIX seconds, said so; other times as written."""
    mid = float(np.nanmedian(time))
    if not (DATENUM_SPAN[0] <= mid <= DATENUM_SPAN[1] and float(np.nanmax(np.diff(time))) < DATENUM_STEP):
        return time.astype(float)
    units[name] = "s"
    notes.append(f"{name}: MATLAB datenum days (years 1900 to 2100), taken as POSIX seconds (datenum - "
                 f"{DATENUM_1970:.0f}) x 86400; seconds from a start would be read with --time '{group}.{name}[s]'")
    return (time.astype(float) - DATENUM_1970) * 86400.0


def _table(path: Path, group: str, fields: dict) -> tuple[Table, str | None] | None:
    """One group as a table and its time field's name (None: no channel in it); the time field a
    column the tables' clock finder takes by name (measurements.tables.time_of)."""
    read = _read_fields(group, fields)
    if not read.columns:
        return None
    units: dict = {}
    time = None if read.time is None else _datenum(group, read.time, np.asarray(fields[read.time]), units, read.notes)
    if time is None:
        read.notes.insert(0, f"no time field (expected one named {', '.join(TIME_NAMES[:4])} ..., any letter case, "
                             f"one number per row): untimed")
    frame = _matched(read, time)
    return Table(path, group, frame, units, notes=[f"{group}: {n}" for n in read.notes]), read.time


def _groups(name: str, fields: dict, out: list) -> None:
    """(group name, fields) of a struct and of the structs inside it (``outer_inner``)."""
    out.append((name, fields))
    for k, v in fields.items():
        if isinstance(v, dict):
            _groups(f"{name}_{k}", v, out)


def mat_tables(path: Path) -> list[Table]:
    """The file's groups as tables: its top-level arrays (named after the file) and each struct;
    a LogError naming the file and its structs when no group has a time field."""
    _, variables = mat_variables(path)
    groups: list = []
    top = {k: v for k, v in variables.items() if not isinstance(v, dict)}
    if any(isinstance(v, np.ndarray) and v.size > 1 for v in top.values()):
        groups.append((_NAME.sub("_", path.stem).strip("_") or "mat", top))
    for k, v in variables.items():
        if isinstance(v, dict):
            _groups(k, v, groups)
    read = [found for name, fields in groups for found in [_table(path, name, fields)] if found is not None]
    if not any(time for _, time in read):
        held = "; ".join(f"{'the top-level arrays' if fields is top else 'struct'} {name} (fields "
                         f"{', '.join(list(fields)[:8]) or 'none'})" for name, fields in groups)
        raise LogError(f"{path}: no time field in it: {held or 'no variable of numbers'}; expected in each struct a "
                       f"field named {', '.join(TIME_NAMES[:4])} (any letter case, or {', '.join(TIME_NAMES[4:8])} "
                       f"...) holding one time per row of its data (POSIX seconds, or seconds from the recording's "
                       f"start)")
    _name_clocks(read)
    return [t for t, _ in read]


def _name_clocks(read: list[tuple[Table, str | None]]) -> None:
    """Each group whose times count from its own start, named beside the groups on POSIX dates
    (streams.is_boot_clock): different clocks, never joined as one."""
    timed = [(t, t.frame[time].to_numpy(float)) for t, time in read if time is not None]
    dated = [t.name for t, x in timed if not is_boot_clock(x)]
    for t, x in timed:
        if dated and is_boot_clock(x):
            t.notes.append(f"{t.name}: its clock counts from its own start ({x[0]:.3f} s), the clock of "
                           f"{', '.join(dated)} from 1970 (POSIX dates): a different clock, its times share none "
                           f"with theirs")


class MatlabReader(TableReader):
    """MATLAB .mat files: each struct a table on its own clock, joined on time as tables are."""

    kind, name, listed = "matlab", "MATLAB .mat files", "MATLAB structs as groups of channels on their own clocks"
    files = "*.mat, v4 to v7.3: a struct per group of channels, its time field its clock"
    suffixes = (SUFFIX,)
    raw = True

    def streams(self, files: dict[str, list[Path]], options, source: Path):
        streams = table_streams(files[self.kind], options, source)
        streams.report["files"] = {self.kind: list(dict.fromkeys(streams.report["files"].pop("table")))}
        return streams

    def listing(self, paths: list[Path], options, source: Path) -> list[str]:
        return [f"MATLAB file {p.name}: MAT-file version {mat_version(p)}{_header(p)}" for p in paths] + \
            list_tables(paths, options)


def _header(path: Path) -> str:
    """' (the header text MATLAB writes: platform, date)' of a v5 to v7.3 file, '' of a v4 one."""
    with open(path, "rb") as f:
        text = f.read(116).decode("ascii", "replace").strip(" \x00")
    return f" ({text})" if text.startswith("MATLAB") and text.isprintable() else ""


READER = MatlabReader()
GROUPED_FILES[SUFFIX] = mat_tables
