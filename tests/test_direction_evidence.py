"""Reversing found on generated recordings (harness.quirk_recordings) that carry it with a known
truth: a tractor backing up straight (the wheels do not steer: only the gyro, integrated, shows the
course turned by pi while the body did not), and a mower backing up while its receiver falls to
DGPS (the positions' noise is of the size of a short chord: the course is read over a longer one)."""
from __future__ import annotations

import pytest

from agrobot.api import convert
from agrobot.measurements import LogError
from harness.quirk_recordings import compose


def named(meaning: str) -> list[tuple[float, float]]:
    """The stretches a reversing finding's text names: 'reverses at 1.0-2.0 s, 3.0-4.0 s (...'."""
    said = meaning.split("reverses at ")[1].split(" (")[0]
    return [tuple(float(x) for x in part.strip().removesuffix(" s").split("-")) for part in said.split(",")]


@pytest.mark.parametrize("seed, classes, machine", [
    (5656, {"reversing_unsigned"}, "tractor"),
    (5519, {"reversing_unsigned", "fix_quality_drop", "nmea_checksum"}, "mower"),
    (5471, {"reversing_unsigned", "clock_jump", "mislabelled_channel"}, "mower"),
])
def test_each_reversing_stretch_is_named_within_a_second(tmp_path, seed, classes, machine):
    truth = compose(seed, tmp_path / "rec")             # the composition benchmarks/quirk_composition.py draws
    assert set(truth["planted"]) == classes and truth["machine"] == machine
    want = truth["planted"]["reversing_unsigned"]["stretches"]
    with pytest.raises(LogError, match="--sign-speed"):
        convert(tmp_path / "rec")
    rec = convert(tmp_path / "rec", sign_speed=True)
    found = [f for f in rec.report["audit"]["findings"] if f["kind"] == "reversing"]
    assert len(found) == 1
    got = named(found[0]["meaning"])
    assert len(got) == len(want), (got, want)
    for (a, b), (ta, tb) in zip(got, want):
        assert abs(a - ta) <= 1.0 and abs(b - tb) <= 1.0, (got, want)


@pytest.mark.parametrize("seed, layout, machine", [(7001, "devices", "tractor"), (7002, "nmea", "mower"),
                                                   (7003, "table", "utility")])
def test_a_clean_recording_names_no_reversing(tmp_path, seed, layout, machine):
    compose(seed, tmp_path / "rec", classes=[], layout=layout, machine=machine)
    rec = convert(tmp_path / "rec")
    assert not [f for f in rec.report["audit"]["findings"] if "revers" in f["kind"]]
