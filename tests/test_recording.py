"""The emulator records its buses as a field log: ``emulate --record DIR`` writes the receiver's
NMEA with the host's UNIX time before each sentence (gps.nmea) and every CAN frame sent or
received as a candump log (can.log), which python-can reads back and the project's DBC decodes."""
from __future__ import annotations

from pathlib import Path

import pytest
from tests.commands import cli


@pytest.fixture(scope="module")
def recording(tmp_path_factory) -> Path:
    where = tmp_path_factory.mktemp("rec") / "field"
    res = cli("emulate", "studies/tractor_emulator.toml", "--nmea-port", "0", "--duration", "6", "--record", where,
              "--set", "can.interface=virtual", "--set", "can.channel=recording-test", timeout=120)
    assert res.returncode == 0, res.stdout + res.stderr
    return where


def test_the_nmea_recording_has_host_stamps_and_parses(recording):
    from agrobot.components.hardware.nmea import NMEAStream, Position

    lines = (recording / "gps.nmea").read_text().splitlines()
    stamps = [float(line.split(" ", 1)[0]) for line in lines]
    assert stamps == sorted(stamps) and 5.0 < stamps[-1] - stamps[0] < 7.0          # real time, 6 s
    stream = NMEAStream()
    items = stream.feed("".join(line.split(" ", 1)[1] + "\r\n" for line in lines).encode())
    fixes = [i for i in items if isinstance(i, Position)]
    assert len(fixes) == pytest.approx(6 / 0.05, abs=3)                               # 20 Hz GGA
    c = stream.counters
    assert (c.bad_checksum, c.malformed, c.partial) == (0, 0, 0)


def test_the_can_recording_is_a_candump_log_the_dbc_decodes(recording):
    import can

    from agrobot.components.hardware.can_frames import load_dbc

    db = load_dbc("")
    frames = list(can.LogReader(str(recording / "can.log")))
    feedback = db.get_message_by_name("TractorFeedback")
    sent = [f for f in frames if f.arbitration_id == feedback.frame_id]
    assert len(sent) > 100 and all(not f.is_rx for f in sent)
    decoded = [feedback.decode(f.data) for f in sent]
    assert {"SteerAngle", "YawRate", "Speed"} <= set(decoded[-1])
    # no guidance is connected: the tractor stands, its wheel angle and speed reported as 0
    assert all(d["Speed"] == 0 and abs(d["SteerAngle"]) < 1e-3 for d in decoded)
    times = [f.timestamp for f in sent]
    assert times == sorted(times)


def test_record_into_a_file_is_refused_by_name(tmp_path):
    target = tmp_path / "a_file"
    target.write_text("x")
    res = cli("emulate", "studies/tractor_emulator.toml", "--nmea-port", "0", "--duration", "1", "--record", str(target),
              timeout=60)
    assert res.returncode == 2 and "--record" in res.stderr and "is a file" in res.stderr
    assert target.read_text() == "x"
