"""``convert SOURCE --list``: what a recording holds, so that a user can choose its signals: each
format's reader lists its files (measurements.recording_readers, in their order): ROS topics with their
types and numeric fields, ISO 11783-10 time logs with their DDIs, NMEA sentences and fixes, CAN
messages and signals (units, declared ranges, the values seen, rates, buses) with the DBC's load
report, table columns with their ranges and the time found."""
from __future__ import annotations

from pathlib import Path

from . import recording_readers as readers
from .log import LogError
from .recording import recording_files


def list_source(source: Path, options) -> list[str]:
    """The lines of every format the source holds, format by format in the readers' order."""
    source = Path(source)
    files = recording_files(source)
    lines = [line for r in readers.READERS if files.get(r.kind) for line in r.listing(files[r.kind], options, source)]
    if not lines:
        raise LogError(readers.no_recording(source))
    return lines
