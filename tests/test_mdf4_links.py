"""MDF 4 files whose block links loop, leave the file or declare impossible sizes are refused in
bounded time with the file and the offset named; random damage never hangs the reader (a fuzz
test: every damaged copy is read or refused with a LogError within its time)."""
from __future__ import annotations

import struct
import time
from pathlib import Path

import numpy as np
import pytest

from agrobot.measurements.log import LogError
from agrobot.measurements.mdf4 import mdf_tables

asammdf = pytest.importorskip("asammdf")


@pytest.fixture(scope="module")
def mf4(tmp_path_factory) -> Path:
    return two_groups(tmp_path_factory.mktemp("links") / "drive.mf4")


def two_groups(path: Path) -> Path:
    """An MDF 4.10 file of two data groups (IMU: YawRate, Vehicle: Speed), 5 s at 100 Hz."""
    from asammdf import MDF, Signal

    t = np.arange(0.0, 5.0, 0.01)
    mdf = MDF(version="4.10")
    mdf.append([Signal(np.sin(t), t, name="YawRate", unit="rad/s")], acq_name="IMU")
    mdf.append([Signal(np.cos(t), t, name="Speed", unit="m/s")], acq_name="Vehicle")
    mdf.save(path, overwrite=True)
    mdf.close()
    return path


def _blocks(raw: bytes, ident: bytes) -> list[int]:
    """Offsets of the blocks with ``ident`` (found by scanning for their headers, not through the reader)."""
    found, at = [], raw.find(ident)
    while at >= 0:
        found.append(at)
        at = raw.find(ident, at + 1)
    return found


def _damaged(mf4: Path, tmp_path: Path, edit) -> Path:
    raw = bytearray(mf4.read_bytes())
    edit(raw)
    out = tmp_path / "damaged.mf4"
    out.write_bytes(bytes(raw))
    return out


def test_a_data_group_whose_next_link_points_back_is_a_loop_named_at_its_offset(mf4, tmp_path):
    raw = mf4.read_bytes()
    first, second = _blocks(raw, b"##DG")[:2]

    def loop(b):                      # the second group's "next" (its first link) -> the first group
        b[second + 24:second + 32] = struct.pack("<Q", first)
    began = time.perf_counter()
    with pytest.raises(LogError, match=rf"damaged MDF file: the block ##DG at offset {second} links back to offset "
                                       rf"{first}, a loop"):
        mdf_tables(_damaged(mf4, tmp_path, loop))
    assert time.perf_counter() - began < 5


def test_impossible_block_sizes_and_links_outside_the_file_are_named(mf4, tmp_path):
    raw = mf4.read_bytes()
    cn = _blocks(raw, b"##CN")[0]

    def huge(b):
        b[cn + 8:cn + 16] = struct.pack("<Q", 1 << 40)
    with pytest.raises(LogError, match=rf"block ##CN at offset {cn} declares {1 << 40} bytes .* impossible block size"):
        mdf_tables(_damaged(mf4, tmp_path, huge))

    def outside(b):
        b[cn + 24:cn + 32] = struct.pack("<Q", len(raw) + 1000)
    with pytest.raises(LogError, match=rf"block ##CN at offset {cn} links to offset {len(raw) + 1000}, outside"):
        mdf_tables(_damaged(mf4, tmp_path, outside))


def test_random_damage_is_read_or_refused_never_hung(mf4, tmp_path):
    rng = np.random.default_rng(58)
    raw = mf4.read_bytes()
    outcomes = {"read": 0, "refused": 0}
    for trial in range(40):
        b = bytearray(raw)
        for at in rng.integers(64, len(raw), size=int(rng.integers(1, 6))):
            b[int(at)] = int(rng.integers(0, 256))
        path = tmp_path / f"fuzz{trial}.mf4"
        path.write_bytes(bytes(b))
        began = time.perf_counter()
        try:
            mdf_tables(path)
            outcomes["read"] += 1
        except LogError:
            outcomes["refused"] += 1
        assert time.perf_counter() - began < 10, trial
    assert outcomes["read"] + outcomes["refused"] == 40
