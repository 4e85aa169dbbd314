"""A bus log a logger left unfinalized (its identification 'UnFinMF ', the unfinalized flags set,
as CANedge loggers write them): read as the same frames as the finalized file, not refused as
'not an MDF file'."""
from __future__ import annotations

import struct

import numpy as np
import pytest

from agrobot.measurements.recording import import_recording
from harness.generated_recordings import write_candump

pytest.importorskip("asammdf")
UPDATE_CYCLE_COUNTERS = 1    # the unfinalized flags (ASAM MDF 4.1 ID block): bit 0, the cycle counters
UPDATE_LAST_DT_LENGTH = 4    # bit 2, the last data block's length (with bit 0 and bit 5 a CANedge's 37)


def _unfinished(tmp_path, flags: int):
    import can

    candump = write_candump(tmp_path / "bus.log", seconds=30.0)
    writer = can.MF4Writer(str(tmp_path / "bus.mf4"))
    for message in can.CanutilsLogReader(str(candump)):
        writer.on_message_received(message)
    writer.stop()
    raw = bytearray((tmp_path / "bus.mf4").read_bytes())
    raw[:8] = b"UnFinMF "
    raw[60:64] = struct.pack("<HH", flags, 0)
    (tmp_path / "unfinished.mf4").write_bytes(bytes(raw))


def test_an_unfinalized_mdf4_bus_log_reads_as_its_finalized_twin(tmp_path):
    _unfinished(tmp_path, UPDATE_CYCLE_COUNTERS)
    finished, unfinished = import_recording(tmp_path / "bus.mf4")[0], import_recording(tmp_path / "unfinished.mf4")[0]
    assert len(unfinished) == len(finished) > 500
    for column in finished.columns:
        np.testing.assert_allclose(unfinished[column], finished[column], rtol=0, atol=1e-9)
    # the candump's truth (harness.generated_recordings.candump_lines): 2 m/s
    assert np.max(np.abs(unfinished["v"] - 2.0)) < 1e-9


def test_an_unfinalized_file_asammdf_cannot_finalize_is_named_without_a_traceback(tmp_path, capsys):
    from agrobot.measurements.log import LogError

    _unfinished(tmp_path, UPDATE_CYCLE_COUNTERS | UPDATE_LAST_DT_LENGTH | 32)
    try:
        import_recording(tmp_path / "unfinished.mf4")
    except LogError as exc:
        assert "unfinalized MDF file" in str(exc) and "finalize it" in str(exc)
    out = capsys.readouterr()
    assert "Traceback" not in out.out + out.err
