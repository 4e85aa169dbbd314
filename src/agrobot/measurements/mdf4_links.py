"""The link structure of an ASAM MDF 4 file checked before a reader follows it.

Every MDF 4 block after the 64-byte identification starts with a header: ``##XX`` (its id),
4 reserved bytes, its length (uint64) and its number of links (uint64), then that many links
(uint64 file offsets, 0 for none). The blocks and their links form a graph rooted at the header
block (offset 64) that the standard requires to be free of loops: a ``next`` link pointing back
makes a reader walk forever. The walk here (depth first, each block once) refuses in bounded time
and memory, naming the offset:

- a link outside the file or into the identification block;
- a block whose id does not start with ``##``, whose length is below its header and links, or
  which runs past the end of the file;
- a link back to a block on the current path (a loop);
- more than ``MAX_BLOCKS`` blocks (a file built to exhaust memory);
- a channel (CN) whose bytes lie outside its group's record (CG: data plus invalidation bytes),
  or whose data type is not one the standard defines: a reader would read past its record.
"""
from __future__ import annotations

import mmap
import struct
from pathlib import Path

from .log import LogError

HEAD = struct.Struct("<4s4xQQ")       # id, reserved, length, link count
FIRST = 64                            # the header block (HD) follows the identification block
MAX_BLOCKS = 5_000_000
MAX_LINKS = 1 << 24


def check_links(path: Path) -> None:
    """LogError naming the file and the offset when the MDF 4 file's blocks do not form a finite,
    loop-free graph inside the file (see the module docstring); an MDF 3 file is not walked."""
    with open(path, "rb") as f:
        if f.read(16)[8:9] != b"4":
            return
        with mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as data:
            _walk(path, data)


def _block_links(path: Path, data, at: int) -> list[int]:
    """The links of the block at ``at``, after its header is checked."""
    size = len(data)
    if at + HEAD.size > size:
        raise LogError(f"{path}: a damaged MDF file: a link points to offset {at}, past the file's end ({size} bytes)")
    ident, length, count = HEAD.unpack_from(data, at)
    name = ident.decode("latin-1")
    if not ident.startswith(b"##"):
        raise LogError(f"{path}: a damaged MDF file: the block at offset {at} has id {ident!r}, not '##..'")
    if count > MAX_LINKS or length < HEAD.size + 8 * count or at + length > size:
        raise LogError(f"{path}: a damaged MDF file: the block {name} at offset {at} declares {length} bytes and "
                       f"{count} links (the file has {size} bytes): an impossible block size")
    links = struct.unpack_from(f"<{count}Q", data, at + HEAD.size)
    for link in links:
        if link and (link < FIRST or link >= size):
            raise LogError(f"{path}: a damaged MDF file: the block {name} at offset {at} links to offset {link}, "
                           f"outside the file's blocks (64 to {size} bytes)")
    return [link for link in links if link]


CG_RECORD = struct.Struct("<QQHH4xII")       # record id, cycles, flags, path separator, data bytes, invalidation bytes
CN_LAYOUT = struct.Struct("<BBBBIII")        # type, sync, data type, bit offset, byte offset, bit count, flags
VIRTUAL = (3, 6)                             # virtual master and virtual data channels: no bytes in the record
DATA_TYPES = 16                              # data types 0..15 (MDF 4.1: 0..15; 4.2 adds complex, up to 16)


def _check_channels(path: Path, data, cg: int) -> None:
    """Every channel of the group at ``cg`` inside the group's record."""
    count = HEAD.unpack_from(data, cg)[2]
    if len(data) < cg + HEAD.size + 8 * count + CG_RECORD.size:
        raise LogError(f"{path}: a damaged MDF file: the channel group at offset {cg} is cut short")
    _, _, _, _, size, invalid = CG_RECORD.unpack_from(data, cg + HEAD.size + 8 * count)
    raw = struct.unpack_from(f"<{count}Q", data, cg + HEAD.size)
    cn, seen = raw[1] if count > 1 else 0, set()
    while cn and cn not in seen and len(seen) < MAX_BLOCKS:
        seen.add(cn)
        _block_links(path, data, cn)
        n = HEAD.unpack_from(data, cn)[2]
        if len(data) < cn + HEAD.size + 8 * n + CN_LAYOUT.size:
            raise LogError(f"{path}: a damaged MDF file: the channel at offset {cn} is cut short")
        kind, _, dtype, bit, byte, bits, _ = CN_LAYOUT.unpack_from(data, cn + HEAD.size + 8 * n)
        if dtype > DATA_TYPES or (kind not in VIRTUAL and byte + (bit + bits + 7) // 8 > size + invalid):
            raise LogError(f"{path}: a damaged MDF file: the channel at offset {cn} (data type {dtype}, bytes "
                           f"{byte} to {byte + (bit + bits + 7) // 8}) lies outside its group's record of "
                           f"{size + invalid} bytes (group at offset {cg})")
        cn = struct.unpack_from("<Q", data, cn + HEAD.size)[0] if n else 0      # cn_cn_next


def _walk(path: Path, data) -> None:
    """Depth-first walk from the header block: each block once, a link back onto the path refused."""
    state: dict[int, bool] = {FIRST: True}          # offset -> on the current path
    stack = [(FIRST, iter(_block_links(path, data, FIRST)))]
    while stack:
        at, links = stack[-1]
        link = next(links, None)
        if link is None:
            state[at] = False
            stack.pop()
            continue
        if state.get(link):
            name = bytes(data[at:at + 4]).decode("latin-1")
            raise LogError(f"{path}: a damaged MDF file: the block {name} at offset {at} links back to offset {link}, "
                           f"a loop (a reader would follow it forever)")
        if link in state:
            continue
        if len(state) >= MAX_BLOCKS:
            raise LogError(f"{path}: a damaged MDF file: more than {MAX_BLOCKS} blocks")
        state[link] = True
        links_of = _block_links(path, data, link)
        if data[link:link + 4] == b"##CG":
            _check_channels(path, data, link)
        stack.append((link, iter(links_of)))
