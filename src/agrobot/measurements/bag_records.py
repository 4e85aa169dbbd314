"""The record structure of a ROS 1 bag and of an MCAP file checked before a reader follows it.

Both formats are a sequence of length-prefixed records; a reader trusts each declared length and
reads that many bytes at once, so one damaged length asks for terabytes (a memory blow-up) and a
damaged offset sends it outside the file. The walk here reads only the record headers, once each
and forwards (bounded time: at most one record per 9 bytes of file), and refuses, naming the file,
the offset and the field:

- ROS 1 (``#ROSBAG V2.0``; records ``header_len`` u32, header fields ``len`` u32 + ``name=value``,
  ``data_len`` u32, data): a length past the file's end, a header field past its header, a record
  without ``op``; the bag header's ``index_pos`` (0 in a bag whose recording was cut: left to the
  reader, which says so) and a chunk info's ``chunk_pos`` off a record start; a chunk's declared uncompressed ``size`` above MAX_CHUNK, or unlike its data when stored
  uncompressed.
- MCAP (magic ``\\x89MCAP0\\r\\n``; records opcode u8, length u64, content; a footer and the magic
  at the end): a length past the file's end, a missing footer or end magic, a footer's summary
  offsets outside the file, a chunk whose compression name or records run past its record, whose
  declared uncompressed size is above MAX_CHUNK or unlike its records when stored uncompressed, a
  chunk index pointing outside the file.

- ROS 2 ``.db3`` (SQLite, magic ``SQLite format 3\\0``; pages of a size the header gives): a file
  shorter than its header, without the magic, with a page size that is no power of two from 512 to
  65536, cut inside a page or shorter than the pages its header declares; then SQLite's own check of
  every page and index (``PRAGMA integrity_check``, the file opened read-only and immutable) on a
  file of at most INTEGRITY_CHECK_BYTES, above which a damaged page is named by the message being
  read when it is met; the tables a rosbag2 bag holds (``topics``, ``messages``) with their columns,
  the text of its small tables (topics, type definitions, metadata) in UTF-8, and each ``ros2msg``
  type definition holding a ``MSG:`` section for every message type its fields use.
"""
from __future__ import annotations

import re
import sqlite3
import struct
from contextlib import closing
from pathlib import Path

from .log import LogError

ROS1_MAGIC = b"#ROSBAG V2.0\n"
MCAP_MAGIC = b"\x89MCAP0\r\n"
SQLITE_MAGIC = b"SQLite format 3\x00"
INTEGRITY_CHECK_BYTES = 1 << 30     # a larger .db3 is checked page by page as its messages are read
MAX_CHUNK = 1 << 30            # a chunk's uncompressed bytes: a reader holds one whole chunk in memory
U32, U64 = struct.Struct("<I"), struct.Struct("<Q")


def check_bag_file(path: Path) -> None:
    """LogError naming the file, the offset and the field when the ROS 1 bag, MCAP file or ROS 2
    ``.db3`` at ``path`` declares a record, chunk, page or offset its bytes cannot hold; other files
    pass."""
    with open(path, "rb") as f:
        head = f.read(len(SQLITE_MAGIC))
        if head.startswith(MCAP_MAGIC):
            _walk_mcap(path, f)
        elif head.startswith(ROS1_MAGIC):
            _walk_ros1(path, f)
        elif head == SQLITE_MAGIC or Path(path).suffix.lower() == ".db3":
            _walk_sqlite(path, f)


def _fail(path: Path, kind: str, at: int | None, what: str) -> LogError:
    """``what`` is wrong with the file at byte offset ``at`` (None: the file as a whole)."""
    return LogError(f"{path}: cannot read as a {kind}, it is damaged: {what}" + ("" if at is None else
                                                                                f" (at byte offset {at})"))


def _read(f, at: int, n: int, size: int, path: Path, kind: str, what: str) -> bytes:
    """``n`` bytes at ``at``, refused when the file ends before them."""
    if at + n > size:
        raise _fail(path, kind, at, f"{what} needs {n} bytes, the file has {max(size - at, 0)} left ({size} bytes)")
    f.seek(at)
    return f.read(n)


def _ros1_fields(path: Path, header: bytes, at: int) -> dict[str, bytes]:
    """The header fields of the record at ``at`` (its header follows a 4-byte length)."""
    fields, i = {}, 0
    while i < len(header):
        if i + 4 > len(header):
            raise _fail(path, "ROS bag", at + 4 + i, "a header field's length is cut off")
        n = U32.unpack_from(header, i)[0]
        if n > len(header) - i - 4:
            raise _fail(path, "ROS bag", at + 4 + i, f"a header field declares {n} bytes, its header has {len(header) - i - 4} left")
        name, eq, value = header[i + 4:i + 4 + n].partition(b"=")
        if not eq:
            raise _fail(path, "ROS bag", at + 4 + i, "a header field without '='")
        fields[name.decode("latin-1")] = value
        i += 4 + n
    if len(fields.get("op", b"")) != 1:
        raise _fail(path, "ROS bag", at, "a record header without its one-byte 'op' field")
    return fields


def _number(path: Path, fields: dict, name: str, at: int, width: struct.Struct = U64) -> int:
    value = fields.get(name, b"")
    if len(value) != width.size:
        raise _fail(path, "ROS bag", at, f"field '{name}' has {len(value)} bytes, not {width.size}")
    return width.unpack(value)[0]



def _walk_ros1(path: Path, f) -> None:
    """Every top-level record of a ROS 1 bag inside the file; the offsets its index gives on a record."""
    size = f.seek(0, 2)
    at, starts, pointed = len(ROS1_MAGIC), set(), []
    while at < size:
        starts.add(at)
        n = U32.unpack(_read(f, at, 4, size, path, "ROS bag", "a record's header length"))[0]
        if at + 8 + n > size:
            raise _fail(path, "ROS bag", at, f"a record's field 'header_len' declares {n} bytes, the file has "
                                             f"{size - at - 8} left ({size} bytes)")
        fields = _ros1_fields(path, _read(f, at + 4, n, size, path, "ROS bag", "a record header"), at)
        data_at = at + 4 + n
        data_len = U32.unpack(_read(f, data_at, 4, size, path, "ROS bag", "a record's data length"))[0]
        if data_at + 4 + data_len > size:
            raise _fail(path, "ROS bag", at, f"a record's field 'data_len' declares {data_len} bytes, the file has "
                                             f"{size - data_at - 4} left ({size} bytes)")
        op = fields["op"][0]
        if op == 0x03:
            pointed.append(("index_pos", _number(path, fields, "index_pos", at), at))
        elif op == 0x06:
            pointed.append(("chunk_pos", _number(path, fields, "chunk_pos", at), at))
        elif op == 0x05:
            declared = _number(path, fields, "size", at, U32)
            if declared > MAX_CHUNK or (fields.get("compression") == b"none" and declared != data_len):
                raise _fail(path, "ROS bag", at, f"a chunk declares {declared} uncompressed bytes for "
                                                 f"{data_len} stored ({fields.get('compression', b'?').decode('latin-1')})"
                                                 f": an impossible chunk size (at most {MAX_CHUNK})")
        at = data_at + 4 + data_len
    for name, offset, where in pointed:
        if offset not in starts and not (name == "index_pos" and offset in (0, size)):   # 0: never indexed
            raise _fail(path, "ROS bag", where, f"field '{name}' points to offset {offset}, not a record's start "
                                                f"(the file has {size} bytes)")


MCAP_FOOTER, MCAP_CHUNK, MCAP_CHUNK_INDEX = 0x02, 0x06, 0x08


def _walk_mcap(path: Path, f) -> None:
    """Every record of an MCAP file inside the file, ended by a footer and the magic."""
    size = f.seek(0, 2)
    end = size - len(MCAP_MAGIC)
    if _read(f, end, len(MCAP_MAGIC), size, path, "MCAP file", "the end magic") != MCAP_MAGIC:
        raise _fail(path, "MCAP file", end, "the file does not end with the MCAP magic (cut short?)")
    at, footer, starts = len(MCAP_MAGIC), False, set()
    while at < end and not footer:
        starts.add(at)
        opcode, length = struct.unpack("<BQ", _read(f, at, 9, end, path, "MCAP file", "a record's opcode and length"))
        if length > end - at - 9:
            raise _fail(path, "MCAP file", at, f"record opcode 0x{opcode:02x} declares {length} bytes, the file has "
                                               f"{end - at - 9} left before its end magic")
        if opcode in (MCAP_FOOTER, MCAP_CHUNK, MCAP_CHUNK_INDEX):
            _mcap_record(path, opcode, _read(f, at + 9, length, end, path, "MCAP file", "a record"), at, starts, size)
        footer = opcode == MCAP_FOOTER
        at += 9 + length
    if not footer:
        raise _fail(path, "MCAP file", at, "no footer record before the end magic")


def _mcap_record(path: Path, opcode: int, body: bytes, at: int, starts: set[int], size: int) -> None:
    """The sizes and offsets a footer, chunk or chunk index declares, against its record and the
    records before it (``starts``: their offsets; a footer is the last record)."""
    kind = "MCAP file"
    try:
        if opcode == MCAP_FOOTER:
            for name, offset in zip(("summary_start", "summary_offset_start"), struct.unpack_from("<QQ", body)):
                if offset and offset not in starts:
                    raise _fail(path, kind, at, f"the footer's {name} {offset} is not a record's start "
                                                f"(the file has {size} bytes)")
        elif opcode == MCAP_CHUNK:
            declared = U64.unpack_from(body, 16)[0]
            n = U32.unpack_from(body, 28)[0]
            compression = body[32:32 + n]
            if 32 + n + 8 > len(body):
                raise _fail(path, kind, at, f"a chunk's compression name declares {n} bytes, its record has "
                                            f"{len(body) - 32} left")
            stored = U64.unpack_from(body, 32 + n)[0]
            if stored != len(body) - 40 - n or declared > MAX_CHUNK or (not compression and declared != stored):
                raise _fail(path, kind, at, f"a chunk declares {declared} uncompressed bytes and {stored} stored "
                                            f"in a record of {len(body)} ({compression.decode('latin-1') or 'none'})"
                                            f": an impossible chunk size (at most {MAX_CHUNK})")
        else:
            _mcap_chunk_index(path, body, at, size)
    except struct.error:
        raise _fail(path, kind, at, f"record opcode 0x{opcode:02x} of {len(body)} bytes is too short for its "
                                    f"fields") from None


def _mcap_chunk_index(path: Path, body: bytes, at: int, size: int) -> None:
    """A chunk index's chunk inside the file, its sizes within that chunk and MAX_CHUNK."""
    start, length = struct.unpack_from("<QQ", body, 16)
    if start + length > size:
        raise _fail(path, "MCAP file", at, f"a chunk index points to bytes {start} to {start + length}, outside the "
                                           f"file ({size} bytes)")
    i = 32 + 4 + U32.unpack_from(body, 32)[0] + 8               # past the message index offsets and their length
    n = U32.unpack_from(body, i)[0]
    stored, declared = struct.unpack_from("<QQ", body, i + 4 + n)
    if stored > length or declared > MAX_CHUNK:
        raise _fail(path, "MCAP file", at, f"a chunk index declares {stored} stored and {declared} uncompressed bytes "
                                           f"for a chunk of {length}: an impossible chunk size (at most {MAX_CHUNK})")


U16BE, U32BE = struct.Struct(">H"), struct.Struct(">I")
BAG_TABLES = {"topics": {"id", "name", "type", "serialization_format"}, "messages": {"id", "topic_id", "timestamp", "data"}}


def _walk_sqlite(path: Path, f) -> None:
    """A ROS 2 .db3: its header against the file's size, SQLite's check of its pages, its tables."""
    kind, size = "ROS 2 bag (SQLite)", f.seek(0, 2)
    header = _read(f, 0, 100, size, path, kind, "the SQLite header")
    if not header.startswith(SQLITE_MAGIC):
        raise _fail(path, kind, 0, "the file does not start with the SQLite magic 'SQLite format 3'")
    page = U16BE.unpack_from(header, 16)[0]
    page = 65536 if page == 1 else page
    if page < 512 or page & (page - 1):
        raise _fail(path, kind, 16, f"the header's page size {page} is no power of two from 512 to 65536")
    if size % page:
        raise _fail(path, kind, size - size % page, f"the file ends {size % page} bytes into a page of {page} "
                                                    f"bytes (cut short?)")
    pages = U32BE.unpack_from(header, 28)[0]
    if header[24:28] == header[92:96] and pages * page > size:       # the count is valid for this change
        raise _fail(path, kind, 28, f"the header declares {pages} pages of {page} bytes ({pages * page} bytes), "
                                    f"the file has {size} (cut short?)")
    try:
        with closing(sqlite3.connect(f"{Path(path).absolute().as_uri()}?mode=ro&immutable=1", uri=True)) as db:
            if size <= INTEGRITY_CHECK_BYTES:
                found = [row[0] for row in db.execute("PRAGMA integrity_check(3)")]
                if found != ["ok"]:
                    raise _fail(path, kind, None, f"SQLite's check of its pages finds {'; '.join(map(str, found))}")
            columns = {t: {row[1] for row in db.execute(f"PRAGMA table_info({t})")} for t in BAG_TABLES}
            for table, wanted in BAG_TABLES.items():
                if not wanted <= columns[table]:
                    raise _fail(path, kind, None, f"no table '{table}' with columns {', '.join(sorted(wanted))} (a "
                                               f"rosbag2 bag's); it has {', '.join(sorted(columns[table])) or 'none'}")
            _utf8_text(path, kind, db)
            _definitions_whole(path, kind, db)
    except sqlite3.DatabaseError as exc:
        raise _fail(path, kind, None, f"SQLite's check of its pages cannot read them: {exc}") from None


def _utf8_text(path: Path, kind: str, db) -> None:
    """Every text of the bag's small tables (all but ``messages``) in UTF-8."""
    db.text_factory = bytes
    tables = [row[0] for row in db.execute("SELECT name FROM sqlite_master WHERE type = 'table'")]
    for table in (t for t in tables if t != b"messages"):
        name = table.decode("utf-8", "replace")
        for row in db.execute(f'SELECT rowid, * FROM "{name}"'):
            for value in row[1:]:
                try:
                    value.decode("utf-8") if isinstance(value, bytes) else None
                except UnicodeDecodeError as exc:
                    raise _fail(path, kind, None, f"table '{name}' row {row[0]}: a text that is not UTF-8 ({exc.reason} "
                                               f"at its byte {exc.start})") from None


SECTION = re.compile(rb"^=+\s*$", re.M)


def _message_type(name: bytes) -> bytes:
    """``pkg/msg/Type`` or ``pkg/Type`` as ``pkg/Type``, without an array or bound suffix."""
    parts = re.sub(rb"(\[.*\]|<=\d+)$", b"", name).split(b"/")
    return parts[0] + b"/" + parts[-1]


def _definitions_whole(path: Path, kind: str, db) -> None:
    """Every ``ros2msg`` definition (table ``message_definitions``) defines, in a ``MSG: pkg/Type`` section,
    each message type its fields use (a damaged section name leaves a field's type undefined)."""
    if not list(db.execute("SELECT name FROM sqlite_master WHERE name = 'message_definitions'")):
        return                                                     # an older rosbag2 bag: none stored
    db.text_factory = bytes
    rows = db.execute("SELECT rowid, topic_type, encoding, encoded_message_definition FROM message_definitions")
    for row, topic_type, encoding, text in rows:
        if encoding != b"ros2msg" or not text:
            continue
        sections = SECTION.split(text)
        defined = {_message_type(topic_type)} | {_message_type(s.strip().splitlines()[0][4:].strip())
                                                 for s in sections[1:] if s.strip().startswith(b"MSG:")}
        for line in (x.split(b"#")[0].split() for s in sections for x in s.splitlines()):
            if len(line) >= 2 and b"/" in line[0] and b"=" not in line[1] and _message_type(line[0]) not in defined:
                raise _fail(path, kind, None, f"table 'message_definitions' row {row} ({topic_type.decode()}): the "
                                              f"field type {line[0].decode()} has no MSG: section (a damaged "
                                              f"definition)")
