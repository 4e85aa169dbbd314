"""The import audit on generated recordings with a planted quirk and its known truth
(harness.quirk_recordings): clock steps inside a file, a GPS week rollover, leap seconds, a
dual-antenna heading without a gyro, raw units, channels beyond physical range, and a refusal
that lists the other findings."""
from __future__ import annotations

import csv
import math
import re

import numpy as np
import pytest

from agrobot.api import convert
from agrobot.measurements.log import LogError
from harness.quirk_recordings import START, WEEK_ROLLOVER, compose


def findings(rec, kind: str) -> list[dict]:
    return [f for f in rec.report["audit"]["findings"] if f["kind"] == kind]


def log_times(rec) -> np.ndarray:
    """The log's samples on the truth's clock (s from the recording's start)."""
    return rec.report["used"]["utc_start_s"] - START + rec.log["t"].to_numpy(float)


@pytest.mark.parametrize("seed", [21, 24])
def test_a_clock_step_is_named_with_its_size_and_moment(tmp_path, seed):
    truth = compose(seed, tmp_path, classes=["clock_jump"])["planted"]["clock_jump"]
    rec = convert(tmp_path)
    found = findings(rec, "clock_jump")
    assert len(found) == 1
    assert found[0]["value"] == pytest.approx(truth["by_s"], abs=0.05)
    moment = float(found[0]["meaning"].split("(at ")[-1].split(" s")[0])
    assert moment == pytest.approx(truth["at_s"], abs=1.0)


def test_a_gps_week_rollover_between_files_is_moved_and_named(tmp_path):
    compose(1, tmp_path, classes=["gps_week_rollover"], layout="devices")
    rec = convert(tmp_path)
    found = findings(rec, "gps_week_rollover")
    assert [f["value"] for f in found] == [WEEK_ROLLOVER]
    assert rec.report["used"]["utc_start_s"] == pytest.approx(START, abs=1.0)


def test_leap_seconds_between_a_receiver_and_the_others_are_aligned(tmp_path):
    compose(6, tmp_path, classes=["leap_seconds"], layout="devices")
    rec = convert(tmp_path)
    offsets = rec.report["audit"]["alignment"]["offsets_s"]
    assert offsets.pop("gnss") == pytest.approx(18.0, abs=0.1)      # the receiver's stamps on GPS time
    assert all(abs(x) < 0.1 for x in offsets.values())
    assert any("leap seconds" in f["meaning"] for f in findings(rec, "clock_offset"))


def test_a_heading_without_a_gyro_is_the_logs_yaw_angle(tmp_path):
    drive = compose(2, tmp_path, classes=["heading_no_gyro"], layout="table")["drive"]
    rec = convert(tmp_path)
    psi = drive.at("psi", log_times(rec))
    error = np.degrees(np.abs(np.angle(np.exp(1j * (rec.log["heading"].to_numpy(float) - psi)))))
    assert "yaw_rate" not in rec.log and float(np.median(error)) < 2.0


def test_an_undeclared_speed_in_kmh_is_converted_on_the_receivers_evidence(tmp_path):
    truth = compose(1, tmp_path, classes=["raw_units"], layout="table", machine="utility")
    assert truth["planted"]["raw_units"]["channel"] in ("v", "yaw_rate")
    rec = convert(tmp_path)
    c = truth["planted"]["raw_units"]["channel"]
    x = np.percentile(np.abs(rec.log[c].to_numpy(float)), 90)
    y = np.percentile(np.abs(truth["drive"].at(c, log_times(rec))), 90)
    assert x / y == pytest.approx(1.0, abs=0.03)


def test_values_beyond_physical_range_are_named(tmp_path):
    compose(3, tmp_path, classes=[], layout="table", machine="tractor")
    path = tmp_path / "log.csv"
    rows = list(csv.reader(path.open()))
    v, r = rows[0].index("v"), rows[0].index("yaw_rate")
    for k in (100, 400, 900):
        rows[k][v] = "9.2e18"
    for k in range(1200, 1260):
        rows[k][r] = "100"
    with path.open("w") as f:
        csv.writer(f, lineterminator="\n").writerows(rows)
    with pytest.raises(LogError) as refused:          # the yaw rate refused, both named
        convert(tmp_path)
    text = str(refused.value)
    assert "out_of_range (v)" in text and "9.2e+18 m/s" in text
    assert "out_of_range (yaw_rate)" in text and "60 of 1800 samples" in text


def test_a_refusal_lists_the_other_findings(tmp_path):
    truth = compose(5, tmp_path, classes=["reversing_unsigned", "clock_jump"], layout="table")
    with pytest.raises(LogError) as refused:
        convert(tmp_path)
    text = str(refused.value)
    assert "--sign-speed" in text and "clock_jump" in text
    assert f"{abs(truth['planted']['clock_jump']['by_s']):.3f}" in text
    assert not math.isnan(truth["planted"]["clock_jump"]["at_s"])


def test_a_receivers_repeated_epochs_are_counted(tmp_path):
    truth = compose(2, tmp_path, classes=["duplicate_stamps"], layout="nmea")["planted"]["duplicate_stamps"]
    notes = [n for n in convert(tmp_path).report["notes"] if "repeat the time" in n]
    assert notes and notes[0].startswith(f"gnss.nmea: {truth['count']} GGA")


def test_a_receivers_heading_gaps_and_holds_are_named(tmp_path):
    truth = compose(2, tmp_path, classes=["channel_dropouts"], layout="nmea")["planted"]["channel_dropouts"]
    assert truth["channel"] == "heading"
    gaps = [f for f in convert(tmp_path).report["audit"]["findings"]
            if f["kind"].startswith("gap_") and f["channels"] == ["heading"]]
    assert max(f["value"] for f in gaps) == pytest.approx(truth["longest_s"], abs=0.15)


def test_a_mode_column_and_fix_quality_changes_are_named_with_their_stretches(tmp_path):
    truth = compose(7, tmp_path, classes=["mode_stretches", "fix_quality_drop"], layout="table")["planted"]
    rec = convert(tmp_path)
    modes, = findings(rec, "mode_stretches")
    fixes, = findings(rec, "fix_quality_changes")
    for (a, b), text in [(s, modes["meaning"]) for s in truth["mode_stretches"]["manual"]] + \
            [(s[:2], fixes["meaning"]) for s in truth["fix_quality_drop"]["stretches"]]:
        said = [float(x) for pair in re.findall(r"(\d+\.\d)-(\d+\.\d) s", text) for x in pair]
        assert min(abs(x - a) for x in said) < 1.0 and min(abs(x - b) for x in said) < 1.0
