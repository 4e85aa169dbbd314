"""The recording formats in their order of precedence: the one list that the converter
(measurements.recording), the listing (measurements.listing) and the ``convert`` help read.

A reader (streams.Reader) names its kind, its suffixes and how the help names it; it claims a
file or a folder, turns the recording's files into Streams and lists what they hold. The order
of READERS decides twice:

- a file goes to the first reader that claims it (a .log of NMEA sentences is NMEA before it is a
  candump, an MDF4 file of bus logging is CAN before it is a table);
- of the kinds a recording holds, the first reader's makes the recording: a ROS bag, else an
  ISO 11783-10 TaskData, else NMEA and CAN logs (read together), else folders of numpy channels, else
  MATLAB .mat files, else tables.

A new format is one module with its reader, listed here once (or added with ``register``).
"""
from __future__ import annotations

from pathlib import Path

from . import isoxml_log, matlab, nmea_can, rosbag, tables
from .streams import Reader

READERS: list[Reader] = [rosbag.READER, isoxml_log.READER, nmea_can.NMEA, nmea_can.CAN, tables.NUMPY_READER,
                         matlab.READER, tables.READER]


def register(reader: Reader, before: str | None = None) -> Reader:
    """Add ``reader`` ahead of the reader of kind ``before`` (None: after every other); a kind is
    registered once."""
    kinds = [r.kind for r in READERS]
    if reader.kind in kinds:
        raise ValueError(f"a reader of kind {reader.kind!r} is registered already")
    if before is not None and before not in kinds:
        raise ValueError(f"no reader of kind {before!r}: one of {', '.join(kinds)}")
    READERS.insert(kinds.index(before) if before is not None else len(READERS), reader)
    return reader


def kinds() -> tuple[str, ...]:
    """Every reader's kind, in the order of precedence."""
    return tuple(r.kind for r in READERS)


def claimant(path: Path) -> Reader | None:
    """The first reader that claims ``path``, or None."""
    return next((r for r in READERS if r.claims(path)), None)


def first_held(files: dict[str, list[Path]]) -> Reader | None:
    """The first reader whose kind has files: the one that makes the recording."""
    return next((r for r in READERS if files.get(r.kind)), None)


def raw_suffixes() -> frozenset[str]:
    """The suffixes of a file that is a raw recording (a table's alone are a log as it is)."""
    return frozenset(s for r in READERS if r.raw for s in r.suffixes)


def names() -> str:
    """The formats as a help names them in passing: 'ROS bags, ..., tables'."""
    return ", ".join(r.name for r in READERS)


def described(last: str = ", ") -> str:
    """Every format with its files ('ROS bags (*.bag, ...), ...'), ``last`` before the last one."""
    parts = [f"{r.name} ({r.files})" for r in READERS]
    return last.join([", ".join(parts[:-1]), parts[-1]]) if len(parts) > 1 else "".join(parts)


def listed() -> str:
    """What ``convert --list`` shows, format by format."""
    return "; ".join(r.listed for r in READERS)


def no_recording(source: Path) -> str:
    """The refusal of a source that holds no file of any format."""
    return f"{source}: no recording in it: expected {described(' or ')}"
