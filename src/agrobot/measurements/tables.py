"""Other tools' tables (CSV, TSV, Parquet) as a recording: one table, or several on their own
clocks (one CSV per ROS topic, a logger's files per sensor), joined on time.

A table is read as it comes, recognised by its content as well as its suffix (a ``.txt`` of
numbers in columns is a table): lines starting with ``#`` or ``//`` are comments; rows wrapped
whole in quotes (``"1.0,2.5,3"``) are unwrapped; the delimiter (``,`` ``;`` tab ``|`` or white
space) is the one that splits the rows below the header alike into the most numbers. A comment
line right above header-less rows that splits like them into names is their header (numpy.savetxt
writes ``# time(s),x(m),...``). The data
is the longest run of rows with one field count that hold numbers (from its first run of that
count); the header is the rows right above it that hold no number (or have its field count: a
row of IDs); lines above the header (a metadata line of keys and values, as OptiTrack Motive
writes one) are a preamble, named in the notes and left out. No header means a file without
one, its columns named ``col1``, ``col2`` ...; the first row names the columns, a row of units
under it (``deg``, ``km/h``, ``Unix epoch seconds`` ...) gives their declared units, further rows
of names are joined with ``_`` (a group's name over its columns: ``Position_X``), less the rows
with one name over every column (a body's name over all of them). A header's unit in brackets,
``speed [km/h]`` or ``speed (km/h)``, is the column's unit (the name is what precedes it). A
column that holds no number is named with why (empty, text); a table of text only is refused.
With lat/lon columns, a ``fix_quality`` column (or ``quality``, ``gps_quality`` ...) is the
receiver's fix quality, held at its own times; without one the log has none (never assumed). A
yaw rate taken from one axis of a table's gyro (``gyro_z``) beside its accelerometer (``acc_x/y/z``)
is checked against the axis that carries gravity (measurements.imu_axes). A column is named by
``TABLE.COLUMN`` (TABLE: the file name without its suffix) or by the column alone where only one
table has it.

Time, per table: ``--time`` names it (``COLUMN[unit]`` with any pint time unit, ``COLUMN[datetime]``
for date strings, ``SECONDS+NANOSECONDS`` for a pair of integer columns, ``A+B[datetime]`` for a
date and a time in two columns; ``TABLE.COLUMN`` takes it from one table for the tables without
their own, row by row: the same number of rows, or one fewer, a value per interval; they share its clock,
Streams.clocks: a lag between them is a sensor's own latency, never aligned), else it is
found by name (a seconds + nanoseconds pair such as ``s, ns`` or ``sec, nsec``; ``t``, ``time``,
``timestamp``, ``stamp``, ``%time`` ...; its unit from its header, else from its size: POSIX
nanoseconds, microseconds, milliseconds or seconds), else ``--rate``. Date strings without a zone
are taken as UTC (said so). Rows whose time is missing are dropped, repeated times kept once,
and the counts named.
"""
from __future__ import annotations

import csv
import io
import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from agrobot.orchestrator.units import base_unit

from .headings import as_yaw
from .imu_axes import GRAVITY, axis_check, axis_siblings
from .log import CANONICAL, LogError
from .modes import is_mode_name, mode_codes
from .mdf4 import mdf_tables
from .numpy_channels import channel_folders, read_channel
from .quirks import fixes_from_columns
from .runs import held
from .signal_expressions import SignalSpec, check_unit, evaluate, target_unit, unknown_name
from .streams import Reader, Series, Streams, is_boot_clock, iso
from .time_base import clock_steps, rollover_between, rollover_by_written, rollover_finding, span_step, undo_step

TABLE_SUFFIXES = (".csv", ".tsv", ".parquet", ".pq")
MDF_SUFFIXES = (".mf4", ".mdf")          # ASAM MDF4: one table per channel group (measurements.mdf4)
TEXT_SUFFIXES = (".txt", ".dat", ".log", "")      # read as a table when their content is one
PAIRS = (("s", "ns"), ("sec", "nsec"), ("secs", "nsecs"), ("sec", "nanosec"), ("seconds", "nanoseconds"),
         ("stamp_sec", "stamp_nanosec"), ("header.stamp.sec", "header.stamp.nanosec"),
         ("header.stamp.secs", "header.stamp.nsecs"), ("field.header.stamp.secs", "field.header.stamp.nsecs"))
TIME_NAMES = ("t", "time", "timestamp", "time_s", "times", "stamp", "%time", "utc", "datetime", "date_time",
              "unix_time", "posix_time", "ts", "time_stamp", "gps_time")
_UNIT_IN_HEADER = re.compile(r"^\s*(.*?)\s*[\[(]\s*([^\[\]()]+?)\s*[\])]\s*$")


@dataclass
class Table:
    """One file: its columns (numbers where they are), units from its header, its times."""

    path: Path
    name: str
    frame: pd.DataFrame
    units: dict = field(default_factory=dict)
    headerless: bool = False
    t: np.ndarray | None = None
    time_how: str = ""
    time_columns: tuple = ()
    notes: list = field(default_factory=list)
    mapped: set = field(default_factory=set)      # columns a --signal takes as data: never guessed as the clock
    time_base: list = field(default_factory=list)  # {finding, at}: its clock's steps and rollover (measurements.time_base)
    clock: str = ""                                # the table whose times it takes row by row (--time TABLE.COLUMN)


COMMENTS = ("#", "//")       # a line starting so is a comment (a ROS dump's '%time' is a header)
DELIMITERS = (",", ";", "\t", "|")
DECIMAL_COMMA = re.compile(r"^[-+]?\d*,\d+(?:[eE][-+]?\d+)?$")     # 1,5: a decimal comma (a European locale)
DECIMAL_POINT = re.compile(r"^[-+]?\d*\.\d+(?:[eE][-+]?\d+)?$")
_EPOCH = re.compile(r"^(?:(?:unix|posix|epoch|utc|gps)\s+)*(?:epoch\s+|time\s+)?(s|sec|secs|seconds|ms|milliseconds|us|"
                    r"microseconds|ns|nanoseconds)(?:\s+since\s+(?:the\s+)?(?:unix\s+)?epoch|\s+\(?(?:unix|posix|"
                    r"epoch|utc)\)?)?$")
_SHORT = {"sec": "s", "secs": "s", "seconds": "s", "milliseconds": "ms", "microseconds": "us", "nanoseconds": "ns"}
NO_UNIT = ("", "-", "--", "1", "none", "n/a", "na", "unitless", "dimensionless", "#", "text", "string", "enum")
DATE_UNITS = ("datetime", "date", "iso", "iso 8601", "iso8601", "date time", "yyyy-mm-dd hh:mm:ss", "utc date")


def _lines(path: Path, n: int = 20) -> list[str]:
    with open(path, encoding="utf-8", errors="replace") as f:
        return [line.strip() for line, _ in zip(f, range(n)) if line.strip()]


def _unquoted(line: str) -> str:
    """A row wrapped whole in one pair of quotes, unwrapped ("1,2,3" -> 1,2,3)."""
    return line[1:-1].replace('""', '"') if _wrapped(line) else line


def _wrapped(line: str) -> bool:
    return len(line) > 2 and line[0] == line[-1] == '"' and not any(f'"{s}"' in line for s in DELIMITERS + (" ",))


def _content(lines: list[str]) -> tuple[list[str], list[str]]:
    """(the rows, notes): blank and comment lines left out, rows wrapped whole in quotes unwrapped
    (when most rows are: a writer that quoted whole rows)."""
    notes = []
    rows = [x for x in lines if x and not x.startswith(COMMENTS)]
    comments = sum(1 for x in lines if x.startswith(COMMENTS))
    if comments:
        notes.append(f"{comments} comment line(s) (starting with {' or '.join(COMMENTS)}) left out")
    if rows and sum(map(_wrapped, rows)) > len(rows) / 2:
        rows = [_unquoted(x) for x in rows]
        notes.append("every row is wrapped in quotes: unwrapped")
    return rows, notes


def _split(row: str, sep: str) -> list[str]:
    if sep == " ":
        return row.split()
    return [x.strip() for x in next(csv.reader([row], delimiter=sep))]


def _delimiter(rows: list[str]) -> str:
    """The field separator read from the content: of , ; tab | and white space, the one that
    splits the rows below the header into one number (> 1) of fields, most of them numbers; else
    a comma."""
    sample = rows[len(rows) // 3:][:60] or rows
    best, score = None, (0.0, 0)
    for sep in DELIMITERS + (" ",):
        widths = [len(_split(r, sep)) for r in sample]
        width = max(set(widths), key=widths.count)
        if width < 2 or widths.count(width) < 0.9 * len(widths):
            continue
        fields = [v for r in sample for v in _split(r, sep)]
        numeric = round(sum(_is_number(v) or (sep != "," and bool(DECIMAL_COMMA.match(v))) for v in fields)
                        / max(len(fields), 1), 2)
        if (numeric, width) > score:
            best, score = sep, (numeric, width)
    return best or ","


def _decimal_points(rows: list[str], sep: str, notes: list) -> list[str]:
    """Rows whose numbers are written with a decimal comma (``1,5``; fields separated by another
    character, no number with a decimal point among them) with points instead, named with the
    count of columns that hold one; else the rows as they are."""
    if sep == ",":
        return rows
    sample = [_split(r, sep) for r in rows[len(rows) // 3:][:60] or rows]
    fields = [v for r in sample for v in r]
    if not any(DECIMAL_COMMA.match(v) for v in fields) or any(DECIMAL_POINT.match(v) for v in fields):
        return rows
    columns = {k for r in sample for k, v in enumerate(r) if DECIMAL_COMMA.match(v)}
    notes.append(f"numbers written with a decimal comma (1,5 for 1.5) in {len(columns)} columns: read as decimal points")
    return [re.sub(r"(?<=\d),(?=\d)", ".", r) for r in rows]


def declared_unit(text: str) -> str | None:
    """A units row's cell as a unit: pint's units, 'Unix epoch seconds' (and the like) -> s, ms ...,
    a date's 'datetime', '' for none (and 1); None where it is not a unit (a number other than 1)."""
    text = text.strip().strip("[]()").strip()
    low = text.lower()
    if low in NO_UNIT:
        return ""
    if low in DATE_UNITS:
        return "datetime"
    m = _EPOCH.match(low)
    if m:
        return _SHORT.get(m.group(1), m.group(1))
    if _is_number(text):                # a number other than 1 is a value (an ID), never a unit
        return None
    try:
        check_unit(text, "")
    except LogError:
        return None
    return text


def _holds_number(row: list[str]) -> bool:
    return any(_is_number(v) for v in row)


def _data_start(rows: list[list[str]]) -> tuple[int, int] | None:
    """(first row, field count) of the data: the rows holding a number come in runs of one field
    count; the data starts at the first run of the longest run's count at least min(3, the longest)
    rows long, and takes in the rows right above it that are mostly numbers and not wider (a row
    short of its last fields). A metadata line (key, value pairs holding numbers, another count) or
    a numeric row inside a header makes no such run. The field count is the widest of the data's
    first 50 rows. None when no row holds a number."""
    runs: list[list[int]] = []                        # [start, length, field count]
    for i, r in enumerate(rows):
        if not _holds_number(r):
            continue
        if runs and sum(runs[-1][:2]) == i and runs[-1][2] == len(r):
            runs[-1][1] += 1
        else:
            runs.append([i, 1, len(r)])
    if not runs:
        return None
    longest = max(runs, key=lambda run: run[1])
    start = next(s for s, n, w in runs if w == longest[2] and n >= min(3, longest[1]))
    while start > 0 and len(rows[start - 1]) <= longest[2] and _mostly_numbers(rows[start - 1]):
        start -= 1
    return start, max(len(r) for r in rows[start:start + 50] if _holds_number(r))


def _mostly_numbers(row: list[str]) -> bool:
    cells = [v for v in row if v]
    return bool(cells) and sum(map(_is_number, cells)) >= 0.5 * len(cells)


def _header_start(rows: list[list[str]], first: int, width: int) -> int:
    """The header's first row: the rows right above the data that hold no number or have its field
    count (an ID row of numbers between rows of names), less those on top that hold a number (a
    header starts with names); the rows above it are a preamble (a metadata line such as
    'Format Version,1.21,...,Capture Frame Rate,120')."""
    top = first
    while top > 0 and (not _holds_number(rows[top - 1]) or len(rows[top - 1]) == width):
        top -= 1
    while top < first and _holds_number(rows[top]):
        top += 1
    return top


def _header(rows: list[list[str]], path: Path, notes: list) -> tuple[list[str], dict, int, bool]:
    """(names, units, first data row, header-less) of the rows: the data is the rows from
    _data_start, the header the rows right above it (_header_start), a preamble above that is
    named in the notes and left out. The header's first row is the names, a row of units (most of
    its cells units) gives the units, other rows are more of the names (_names)."""
    found = _data_start(rows)
    if found is None:
        raise LogError(f"{path}: a table of text only, no column to take: no row holds a number (first rows: "
                       + "; ".join(",".join(r[:6]) for r in rows[:3]) + "); expected a header and rows of numbers")
    first, width = found
    top = _header_start(rows, first, width)
    if top:
        notes.append(f"{top} line(s) above the header taken as a preamble, not the table (their fields are not the "
                     f"data's {width}): " + "; ".join(repr(",".join(r)[:80]) for r in rows[:min(top, 3)])
                     + f"; header: {first - top} row(s) above the data" + (", none: columns named col1 ..."
                                                                          if top == first else ""))
    if top == first:
        return [f"col{i + 1}" for i in range(width)], {}, first, True
    head = [(list(r) + [""] * width)[:width] for r in rows[top:first]]
    units_row, name_rows = None, [head[0]]
    for r in head[1:]:
        cells = [None if _is_number(v) else declared_unit(v) for v in r if v]      # a row of IDs is names
        if units_row is None and cells and sum(c is not None for c in cells) >= 0.5 * len(cells):
            units_row = r
        else:
            name_rows.append(r)
    names = _names(name_rows, width, notes)
    units, unknown = {}, []
    for name, cell in zip(names, units_row or []):
        unit = declared_unit(cell) if cell else ""
        if unit:
            units[name] = unit
        elif unit is None:
            unknown.append(f"{name} {cell!r}")
    if units_row is not None:
        notes.append("a units row under the header, its units used: " + ", ".join(f"{n} [{u}]" for n, u in units.items())
                     + (f"; not units, ignored: {', '.join(unknown)} (declare one with --signal COLUMN=NAME[unit])"
                        if unknown else ""))
    return names, units, first, False


def _names(name_rows: list[list[str]], width: int, notes: list) -> list[str]:
    """The columns' names from a header's rows of names: a group's name spans the cells after it
    (merged cells); a row above the last that holds one name over all its cells tells no column
    from another and is left out (said); the rest are joined with '_' from the top, repeated names
    made unique with _2, _3 ... (_unique)."""
    for r in name_rows[:-1]:
        for k in range(1, width):
            r[k] = r[k] or r[k - 1]
    same = [r for r in name_rows[:-1] if len({v for v in r if v}) == 1]
    if same:
        notes.append(f"{len(same)} header row(s) with one name over every column left out of the names: "
                     + ", ".join(repr(next(v for v in r if v)) for r in same))
    name_rows = [r for r in name_rows if not any(r is x for x in same)]
    names = ["_".join(dict.fromkeys(r[k] for r in name_rows if r[k])) for k in range(width)]
    names = _unique([n or f"Unnamed: {k}" for k, n in enumerate(names)])      # named col<k+1> by read_table
    if len(name_rows) > 1:
        notes.append(f"a header of {len(name_rows)} rows of names, joined with '_': {', '.join(names[:10])}")
    return names


def _unique(names: list[str]) -> list[str]:
    seen: dict[str, int] = {}
    out = []
    for n in names:
        seen[n] = seen.get(n, 0) + 1
        out.append(n if seen[n] == 1 else f"{n}_{seen[n]}")
    return out


def looks_like_table(path: Path) -> bool:
    """A text file of rows with the same number of fields, mostly numbers (a header allowed)."""
    try:
        lines, _ = _content(_lines(path, 40))
    except OSError:
        return False
    if len(lines) < 3 or any(len(x) > 4000 for x in lines):
        return False
    sep = _delimiter(lines)
    split = [_split(x, sep) for x in lines[-12:]]
    widths = {len(r) for r in split}
    numeric = sum(_is_number(v) for r in split for v in r) / max(sum(len(r) for r in split), 1)
    return len(widths) == 1 and numeric > 0.8


def read_table(path: Path) -> Table:
    """A table file with its header's units; a LogError names the file when it is not a table."""
    suffix = path.suffix.lower()
    notes: list[str] = []
    units: dict = {}
    try:
        if suffix in (".parquet", ".pq"):
            frame, headerless = pd.read_parquet(path), False
        else:
            frame, units, headerless = _text_table(path, suffix, notes)
    except LogError:
        raise
    except Exception as exc:            # noqa: BLE001 - pandas raises many kinds
        raise LogError(f"{path}: cannot read as a table ({suffix}): {type(exc).__name__}: {exc}") from None
    if frame.shape[1] == 0 or len(frame) == 0:
        raise LogError(f"{path}: an empty table")
    names, drop = [], []
    for k, c in enumerate(frame.columns):
        text = str(c).strip()
        m = _UNIT_IN_HEADER.match(text)
        name, unit = (m.group(1), m.group(2)) if m and m.group(1) else (text, None)
        if name.startswith("Unnamed:") or name == "":
            name = f"col{k + 1}"
            col = frame[c]
            if pd.api.types.is_numeric_dtype(col) and col.nunique() <= 1:
                notes.append(f"column {k + 1} has no name and one value ({col.iloc[0]}): an index the writer left, "
                             f"ignored")
                drop.append(name)
        names.append(name)
        if unit:
            units[name] = unit
        elif text in units:
            units[name] = units.pop(text)
    frame.columns = names
    frame = frame.drop(columns=drop)
    notes += _text_columns(frame)
    return Table(path, path.stem, frame, units, headerless, notes=notes)


def _text_table(path: Path, suffix: str, notes: list) -> tuple[pd.DataFrame, dict, bool]:
    """(frame, units, headerless) of a text table: comments and quotes taken off, the delimiter
    read from the content, the header's rows (names, units) parsed (_header)."""
    with open(path, encoding="utf-8", errors="replace") as f:
        lines = [line.strip().strip("\x00").strip() for line in f]
    rows, more = _content(lines)
    notes += more
    if not rows:
        raise LogError(f"{path}: an empty table (no row of text in it: blank, zero bytes or comments only); expected a "
                       f"header and rows of numbers")
    sep = "\t" if suffix == ".tsv" else _delimiter(rows)
    head = _commented_header(lines, rows, sep)
    if head is not None:
        rows = [head] + rows
        notes[:] = [_one_comment_fewer(n) for n in notes if not n.startswith("1 comment line(s)")]
        notes.append(f"the header is a comment line ('{head[:40]}...', as numpy.savetxt writes one): its names used")
    rows = _decimal_points(rows, sep, notes)
    names, units, first, headerless = _header([_split(r, sep) for r in rows[:200]], path, notes)
    frame = pd.read_csv(io.StringIO("\n".join(rows[first:])), sep=r"\s+" if sep == " " else sep, header=None,
                        engine="python" if sep == " " else "c", skipinitialspace=True)
    names = (names + [f"col{i + 1}" for i in range(len(names), frame.shape[1])])[:frame.shape[1]]
    frame.columns = names
    if sep not in (",", "\t"):
        notes.append(f"fields separated by {'white space' if sep == ' ' else repr(sep)} (read from the content)")
    return frame, units, headerless


def _one_comment_fewer(note: str) -> str:
    """A note counting the comment lines left out, less the one that is the header."""
    count, _, rest = note.partition(" comment line(s)")
    return f"{int(count) - 1} comment line(s){rest}" if rest and count.isdigit() else note


def _commented_header(lines: list[str], rows: list[str], sep: str) -> str | None:
    """The comment line right above a header-less table's first row when, its marker taken off, it
    splits like the rows into as many names (no number among them): a header written as a comment
    (numpy.savetxt's ``# a,b,c``, Octave's); None otherwise."""
    above = None
    for line in lines:
        if not line:
            continue
        if not line.startswith(COMMENTS):
            break
        above = line
    if above is None or not rows or not any(_is_number(v) for v in _split(rows[0], sep)):
        return None
    text = above.lstrip("#/").strip()
    cells = _split(text, sep)
    if len(cells) < 2 or len(cells) != len(_split(rows[0], sep)) or any(not c or _is_number(c) for c in cells):
        return None
    return text


def _text_columns(frame: pd.DataFrame) -> list[str]:
    """Each column that holds no number, named with why: empty, or text (with an example)."""
    out = []
    for c in frame.columns:
        col = frame[c]
        if pd.api.types.is_numeric_dtype(col) and col.notna().any():
            continue
        if col.isna().all():
            out.append(f"column {c!r} holds no number: every value is missing")
            continue
        x = pd.to_numeric(col, errors="coerce")
        text = col[x.isna() & col.notna()]
        if x.notna().any():
            out.append(f"column {c!r} holds no number in {len(text)} of {len(col)} rows: text such as "
                       f"{str(text.iloc[0])[:30]!r} (row {int(text.index[0]) + 1} of the data)")
        else:
            out.append(f"column {c!r} holds no number: text such as {str(text.iloc[0])[:30]!r} (a label, a mode "
                       f"or a date: not a signal)")
    return out


def _is_number(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False


def table_files(source: Path) -> list[Path]:
    if source.is_file():
        return [source] if source.suffix.lower() in TABLE_SUFFIXES else []
    return sorted(p for p in source.iterdir() if p.is_file() and p.suffix.lower() in TABLE_SUFFIXES)


# --- time ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class TimeSpec:
    """``--time``: the column(s), and their unit or 'datetime'."""

    columns: tuple[str, ...]
    unit: str | None
    text: str


def parse_time(text: str | None) -> TimeSpec | None:
    if text is None:
        return None
    m = re.match(r"^(.*?)(?:\[([^\[\]]+)\])?\s*$", text.strip())
    body, unit = m.group(1).strip(), (m.group(2) or "").strip() or None
    columns = tuple(c.strip() for c in body.split("+"))
    if not body or not all(columns) or len(columns) > 2:
        raise LogError(f"--time {text!r}: expected COLUMN[unit] (s, ms, us, ns, h ...), COLUMN[datetime], "
                       f"SECONDS+NANOSECONDS, or DATE+TIME[datetime]")
    if unit and unit != "datetime":
        b = check_unit(unit, f"--time {text!r}")
        if b.exponents != base_unit("s").exponents:
            raise LogError(f"--time {text!r}: {unit!r} is not a unit of time; expected s, ms, us, ns or datetime")
    return TimeSpec(columns, unit, text)


def _column(table: Table, name: str) -> str | None:
    """The table's column called ``name`` or ``TABLE.name``."""
    if name.startswith(table.name + ".") and name[len(table.name) + 1:] in table.frame:
        return name[len(table.name) + 1:]
    return name if name in table.frame else None


def _datetime(values: pd.Series, where: str) -> tuple[np.ndarray, str]:
    try:
        parsed = pd.to_datetime(values, errors="coerce", utc=False, format="mixed")
    except (ValueError, OverflowError, pd.errors.OutOfBoundsDatetime) as exc:    # a date beyond 1677-2262, mixed zones
        raise LogError(f"{where}: the dates do not parse as one clock ({type(exc).__name__}: {exc}); first value "
                       f"{values.iloc[0]!r}; expected date strings between 1677 and 2262, or --time 'COLUMN[s]'") from None
    if not pd.api.types.is_datetime64_any_dtype(parsed):
        raise LogError(f"{where}: the dates do not parse as one clock (mixed time zones?); first value {values.iloc[0]!r}")
    if parsed.dt.tz is None:
        note = "date strings without a time zone, taken as UTC"
    else:
        note = "date strings with their zone"
        parsed = parsed.dt.tz_convert("UTC").dt.tz_localize(None)
    if parsed.isna().all():
        raise LogError(f"{where}: no value parses as a date and time (first: {values.iloc[0]!r})")
    # POSIX seconds in numpy, at the resolution pandas parsed (a date outside 1677-2262 has no ns stamp)
    stamps = parsed.to_numpy()
    secs = (stamps - np.datetime64(0, "s")) / np.timedelta64(1, "s")
    return np.where(np.isnat(stamps), np.nan, secs).astype(float), note


def _magnitude_unit(x: np.ndarray, name: str) -> tuple[float, str]:
    """A time column's unit from its size: POSIX ns, us, ms or s; else seconds (a relative clock),
    said with the --time that declares another for this column alone (``name``: TABLE.COLUMN; a
    bare COLUMN would declare it for every table that has one)."""
    big = float(np.nanmedian(np.abs(x))) if np.isfinite(x).any() else 0.0
    for limit, factor, unit in ((1e17, 1e-9, "ns"), (1e14, 1e-6, "us"), (1e11, 1e-3, "ms")):
        if big > limit:
            return factor, f"POSIX {unit} (from its size)"
    return 1.0, "s" + (" (POSIX, from its size)" if big > 1e8 else " (no unit stated: taken as seconds; "
                                                                       f"declare another with --time '{name}[ms]')")


def time_like(table: Table) -> list[str]:
    """Columns that could be a clock: named as one, or increasing throughout (a header-less dump)."""
    lower = {str(c).lower(): c for c in table.frame.columns}
    named = [lower[n] for n in TIME_NAMES if n in lower] + [lower[s] for s, ns in PAIRS if s in lower and ns in lower]
    rising = []
    for c in table.frame.columns:
        x = pd.to_numeric(table.frame[c], errors="coerce").to_numpy(float)
        if len(x) >= 3 and np.isfinite(x).all() and np.all(np.diff(x) > 0) and c not in named:
            rising.append(c)
    return list(dict.fromkeys(named + rising))


def time_of(table: Table, spec: TimeSpec | None) -> bool:
    """Set ``table.t`` from the spec or the table's own columns (by name; in a table without a
    header, the first column that increases throughout, the guess said); False when it has none.
    Other columns that could be the clock are named in the table's notes."""
    found = _time_of(table, spec)
    others = [c for c in time_like(table) if c not in table.time_columns]
    if found and others and spec is None:
        table.notes.append(f"time: {'+'.join(map(str, table.time_columns))} used; other columns that could be the clock: "
                           f"{', '.join(map(str, others[:5]))} (--time COLUMN[unit] picks one)")
    return found


def _time_of(table: Table, spec: TimeSpec | None) -> bool:
    f = table.frame
    where = str(table.path)
    if spec is not None:
        cols = [_column(table, c) for c in spec.columns]
        if all(cols):
            table.time_columns = tuple(cols)
            if spec.unit == "datetime":
                text = f[cols[0]].astype(str) if len(cols) == 1 else f[cols[0]].astype(str) + " " + f[cols[1]].astype(str)
                table.t, note = _datetime(text, f"{where}: --time {spec.text}")
                table.time_how = f"{'+'.join(cols)} ({note})"
            elif len(cols) == 2:
                table.t = _numbers(f[cols[0]], where, cols[0]) + 1e-9 * _numbers(f[cols[1]], where, cols[1])
                table.time_how = f"{cols[0]} + {cols[1]} x 1e-9 (seconds and nanoseconds)"
            else:
                x = _numbers(f[cols[0]], where, cols[0]) if pd.api.types.is_numeric_dtype(f[cols[0]]) else None
                if x is None:
                    raise LogError(f"{where}: --time {spec.text}: column {cols[0]!r} holds text "
                                   f"({f[cols[0]].iloc[0]!r}); for date strings write --time '{cols[0]}[datetime]'")
                if spec.unit:
                    table.t, table.time_how = x * base_unit(spec.unit).factor, f"{cols[0]} [{spec.unit}]"
                    _header_overruled(table, cols[0], spec)
                else:
                    factor, how = _magnitude_unit(x, f"{table.name}.{cols[0]}")
                    table.t, table.time_how = x * factor, f"{cols[0]} [{how}]"
            return True
        if len(spec.columns) == 1 and "." in spec.columns[0]:
            return _named_time(table)             # its own clock, else another table's row by row (read_tables)
        missing = [c for c, k in zip(spec.columns, cols) if not k]
        raise LogError(f"{where}: --time {spec.text}: no column {missing[0]!r}; columns: "
                       f"{', '.join(map(str, f.columns[:20]))}")
    if _named_time(table):
        return True
    first = f.columns[0] if len(f.columns) > 1 else None
    if table.headerless and first is not None and first in time_like(table) and first not in table.mapped \
            and _even(f[first].to_numpy(float)):
        c = first
        x = _numbers(f[c], where, c)
        factor, how = _magnitude_unit(x, f"{table.name}.{c}")
        table.t, table.time_columns = x * factor, (c,)
        table.time_how = (f"{c} [{how}] (guessed: no header, its first column increases throughout by even steps; "
                          f"--time COLUMN[unit] picks another)")
        table.notes.append(f"no header: columns named col1 ... col{f.shape[1]}; time guessed: {table.time_how}")
        return True
    return False


def _header_overruled(table: Table, column: str, spec: TimeSpec) -> None:
    """A note where --time gives ``column`` a unit other than the one its header states: the
    --time's is taken (the user's word stands), and a bare COLUMN names the TABLE.COLUMN that
    would declare it for one table alone."""
    stated = table.units.get(column)
    said = base_unit(stated) if stated else None        # a header's unit pint does not know: nothing to compare
    if said is None or spec.unit is None or math.isclose(said.factor, base_unit(spec.unit).factor):
        return
    alone = "" if "." in spec.text.split("[")[0] else \
        f" (a bare column name declares it in every table that has one: --time 'TABLE.{column}[{spec.unit}]' names one)"
    table.notes.append(f"time: the header states {column} in {stated}; --time {spec.text} takes it in {spec.unit}{alone}")


def _named_time(table: Table) -> bool:
    """Set ``table.t`` from a column named as a clock (a seconds + nanoseconds pair, then
    TIME_NAMES; its unit from the header, else from its size); False when none is."""
    f, where = table.frame, str(table.path)
    lower = {str(c).lower(): c for c in f.columns}
    for s, ns in PAIRS:
        if s in lower and ns in lower and pd.api.types.is_numeric_dtype(f[lower[s]]):
            table.t = _numbers(f[lower[s]], where, s) + 1e-9 * _numbers(f[lower[ns]], where, ns)
            table.time_columns = (lower[s], lower[ns])
            table.time_how = f"{lower[s]} + {lower[ns]} x 1e-9 (seconds and nanoseconds, found by name)"
            return True
    for name in TIME_NAMES:
        if name in lower:
            c = lower[name]
            table.time_columns = (c,)
            if not pd.api.types.is_numeric_dtype(f[c]):
                table.t, note = _datetime(f[c].astype(str), f"{where}: column {c!r}")
                table.time_how = f"{c} ({note}; found by name)"
            elif c in table.units:
                table.t = _numbers(f[c], where, c) * check_unit(table.units[c], f"{where}: column {c!r}").factor
                table.time_how = f"{c} [{table.units[c]}] (found by name)"
            else:
                x = _numbers(f[c], where, c)
                factor, how = _magnitude_unit(x, f"{table.name}.{c}")
                if c == "%time":                     # rostopic echo -p: receive time in ns
                    factor, how = 1e-9, "ns (rostopic's %time)"
                table.t, table.time_how = x * factor, f"{c} [{how}] (found by name)"
            return True
    return False


def _even(x: np.ndarray) -> bool:
    """Steps of a clock: 90 % of them within half the median step of it."""
    dt = np.diff(x)
    med = float(np.median(dt)) if len(dt) else 0.0
    return med > 0 and float(np.mean(np.abs(dt - med) <= 0.5 * med)) >= 0.9


def _numbers(col: pd.Series, where: str, name: str) -> np.ndarray:
    x = pd.to_numeric(col, errors="coerce").to_numpy(float)
    if not np.isfinite(x).any():
        raise LogError(f"{where}: column {name!r} holds no number (first value {col.iloc[0]!r})")
    return x


def _clean(table: Table) -> None:
    """Rows without a time dropped, rows in time order, a repeated time kept once (counted)."""
    t = table.t
    ok = np.isfinite(t)
    if (~ok).any():
        table.notes.append(f"{int((~ok).sum())} rows without a time dropped")
    frame, t = table.frame[ok].reset_index(drop=True), t[ok]
    data = [pd.to_numeric(frame[c], errors="coerce").to_numpy(float) for c in frame.columns if c not in table.time_columns]
    t, steps = clock_steps(t, data, table.path.name)
    table.time_base += steps
    order = np.argsort(t, kind="stable")
    if np.any(np.diff(t) < 0):
        table.notes.append(f"{int(np.sum(np.diff(t) < 0))} times step back: rows put in time order")
    frame, t = frame.iloc[order].reset_index(drop=True), t[order]
    keep = np.concatenate([[True], np.diff(t) > 0]) if len(t) else np.array([], bool)
    if (~keep).any():
        table.notes.append(f"{int((~keep).sum())} rows repeat the time before them: the first kept")
    table.frame, table.t = frame[keep].reset_index(drop=True), t[keep]


def mdf_groups(path: Path) -> list[Table]:
    """An MDF4 file's channel groups as tables, each on its own clock (measurements.mdf4)."""
    return [Table(path, g.name, g.frame, g.units, t=g.t, time_how=g.time_how, notes=g.notes)
            for g in mdf_tables(path)]


def numpy_groups(root: Path) -> list[Table]:
    """The numpy channel folders at or below ``root`` as tables, each on its own times
    (measurements.numpy_channels)."""
    return [Table(folder, c.name, c.frame, t=c.t, time_how=c.time_how)
            for folder in channel_folders(root) for c in [read_channel(folder, root)]]


# suffix -> the tables of a file of several groups: MDF4 here, MATLAB's by measurements.matlab (which
# builds on this module, its reader adding its own)
GROUPED_FILES: dict[str, Callable[[Path], list[Table]]] = dict.fromkeys(MDF_SUFFIXES, mdf_groups)


def _tables_of(path: Path) -> list[Table]:
    if path.is_dir():
        return numpy_groups(path)
    grouped = GROUPED_FILES.get(path.suffix.lower())
    return grouped(path) if grouped is not None else [read_table(path)]


def read_tables(paths: list[Path], time: str | None, rate: float | None, source: Path,
                mapped: tuple = ()) -> list[Table]:
    """The tables with their times; a table without a time of its own takes the ``--time``
    table's row by row (same rows, or one fewer: a value per interval), else ``--rate``.
    ``mapped``: the names the --signal expressions take as data (never guessed as a clock)."""
    spec = parse_time(time)
    tables = [t for p in paths for t in _tables_of(p)]
    for t in tables:
        t.mapped = {c for c in t.frame.columns if f"{t.name}.{c}" in mapped or str(c) in mapped}
    if spec is not None and not any(_column(t, c) for t in tables for c in spec.columns):
        raise LogError(f"{source}: --time {spec.text}: no table has column {spec.columns[0]!r}; tables: "
                       + "; ".join(f"{t.name}: {', '.join(map(str, t.frame.columns[:10]))}" for t in tables))
    timed = [t for t in tables if t.t is not None or time_of(t, spec)]      # an MDF group has its own clock
    clock = next((t for t in timed if spec is not None and all(_column(t, c) for c in spec.columns)), None)
    for t in tables:
        if t.t is not None:
            continue
        n = len(t.frame)
        if clock is not None and len(clock.frame) in (n, n + 1) and clock.frame.shape[1] == len(clock.time_columns):
            t.t, t.clock = clock.t[:n].copy(), clock.name
            t.time_how = (f"row by row from {clock.name} ({clock.time_how})"
                          + ("; one row fewer: a value per interval, at its start" if n + 1 == len(clock.frame) else ""))
        elif rate is not None:
            t.t = np.arange(n) / rate
            t.time_how = f"row k at k / {rate:g} Hz (--rate; the table has no time column)"
        else:                 # refused when a column of it is asked for (untimed)
            t.time_how = ""
    for t in tables:
        if t.t is not None:
            _clean(t)
    _rollover(tables)
    _stepped_by_span(tables)
    return tables


def _stepped_by_span(tables: list[Table]) -> None:
    """A table whose clock stepped forward where its columns could not tell, told by the other
    tables' span (measurements.time_base.span_step; files that start or end together agree within
    1.5 rows of the slowest): its later stamps moved back, named."""
    dated = [t for t in tables if t.t is not None and len(t.t) > 30 and not is_boot_clock(t.t)]
    if len(dated) < 2:
        return
    tol = 1.5 * max(float(np.median(np.diff(t.t))) for t in dated)
    for t in dated:
        k = span_step(t.t, [(float(o.t[0]), float(o.t[-1])) for o in dated if o is not t], tol)
        if k is not None:
            h = float(np.median(np.diff(t.t)))
            t.time_base.append(undo_step(t.t, k, h, t.path.name, "no column tells a step from a silence, but the "
                                         "file starts with the others and ends the step after them"))


def _rollover(tables: list[Table]) -> None:
    """Tables dated k x 1024 weeks before the others moved onto their dates; a table alone dated
    so before it was written named (measurements.time_base)."""
    dated = {t.name: t for t in tables if t.t is not None and len(t.t) and not is_boot_clock(t.t)}
    moves = rollover_between({n: (float(t.t[0]), float(t.t[-1])) for n, t in dated.items()})
    for name, move in moves.items():
        t = dated[name]
        against = ", ".join(n for n in dated if n not in moves)
        t.time_base.append({"at": None, "finding": rollover_finding(t.path.name, move, float(t.t[0]), against)})
        t.t = t.t + move
    for name, t in dated.items():
        said = rollover_by_written(t.path, float(t.t[-1]), t.path.name) if name not in moves else None
        if said is not None:
            t.time_base.append({"at": None, "finding": said})


def untimed(t: Table, tables: tuple = ()) -> LogError:
    """The error of a column asked of a table without a time: where a time could come from, and
    another table that is a clock of the same rows (named as a time, one increasing column)."""
    return LogError(f"{t.path}{_group_of(t)}: no time column (looked for a seconds + nanoseconds pair such as s, ns, and for "
                    f"{', '.join(TIME_NAMES[:8])} ...); columns: {', '.join(map(str, t.frame.columns[:12]))}; "
                    f"declare it with --time 'COLUMN[s]' (or [ms], [datetime], SECONDS+NANOSECONDS, TABLE.COLUMN "
                    f"of another table), or give --rate HZ" + _clock_beside(t, tables))


def _group_of(t: Table) -> str:
    """' (GROUP)' of a table that is one group of a file (an MDF4 channel group, a MATLAB struct), else ''."""
    return "" if t.name == t.path.stem else f" ({t.name})"


def _clock_beside(t: Table, tables) -> str:
    """'; F holds ...' for a table named as a time whose one column rises over as many rows as t's
    (or one more), the --time that takes it row by row; '' without one."""
    for c in tables:
        rising = time_like(c) if c is not t and str(c.name).lower() in TIME_NAMES else []
        if c.frame.shape[1] == 1 and rising and len(c.frame) in (len(t.frame), len(t.frame) + 1):
            return (f"; {c.path.name} holds one rising column over the same {len(t.frame)} rows: "
                    f"--time '{c.name}.{rising[0]}[s]' (its unit) takes it row by row for every table")
    return ""


# --- names ----------------------------------------------------------------------------------------
def catalog(tables: list[Table]) -> dict[str, tuple[Table, str]]:
    """Name -> (table, column) of every data column: TABLE.COLUMN, and COLUMN where one table has it."""
    names: dict[str, tuple[Table, str]] = {}
    owners: dict[str, list] = {}
    for t in tables:
        for c in t.frame.columns:
            if c in t.time_columns:
                continue
            names[f"{t.name}.{c}"] = (t, c)
            owners.setdefault(str(c), []).append((t, c))
    for c, where in owners.items():
        if len(where) == 1:
            names.setdefault(c, where[0])
    return names


def ambiguous(tables: list[Table], name: str) -> list[str]:
    return [f"{t.name}.{name}" for t in tables if name in t.frame.columns]


def table_series(tables: list[Table], name: str) -> Series | None:
    found = catalog(tables).get(name)
    if found is None:
        return None
    t, c = found
    if t.t is None:
        raise untimed(t, tuple(tables))
    x = pd.to_numeric(t.frame[c], errors="coerce").to_numpy(float)
    ok = np.isfinite(x)
    dtype = t.frame[c].dtype
    wrap = 2.0 ** (8 * dtype.itemsize) if dtype.kind in "iu" and dtype.itemsize <= 4 else None   # a binary file's width
    return Series(t.t[ok], x[ok], t.units.get(c), f"{t.name}.{c}", wrap)


def spans_overlap(tables: list[Table], used: set[str], source: Path) -> None:
    """A LogError naming each table's span when the tables that give columns share no time."""
    chosen = [t for t in tables if t.name in used and t.t is not None and len(t.t)]
    if len(chosen) < 2:
        return
    lo, hi = max(float(t.t[0]) for t in chosen), min(float(t.t[-1]) for t in chosen)
    if hi <= lo:
        boot = any(is_boot_clock(t.t) for t in chosen) and not all(is_boot_clock(t.t) for t in chosen)
        raise LogError(f"{source}: the tables' clocks do not overlap: "
                       + "; ".join(f"{t.path.name}{_group_of(t)} {iso(float(t.t[0]))} to {iso(float(t.t[-1]))} "
                                   f"({t.time_how})"
                                   for t in chosen)
                       + ("; one counts from its start, another from 1970: give them one clock" if boot else
                          "; expected tables of one recording, on one clock"))


def describe_table(t: Table) -> list[str]:
    """``--list`` lines: rows, time, each column's range and unit."""
    lines = [f"table {t.path.name} ({t.name}): {len(t.frame)} rows"
             + (", no header: columns named col1, col2 ..." if t.headerless else "")]
    if t.t is not None and len(t.t) > 1:
        dt = np.diff(t.t)
        lines.append(f"  time: {t.time_how}; {iso(float(t.t[0]))} + {t.t[-1] - t.t[0]:.3f} s, median step "
                     f"{float(np.median(dt)):.4g} s ({1 / float(np.median(dt)):.3g} Hz)")
    for c in t.frame.columns:
        if c in t.time_columns:
            continue
        col = t.frame[c]
        unit = f" [{t.units[c]}]" if c in t.units else ""
        if pd.api.types.is_numeric_dtype(col) and col.notna().any():
            x = col.to_numpy(float)
            lo, hi = np.nanpercentile(x, [0.5, 99.5]) if len(x) > 20 else (np.nanmin(x), np.nanmax(x))
            lines.append(f"  {t.name}.{c}{unit}: {np.nanmin(x):.6g} .. {np.nanmax(x):.6g} (99% within {lo:.4g} .. "
                         f"{hi:.4g})" + (" constant" if np.nanmin(x) == np.nanmax(x) else ""))
        else:
            lines.append(f"  {t.name}.{c}{unit}: text, e.g. {str(col.dropna().iloc[0])[:30]!r}"
                         if col.notna().any() else f"  {t.name}.{c}: empty")
    lines += [f"  note: {n}" for n in t.notes]
    return lines




# --- the recording's streams -------------------------------------------------------------------------
ALIASES = {"lat": ("lat", "latitude"), "lon": ("lon", "longitude", "lng", "long"),
           "fix_quality": ("fix_quality", "gps_quality", "gnss_quality", "fix_type", "quality")}


def fixes_as_given(streams: Streams, source: Path) -> Streams:
    """lat/lon signals as the receiver's fixes (measurements.quirks.fixes_from_columns) with the fix
    quality the source gives (its fix_quality signal, held at its own times), NaN where it gives
    none: a quality is never assumed."""
    given = streams.signals.pop("fix_quality", None) if "lat" in streams.signals else None
    before = streams.gnss
    streams = fixes_from_columns(streams, source)
    if streams.gnss is not None and streams.gnss is not before:
        utc = streams.gnss["utc"].to_numpy(float)
        streams.gnss["quality"] = held(utc, *given) if given is not None else np.nan
        if given is not None:
            streams.report.setdefault("columns", {})["fix_quality"] = "the source's fix quality, held at its own times"
    return streams


def mode_runs(table: Table) -> dict[str, list[tuple[str, float, float]]]:
    """{column: [(value, start, end POSIX s)]} of each column named as a mode or engagement
    channel (measurements.modes.MODE_NAMES) with few values: its stretches, as the rows give them
    (a blank cell holds the value in force)."""
    out = {}
    if table.t is None or len(table.t) < 2:
        return out
    for c in table.frame.columns:
        found = mode_codes(table.t, table.frame[c]) if is_mode_name(c) and c not in table.time_columns else None
        if found is None:
            continue
        t, codes, labels = found
        values = np.array([labels[int(x)] for x in codes] if labels else [f"{x:g}" for x in codes], dtype=object)
        cuts = np.flatnonzero(values[1:] != values[:-1]) + 1
        starts, ends = np.concatenate([[0], cuts]), np.concatenate([cuts, [len(values)]])
        last = [t[b] if b < len(t) else table.t[-1] for b in ends]     # in force until the next value said
        out[str(c)] = [(str(values[a]), float(t[a]), float(e)) for a, e in zip(starts, last)]
    return out


def mode_streams(tables: list[Table], mode_specs: list, used: set, source: Path, into) -> tuple[dict, dict]:
    """(column -> (t, codes), column -> labels) of the mode and engagement channels: each
    ``--signal`` naming one (a text column included), then every column so named in a table that
    gives columns (its name in lower case), held at their own times in the log; added to ``into``
    (the signals, their groups and the columns' descriptions)."""
    signals, labels, groups = {}, {}, {}
    used = used | {n.split(".")[0] for spec in mode_specs for n in spec.names}
    wanted = [(spec.column, spec.names[0]) for spec in mode_specs]
    wanted += [(str(c).lower(), f"{t.name}.{c}") for t in tables if t.name in used for c in t.frame.columns
               if is_mode_name(c) and c not in t.time_columns]
    names = catalog(tables)
    for column, name in wanted:
        found = names.get(name)
        if column in signals or found is None:
            if found is None and any(spec.column == column for spec in mode_specs):
                raise LogError(f"{source}: --signal {column}={name}: no such column (the tables' mode columns: "
                               + ", ".join(f"{t.name}.{c}" for t in tables for c in t.frame.columns if is_mode_name(c))
                               + ")")
            continue
        table, c = found
        codes = mode_codes(table.t, table.frame[c]) if table.t is not None else None
        if codes is None:
            continue
        signals[column], groups[column] = codes[:2], table.name
        if codes[2] is not None:
            labels[column] = codes[2]
    into[0].update(signals)
    into[1].update(groups)
    into[2].update({c: f"{groups[c]}: a mode channel, held at its own times" for c in signals})
    return signals, labels


def _holders(tables: list[Table], name: str) -> list[str]:
    """TABLE.COLUMN of every table with a column called ``name`` (any letter case)."""
    return [f"{t.name}.{c}" for t in tables for c in t.frame.columns
            if str(c).lower() == name and c not in t.time_columns]


def _receiver_specs(tables: list[Table], specs: list, given: set, auto: set) -> None:
    """With a user's mapping, the fix quality column beside the mapped lat (the receiver's own
    word); without one, a ``heading`` column (a dual-antenna or INS heading: the yaw angle,
    measurements.headings). Added to ``specs`` (and ``auto``) in place."""
    lat = next((spec for spec in specs if spec.column == "lat"), None)
    if given and lat is not None and "fix_quality" not in given:
        home = lat.names[0].split(".")[0]
        quality = [h for a in ALIASES["fix_quality"] for h in _holders(tables, a) if h.split(".")[0] == home]
        if quality:
            specs.append(SignalSpec("fix_quality", ((quality[0], 1.0),), 0.0, None, f"fix_quality={quality[0]}"))
    heading = _holders(tables, "heading") if not given else []
    if len(heading) == 1:
        specs.append(SignalSpec("heading", ((heading[0], 1.0),), 0.0, None, f"heading={heading[0]}"))
        auto.add("heading")


def yaw_axis(tables: list[Table], specs: list) -> list[dict]:
    """A yaw rate read from one axis of a table's gyro whose table holds an accelerometer per
    axis: the vertical axis by gravity checked against it (measurements.imu_axes; an
    accelerometer declared in g scaled by g); a mismatch's entry for report["imu_axes"] (the
    audit names it), else none."""
    spec = next((s for s in specs if s.column == "yaw_rate" and len(s.names) == 1), None)
    found = catalog(tables).get(spec.names[0]) if spec is not None else None
    if found is None:
        return []
    t, column = found
    siblings = axis_siblings(str(column), [str(c) for c in t.frame.columns if c not in t.time_columns])
    if siblings is None:
        return []
    axis, accel = siblings
    readings = {a: pd.to_numeric(t.frame[c], errors="coerce").to_numpy(float)
                * (GRAVITY if (t.units.get(c) or "").strip().lower() in ("g", "gn") else 1.0) for a, c in accel.items()}
    if any(np.isfinite(r).sum() < 20 for r in readings.values()):
        return []
    check = axis_check("yaw_rate", f"{t.name}.{column}", axis, {a: f"{t.name}.{c}" for a, c in accel.items()}, readings)
    return [check] if check is not None else []


def table_streams(paths: list[Path], options, source: Path):
    """Streams of the tables: the ``--signal`` expressions; without any, lat/lon columns, and in a
    table laid out as the log (a ``t`` column) the columns named as the log's (delta_cmd, delta,
    v, yaw_rate, x, y: SI, the log's convention, unless the header gives a unit)."""
    tables = read_tables(paths, options.time, options.rate, source,
                         tuple(n for s in options.signals for n in s.names))
    specs = [s for s in options.signals if not is_mode_name(s.column)]
    mode_specs = [s for s in options.signals if is_mode_name(s.column)]
    given = {s.column for s in specs}          # a mode channel's mapping leaves the others found by name
    notes = [f"{t.path.name}: {n}" for t in tables for n in t.notes]
    auto: set[str] = set()
    for column in tuple(CANONICAL[1:]) + ("lat", "lon", "fix_quality"):
        if given:                # the user's mapping is the whole of it: no column taken by its name
            break
        if column == "fix_quality" and "lat" not in auto:      # a quality of fixes the table holds
            break
        for alias in ALIASES.get(column, (column,)):
            # the log's own names only in a table laid out as a log (a 't' column, the names as
            # written): elsewhere 'V' or 'delta' may be a command, and a bare number has no unit
            hits = _holders(tables, alias) if column in ALIASES else \
                [f"{t.name}.{alias}" for t in tables if alias in t.frame.columns and "t" in t.time_columns]
            if len(hits) == 1:
                specs.append(SignalSpec(column, ((hits[0], 1.0),), 0.0, None, f"{column}={hits[0]}"))
                auto.add(column)
                break
            if len(hits) > 1:
                notes.append(f"{alias} is a column of several tables ({', '.join(hits)}): map one with "
                             f"--signal {column}=TABLE.{alias.split('.')[-1]}")
                break
    _receiver_specs(tables, specs, given, auto)
    if not specs:
        raise LogError(f"{source}: no column to take: name them with --signal COLUMN=TABLE.COLUMN[unit] (the log's "
                       f"columns: delta_cmd, delta, v, yaw_rate, x, y, or lat, lon); "
                       + "; ".join(f"{t.name}: {', '.join(map(str, t.frame.columns[:12]))}" for t in tables)
                       + " (convert SOURCE --list shows their ranges)")
    names, signals, columns, used, groups, sums = catalog(tables), {}, {}, set(), {}, {}
    for spec in specs:
        found = {}
        for name in spec.names:
            s = table_series(tables, name)
            if s is None:
                several = ambiguous(tables, name)
                if len(several) > 1:
                    raise LogError(f"{source}: --signal {spec}: column {name!r} is in several tables "
                                   f"({', '.join(several)}); name one as TABLE.COLUMN")
                raise unknown_name(str(source), spec, name, list(names), "column")
            if len(s.t) < 2:
                raise LogError(f"{source}: --signal {spec}: column {s.label} holds {len(s.t)} numbers")
            if spec.column in auto and s.unit is None and spec.unit is None:
                s.unit = target_unit(spec.column)
                s.label += " (no unit in the header: the log's convention)"
            found[name] = s
            used.add(s.label.split(".")[0])
        t, values, how = evaluate(spec, found, str(source), options.wheelbase or 1.4, sums)
        ok = np.isfinite(values)
        signals[spec.column] = (t[ok], values[ok])
        groups[spec.column] = names[spec.names[0]][0].name if spec.names[0] in names else spec.column
        columns[spec.column] = how + ("; found by its name" if spec.column in auto else "") + \
            ("; " + ", ".join(s.label for s in found.values() if "convention" in s.label) if spec.column in auto else "")
    modes, labels = mode_streams(tables, mode_specs, used, source, (signals, groups, columns))
    spans_overlap(tables, used, source)
    boot = [t.name for t in tables if t.name in used and t.t is not None and is_boot_clock(t.t)]
    report = {"source": str(source), "files": {"table": [str(t.path) for t in tables]}, "dbc": None, "notes": notes,
              "imu_axes": yaw_axis(tables, specs), "sums": sums,
              "time_base": [x for t in tables if t.name in used for x in t.time_base],
              "mode_columns": {f"{t.path.name} {c}": runs for t in tables if t.name in used for c, runs in mode_runs(t).items()},
              "tables": {t.name: {"rows": int(len(t.frame)), "time": t.time_how or "none", "used": t.name in used,
                                  "start": iso(float(t.t[0])) if t.t is not None and len(t.t) else None,
                                  "duration_s": float(t.t[-1] - t.t[0]) if t.t is not None and len(t.t) > 1 else 0.0}
                         for t in tables},
              "columns": {**columns, "t": "the tables' clock, s from the run's start"},
              "clocks": {"reference": _clock_reference([t for t in tables if t.name in used], boot)}}
    streams = fixes_as_given(Streams(None, signals, report, {c for c in ("delta_cmd", "speed_cmd") if c in signals}
                                     | set(modes), {}, groups=groups, labels=labels,
                                     clocks={t.name: t.clock for t in tables if t.clock}), source)
    if "heading" in streams.signals:
        spec = next(s for s in specs if s.column == "heading")
        as_yaw(streams, declared=spec.unit is not None or "heading" not in auto or
               "no unit in the header" not in columns.get("heading", ""))
    return streams


def _clock_reference(used: list[Table], boot: list[str]) -> str:
    """What the used tables' times are: their own time columns, or another table's taken row by row
    (--time TABLE.COLUMN)."""
    lent = {t.name: t.clock for t in used if t.clock}
    parts = ["the tables' own time columns"] if len(lent) < len(used) or not used else []
    parts += [f"row by row from {c} (--time) for {', '.join(n for n, k in lent.items() if k == c)}"
              for c in sorted(set(lent.values()))]
    return "; ".join(parts) + (f" ({', '.join(boot)}: seconds from the logger's start, not dates)" if boot else "")


def list_tables(paths: list[Path], options) -> list[str]:
    """``--list``: each table's columns with their ranges and the time found, joined as the
    converter joins them; where they cannot be, each alone, saying why."""
    try:
        tables = read_tables(paths, options.time, options.rate, paths[0].parent,
                             tuple(n for s in options.signals for n in s.names))
    except LogError as exc:                   # each table alone, saying why the set has no clock
        out = [f"tables: {exc}"]
        for p in paths:
            try:
                out += [line for t in _tables_of(p) for line in describe_table(t)]
            except LogError as why:
                out.append(f"table {p.name}: not read: {why}")
        return out
    return [line for t in tables for line in describe_table(t)]


class TableReader(Reader):
    """Other tools' tables: by their suffix, MDF4 files of signals, and text files of columns."""

    kind, name, listed = "table", "tables", "table columns with ranges"
    files = ("*.csv, *.tsv, *.parquet, *.pq, MDF4 signals *.mf4/*.mdf, a .txt/.dat/.log of columns: a folder of "
             "them is joined on time")
    suffixes = TABLE_SUFFIXES + MDF_SUFFIXES + TEXT_SUFFIXES
    raw = False

    def claims(self, path: Path) -> bool:
        return super().claims(path) and (path.suffix.lower() not in TEXT_SUFFIXES or looks_like_table(path))

    def streams(self, files: dict[str, list[Path]], options, source: Path):
        return table_streams(files[self.kind], options, source)

    def listing(self, paths: list[Path], options, source: Path) -> list[str]:
        return list_tables(paths, options)


class NumpyChannelReader(TableReader):
    """Folders of numpy channels (``t`` and ``value`` arrays per signal), read as tables."""

    kind, name, listed = "numpy", "numpy channel folders", "numpy channels with ranges"
    files = "a folder per signal holding its t and value arrays (numpy.save, .npy optional)"
    suffixes = ()

    def claims(self, path: Path) -> bool:
        return path.is_dir() and bool(channel_folders(path))

    def streams(self, files: dict[str, list[Path]], options, source: Path):
        streams = table_streams(files[self.kind], options, source)
        streams.report["files"] = {self.kind: streams.report["files"].pop("table")}
        return streams


READER = TableReader()
NUMPY_READER = NumpyChannelReader()
