"""The import audit on quirks planted together (harness.quirk_recordings compositions, each drawn
from its seed as benchmarks/quirk_composition.py draws it), each against the truth it was planted
with: leap seconds beside a deg/s gyro, a receiver's heading beside held positions, a clock step in
a file with one noisy column and in a file of noise only, duplicated NMEA epochs with bad
checksums, held positions through a degraded fix, a speed in km/h beside held positions through a
degraded fix, devices on one clock whose gyro meets a slow mower's course for 10 s only, a clock stepped back with a row
written late just after it; and a held channel that changes twice in one of its periods."""
from __future__ import annotations

import re

import numpy as np
import pytest

from agrobot.api import convert
from agrobot.measurements.channel_updates import holding
from harness.quirk_recordings import START, compose


def composed(seed: int, folder, classes: set) -> dict:
    truth = compose(seed, folder)
    assert set(truth["planted"]) == classes         # the draw this test is about
    return truth


def kinds(rec, kind: str) -> list[dict]:
    return [f for f in rec.report["audit"]["findings"] if f["kind"] == kind]


def test_leap_seconds_move_the_receiver_and_every_other_device_stays_together(tmp_path):
    """The receiver on GPS time (18 s ahead) beside a gyro in deg/s: the receiver's file is the one
    moved, by the date's leap count, so the gyro's unit is read on the steering of its own clock."""
    truth = composed(5422, tmp_path, {"fix_quality_drop", "leap_seconds", "quoted_rows", "raw_units"})
    rec = convert(tmp_path)
    assert rec.report["audit"]["alignment"]["offsets_s"] == {"gnss": pytest.approx(18.0, abs=1e-9)}
    t = rec.report["used"]["utc_start_s"] - START + rec.log["t"].to_numpy(float)
    want = np.percentile(np.abs(truth["drive"].at("yaw_rate", t)), 90)
    assert np.percentile(np.abs(rec.log["yaw_rate"].to_numpy(float)), 90) == pytest.approx(want, rel=0.03)


@pytest.mark.parametrize("seed", [5443, 5613])
def test_a_receivers_heading_beside_held_positions_keeps_its_own_updates(tmp_path, seed):
    """Positions held at 5 Hz in 10 Hz epochs, the dual antenna's heading at 10 Hz with dropouts:
    the heading is judged at its own 10 Hz, and its longest dropout named within 1.5 epochs."""
    truth = compose(seed, tmp_path)["planted"]
    assert truth["held_channel"]["channel"] == "position" and truth["channel_dropouts"]["channel"] == "heading"
    rec = convert(tmp_path, sign_speed=True)
    row = next(r for r in rec.report["audit"]["channels"] if r["channel"] == "heading")
    assert row["rate_hz"] == pytest.approx(10.0, rel=0.02)
    longest = max(f["value"] for f in kinds(rec, "gap_split") + kinds(rec, "gap_bridged") if f["channels"] == ["heading"])
    assert longest == pytest.approx(truth["channel_dropouts"]["longest_s"], abs=0.15)


def test_a_forward_clock_step_is_named_though_one_noisy_column_jumps(tmp_path):
    """One table, its logger's clock stepped forward: most columns change across the step as over
    one row; one that happens to change more there does not veto them."""
    truth = composed(5501, tmp_path, {"clock_jump", "one_clock_weak", "two_yaw_sources"})["planted"]["clock_jump"]
    rec = convert(tmp_path)
    found = kinds(rec, "clock_jump")
    assert len(found) == 1 and found[0]["value"] == pytest.approx(truth["by_s"], abs=0.05)


def test_a_forward_clock_step_in_a_file_of_noise_is_told_by_the_other_files(tmp_path):
    """The IMU's file holds an accelerometer's vertical axis (noise about g) as its only column, and
    its clock steps forward: nothing in it tells a step from a silence, but it starts with the other
    files and ends the step after them."""
    truth = composed(5512, tmp_path, {"clock_jump", "mislabelled_channel"})["planted"]["clock_jump"]
    rec = convert(tmp_path)
    found = kinds(rec, "clock_jump")
    assert len(found) == 1 and found[0]["channels"] == [f"{truth['file']}.csv"]
    assert found[0]["value"] == pytest.approx(truth["by_s"], abs=0.05)
    moment = float(re.search(r"stamps \S+T\d\d:\d\d:(\d+\.\d+)Z", found[0]["meaning"]).group(1))
    assert moment == pytest.approx(truth["at_s"], abs=1.0)


def test_duplicated_epochs_are_counted_as_the_file_holds_them_readable(tmp_path):
    """Epochs written twice, one copy's GGA corrupt: the reader counts the repeats it can read, and
    the truth says how many those are."""
    truth = composed(5608, tmp_path, {"duplicate_stamps", "fix_quality_drop", "nmea_checksum"})["planted"]
    readable = truth["duplicate_stamps"]["readable"]
    assert readable < truth["duplicate_stamps"]["count"]          # a corrupt sentence hit a copy
    said = [s for s in rec_notes(tmp_path) if "repeat the time" in s]
    assert [int(re.search(r"(\d+) GGA", s).group(1)) for s in said] == [readable]


def rec_notes(folder) -> list[str]:
    return [str(s) for s in convert(folder).report.get("notes", [])]


def test_held_positions_hold_a_degraded_fix_as_well(tmp_path):
    """Positions held x4 in 20 Hz rows with DGPS and float stretches: still one update every 4 rows."""
    truth = composed(5633, tmp_path, {"fix_quality_drop", "held_channel", "raw_units", "reversing_unsigned"})
    held = truth["planted"]["held_channel"]
    rec = convert(tmp_path, sign_speed=True)
    found = [f for f in kinds(rec, "held_samples") if f["channels"] == ["gnss"]]
    assert len(found) == 1 and found[0]["updates_hz"] == pytest.approx(held["update_hz"], rel=0.1)


def test_a_speed_in_kmh_is_read_where_the_fix_is_at_its_usual_quality(tmp_path):
    """A mower's speed in km/h (no unit said), its positions held x4 and falling to DGPS twice: the
    DGPS stretches' noisy positions make the track's speed too fast; read without them, the scale is
    3.6 and the speed is converted."""
    truth = composed(9008, tmp_path, {"fix_quality_drop", "held_channel", "raw_units"})
    assert truth["planted"]["raw_units"]["factor"] == 3.6
    rec = convert(tmp_path)
    found = [f for f in kinds(rec, "scale_disagreement") if f["channels"] == ["gnss_speed", "v"]]
    assert len(found) == 1 and found[0]["value"] == pytest.approx(3.6, rel=0.03) and found[0]["resolved"]
    t = rec.report["used"]["utc_start_s"] - START + rec.log["t"].to_numpy(float)
    want = np.percentile(np.abs(truth["drive"].at("v", t)), 90)
    assert np.percentile(np.abs(rec.log["v"].to_numpy(float)), 90) == pytest.approx(want, rel=0.03)


def test_two_updates_in_one_period_keep_their_own_times():
    """A 5 Hz channel held in 20 Hz rows that changes twice in one of its periods (rows 401 and 402):
    on the sensor's clock both would take one time; each keeps its own, half a row apart at least."""
    rows = 0.05 * np.arange(800)
    x = np.repeat(np.random.default_rng(1).standard_normal(200), 4)
    x[402] += 1.0                       # a second change inside the period that starts at row 400
    found = holding(rows, x)
    assert found is not None and found["held"] == pytest.approx(4.0)
    assert np.min(np.diff(found["times"])) >= 0.025


def test_a_chance_correlation_over_a_few_seconds_moves_no_clock(tmp_path):
    """Three devices on one clock (no clock class planted), a mower above 1 m/s for about 10 s: the
    gyro meets the course by chance 23 s away (correlation 0.78 over 10 s); no file is moved."""
    truth = composed(9050, tmp_path, {"held_channel", "units_row"})
    rec = convert(tmp_path)
    assert rec.report["audit"]["alignment"]["offsets_s"] == {}
    t = rec.report["used"]["utc_start_s"] - START + rec.log["t"].to_numpy(float)
    want = np.percentile(np.abs(truth["drive"].at("yaw_rate", t)), 90)
    assert np.percentile(np.abs(rec.log["yaw_rate"].to_numpy(float)), 90) == pytest.approx(want, rel=0.03)


def test_a_clock_step_back_is_named_though_a_row_written_late_follows_it(tmp_path):
    """One table whose clock steps back 1.5 s at 39 s, a row written late a few rows after the step:
    the rows after it still go on from it at the cadence (all but the late one): a clock's step."""
    truth = composed(9063, tmp_path, {"clock_jump", "out_of_order", "quoted_rows", "units_row"})["planted"]
    rec = convert(tmp_path)
    found = kinds(rec, "clock_jump")
    assert len(found) == 1 and found[0]["value"] == pytest.approx(truth["clock_jump"]["by_s"], abs=0.05)
    said = [s for s in rec.report.get("notes", []) if "step back" in str(s)]
    assert [int(re.search(r"(\d+) times step back", str(s)).group(1)) for s in said] == [truth["out_of_order"]["count"]]
