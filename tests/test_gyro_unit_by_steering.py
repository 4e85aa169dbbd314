"""A gyro logged in deg/s with no second yaw source (no positions, no heading): its unit is read
from the turns its steering and speed imply through the wheelbase (measurements.audit
gyro_unit_by_steering). Generated recordings (harness.quirk_recordings, raw_units planted on the
yaw rate) with the receiver's columns removed; the truth's yaw rate is known."""
from __future__ import annotations

import csv

import numpy as np
import pytest

from agrobot.api import convert
from agrobot.measurements import LogError
from harness.quirk_recordings import START, compose


def deg_gyro_without_fixes(folder, scramble_steering: bool = False):
    """A table-layout composition whose yaw rate is written in deg/s, lat/lon/fix_quality removed."""
    for seed in range(300, 400):
        truth = compose(seed, folder, classes=["raw_units"], layout="table", machine="utility")
        if truth["planted"].get("raw_units", {}).get("channel") == "yaw_rate":
            break
    path = folder / "log.csv"
    rows = list(csv.reader(path.open()))
    keep = [i for i, name in enumerate(rows[0]) if name not in ("lat", "lon", "fix_quality")]
    rows = [[r[i] for i in keep] for r in rows]
    if scramble_steering:           # the steering no longer explains the turns: undecidable
        k = rows[0].index("delta")
        values = [r[k] for r in rows[1:]]
        np.random.default_rng(0).shuffle(values)
        for r, v in zip(rows[1:], values):
            r[k] = v
    with path.open("w", newline="") as f:
        csv.writer(f).writerows(rows)
    return truth


def test_a_deg_per_s_gyro_is_converted_on_the_steerings_evidence(tmp_path):
    truth = deg_gyro_without_fixes(tmp_path / "rec")
    rec = convert(tmp_path / "rec", wheelbase=2.8)
    found = [f for f in rec.report["audit"]["findings"] if f["kind"] == "unit_by_steering"]
    assert len(found) == 1 and abs(found[0]["value"] - 57.2958) < 0.01 and "[rad/s]" in found[0]["meaning"]
    t = rec.log["t"].to_numpy() + rec.report["used"]["utc_start_s"] - START
    want = truth["drive"].at("yaw_rate", t)
    got = rec.log["yaw_rate"].to_numpy()
    assert abs(np.percentile(np.abs(got), 90) / np.percentile(np.abs(want), 90) - 1) < 0.03


def test_without_evidence_it_says_undecided_and_refuses(tmp_path):
    deg_gyro_without_fixes(tmp_path / "rec", scramble_steering=True)
    with pytest.raises(LogError) as err:
        convert(tmp_path / "rec", wheelbase=2.8)
    assert "unit_undecided" in str(err.value) and "yaw_rate" in str(err.value)
