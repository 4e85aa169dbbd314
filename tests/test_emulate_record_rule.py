"""``emulate --record DIR`` without ``--out`` writes its recordings under the rule of every written
file (orchestrator.output): an existing recording is refused without ``--overwrite`` and kept as it
was, the recordings are written under unique temporary names and renamed when the emulator stops,
and a full disk is a named error (exit 2) that leaves no recording and no temporary file behind."""
from __future__ import annotations

import errno
from pathlib import Path

import pytest

from tests.commands import in_process

ROOT = Path(__file__).resolve().parents[1]


def _emulate(folder: Path, capsys, channel: str, *extra: str) -> tuple[int, str, str]:
    return in_process(["emulate", ROOT / "studies" / "tractor_emulator.toml", "--nmea-port", "0", "--duration", "5.2",
                       "--record", folder, "--set", "can.interface=virtual", "--set", f"can.channel={channel}",
                       "--no-progress", *extra], capsys)


def _hidden(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


@pytest.mark.slow     # two real-time runs; the full-disk case stays fast
def test_an_earlier_recording_is_refused_without_overwrite_and_replaced_with_it(tmp_path, capsys):
    folder = tmp_path / "field"
    folder.mkdir()
    (folder / "gps.nmea").write_text("an earlier drive\n")
    code, _, err = _emulate(folder, capsys, "rule-a")
    assert code == 2 and "--record" in err and "gps.nmea" in err and "exists" in err and "--overwrite" in err, err
    assert (folder / "gps.nmea").read_text() == "an earlier drive\n" and _hidden(folder) == []
    assert not (folder / "can.log").exists()
    code, out, err = _emulate(folder, capsys, "rule-b", "--overwrite")
    assert code == 0, err
    lines = (folder / "gps.nmea").read_text().splitlines()
    assert lines and "an earlier drive" not in lines and all(line.split(" ", 1)[1].startswith("$") for line in lines)
    assert (folder / "can.log").stat().st_size > 0 and _hidden(folder) == []


def test_a_full_disk_while_recording_is_named_and_leaves_nothing(tmp_path, capsys, monkeypatch):
    import agrobot.components.nmea_server as server

    class Full:
        """The recording's file as on a full disk: every write fails with ENOSPC."""

        def __init__(self, name, *args, **kwargs) -> None:
            self.name = name

        def write(self, text):
            raise OSError(errno.ENOSPC, "No space left on device", self.name)

        def close(self) -> None:
            pass

    monkeypatch.setattr(server, "open", Full, raising=False)
    folder = tmp_path / "field"
    code, _, err = _emulate(folder, capsys, "rule-c")
    assert code == 2 and "disk is full" in err and "Traceback" not in err, err
    assert f"--record {folder / 'gps.nmea'}: the disk is full" in err and ".writing" not in err, err
    assert sorted(p.name for p in folder.iterdir()) == [], list(folder.iterdir())
