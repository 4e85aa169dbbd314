"""The recording formats are one registry (measurements.recording_readers): the converter, ``convert --list``
and the help read it, so a format is named everywhere by being registered, and the registry's order
decides which reader claims a file and which reader's files make the recording."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from agrobot.measurements import recording_readers as readers
from harness.generated_recordings import write_nmea
from agrobot.measurements.listing import list_source
from agrobot.measurements.log import LogError
from agrobot.measurements.options import ImportOptions
from agrobot.measurements.recording import import_recording, is_recording, load_log, recording_files
from agrobot.measurements.streams import Reader, Streams
from agrobot.orchestrator.cli import build_parser, main


class ToyReader(Reader):
    """A format no module of the package knows: rows of ``t, v, yaw_rate, delta_cmd`` (SI)."""

    name, listed, suffixes = "toy logs", "toy rows", (".toy",)

    def __init__(self, kind: str = "toy") -> None:
        self.kind, self.files = kind, f"*.toy ({kind})"

    def streams(self, files, options, source):
        t, v, r, d = np.loadtxt(files[self.kind][0], delimiter=",", ndmin=2).T
        signals = {"v": (t, v), "yaw_rate": (t, r), "delta_cmd": (t, d)}
        report = {"source": str(source), "files": {self.kind: [str(p) for p in files[self.kind]]}, "dbc": None,
                  "notes": [], "columns": {c: f"{self.kind} {c}" for c in signals}, "clocks": {"reference": "toy"}}
        return Streams(None, signals, report, {"delta_cmd"}, groups={c: self.kind for c in signals})

    def listing(self, paths, options, source):
        return [f"{self.kind} {p.name}: {len(p.read_text().splitlines())} rows" for p in paths]


@pytest.fixture
def registry(monkeypatch):
    """The registry as the package builds it, restored after the test."""
    monkeypatch.setattr(readers, "READERS", list(readers.READERS))
    return readers


def _toy_file(path: Path) -> Path:
    t = 1.7e9 + np.arange(0.0, 40.0, 0.1)
    rows = np.column_stack([t, np.full_like(t, 2.0), 0.1 * np.sin(0.3 * t), 0.05 * np.sin(0.3 * t)])
    np.savetxt(path, rows, delimiter=",", fmt="%.6f")
    return path


def _subparser(name: str) -> argparse.ArgumentParser:
    action = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    return action.choices[name]


def _convert_help() -> str:
    top = build_parser().format_help()
    return " ".join((top + _subparser("convert").format_help()).split())     # argparse's wrapping undone


def _refusal(folder: Path) -> str:
    with pytest.raises(LogError) as caught:
        list_source(folder, ImportOptions())
    return str(caught.value)


def _named(text: str, reader: Reader) -> None:
    assert reader.kind.lower() in text.lower(), (reader.kind, text)
    for suffix in reader.suffixes:
        assert suffix in text, (reader.kind, suffix, text)


def test_every_registered_reader_is_named_by_the_help_and_the_listing(tmp_path):
    help_text, refusal = _convert_help(), _refusal(tmp_path)
    assert [r.kind for r in readers.READERS] == ["bag", "isoxml", "nmea", "can", "numpy", "matlab", "table"]
    for reader in readers.READERS:
        _named(help_text, reader)
        _named(refusal, reader)
        assert f"{reader.name} ({reader.files})" in help_text and reader.listed in help_text
    assert refusal.startswith(f"{tmp_path}: no recording in it: expected ROS bags")


def test_a_new_reader_is_read_listed_and_named_once_registered(registry, tmp_path, capsys):
    toy = registry.register(ToyReader(), before="table")
    source = _toy_file(tmp_path / "drive.toy")
    assert is_recording(source) and recording_files(source)["toy"] == [source]
    _named(_convert_help(), toy)
    _named(_refusal(_empty(tmp_path)), toy)
    log, report = import_recording(source)
    assert report["files"] == {"toy": [str(source)]} and len(log) > 300
    assert np.allclose(log["v"], 2.0)
    assert load_log(source, ("t", "v"), recording=ImportOptions())[0]["v"].notna().all()
    assert main(["convert", str(source), "--out", str(tmp_path / "out.csv")]) == 0
    assert json.loads((tmp_path / "out.import.json").read_text())["files"] == {"toy": [str(source)]}
    assert len(pd.read_csv(tmp_path / "out.csv")) == len(log)
    capsys.readouterr()
    assert main(["convert", str(source), "--list"]) == 0
    assert capsys.readouterr().out.strip() == "toy drive.toy: 400 rows"


def _empty(tmp_path: Path) -> Path:
    (tmp_path / "empty").mkdir(exist_ok=True)
    return tmp_path / "empty"


@pytest.mark.parametrize("first", ["toy_a", "toy_b"])
def test_the_registry_order_decides_which_reader_claims_a_file(registry, tmp_path, first):
    second = "toy_b" if first == "toy_a" else "toy_a"
    registry.register(ToyReader(first))
    registry.register(ToyReader(second))
    source = _toy_file(tmp_path / "drive.toy")
    files = recording_files(tmp_path)
    assert files[first] == [source] and files[second] == []
    assert import_recording(tmp_path)[1]["files"] == {first: [str(source)]}
    assert list_source(tmp_path, ImportOptions()) == [f"{first} drive.toy: 400 rows"]


def test_the_registry_order_decides_which_readers_files_make_the_recording(registry, tmp_path):
    _toy_file(tmp_path / "drive.toy")
    write_nmea(tmp_path / "drive.nmea", 40.0)
    registry.register(ToyReader())                                  # after every other: NMEA makes it
    assert "toy" not in import_recording(tmp_path)[1]["files"]
    listed = list_source(tmp_path, ImportOptions())
    assert listed[0].startswith("NMEA drive.nmea") and listed[-1] == "toy drive.toy: 400 rows"
    registry.READERS.remove(next(r for r in registry.READERS if r.kind == "toy"))
    registry.register(ToyReader(), before="nmea")                   # ahead of NMEA: the toy makes it
    assert import_recording(tmp_path)[1]["files"] == {"toy": [str(tmp_path / "drive.toy")]}
    assert list_source(tmp_path, ImportOptions())[0] == "toy drive.toy: 400 rows"


def test_a_kind_is_registered_once_and_before_a_kind_that_exists(registry):
    with pytest.raises(ValueError, match="kind 'nmea' is registered already"):
        registry.register(ToyReader("nmea"))
    with pytest.raises(ValueError, match="no reader of kind 'gpx'"):
        registry.register(ToyReader(), before="gpx")
