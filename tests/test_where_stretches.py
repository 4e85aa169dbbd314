"""Every stretch a --where selects is judged, not only the longest (identification.from_log
joined_stretches, measurements.modes.long_enough): a generated 240 s tractor recording
(harness.quirk_recordings) driven automatically, by hand (118-141 s) and paused (53-63 s), so the
import's run (62-240 s) holds two automatic stretches either side of the hand-driven one."""
from __future__ import annotations

import pytest

from agrobot.identification.from_log import read_uneven
from agrobot.measurements import LogError
from agrobot.measurements.options import ImportOptions
from harness.quirk_recordings import compose


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    folder = tmp_path_factory.mktemp("where") / "rec"
    truth = compose(11, folder, classes=["mode_stretches"], layout="table", machine="tractor", duration=240.0)
    return folder, truth


def auto_seconds(truth, start: float, end: float) -> list[float]:
    """The truth's automatic stretches inside [start, end], their lengths."""
    cuts = sorted(truth["planted"]["mode_stretches"]["manual"] + truth["planted"]["mode_stretches"]["paused"])
    edges, out, a = [c for c in cuts if c[1] > start and c[0] < end], [], start
    for lo, hi in edges:
        out.append(lo - a)
        a = hi
    return out + [end - a]


def test_both_stretches_are_joined_each_with_its_burn_in(recording):
    folder, truth = recording
    frame, imported, note = read_uneven(folder, recording=ImportOptions(where="mode == auto", min_stretch=10.0))
    used = imported["used"]
    want = [s for s in auto_seconds(truth, used["start"], used["end"]) if s >= 10.0]
    assert len(want) == 2 and "joined" in note
    assert abs(frame["t"].iloc[-1] - sum(want)) < 1.0                 # both, not the longest alone
    assert len(frame.attrs["joins"]) == 1 and abs(frame.attrs["joins"][0] - want[0]) < 0.5
    assert frame.attrs["audit"]                                         # the audit's findings travel with it


def test_a_shorter_stretch_is_left_out_and_named(recording, capsys):
    folder, truth = recording
    frame, imported, note = read_uneven(folder, recording=ImportOptions(where="mode == auto", min_stretch=60.0))
    said = capsys.readouterr().err
    assert "left out, shorter: 1" in said and "--min-stretch" in said
    assert note is None or "joined" not in note


def test_no_stretch_long_enough_is_refused_naming_the_option(recording):
    folder, _ = recording
    with pytest.raises(LogError, match="--min-stretch"):
        read_uneven(folder, recording=ImportOptions(where="mode == auto", min_stretch=500.0))


@pytest.mark.slow
def test_diagnose_judges_both_stretches(recording):
    from agrobot import api

    folder, truth = recording
    d = api.diagnose(folder, recording=ImportOptions(min_stretch=10.0), where="mode == auto", identify=False,
                     plots=False, workers=1)
    report = d.result if hasattr(d, "result") else d.report
    assert any("joined" in w for w in report["warnings"])
    assert report["split"]["spans"][0][1] > 140.0         # the held-out tail ends past the first stretch
