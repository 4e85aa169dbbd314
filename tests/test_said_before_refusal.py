"""A log too short to judge still says what comes before any verdict: the study not being the log's
vehicle (its turns against the study's wheelbase), the study's wheelbase or steering gain off the
log's turns by 10-30 %, and the class's default outline of a study without dimensions. The log is the
small Ackermann truth (wheelbase 1.27 m, harness.truth_tractor), 25 s long."""
from __future__ import annotations

import re

import pytest

from agrobot.diagnosis.pipeline import diagnose
from agrobot.studies import shipped
from harness.steering_maps import read_through
from harness.truth_tractor import SMALL_WHEELBASE, make_log
from harness.vehicle_classes import study


@pytest.fixture(scope="module")
def short_log(tmp_path_factory):
    frame, _ = make_log(3, None, duration=25.0, vehicle="small_ackermann")
    path = tmp_path_factory.mktemp("short") / "small_25s.parquet"
    frame.to_parquet(path)
    return path


def test_a_study_of_another_size_is_named_before_the_refusal_of_a_short_log(short_log):
    """Against the f1tenth study (0.32 m) the 1.27 m machine's turns are named as not the study's,
    with the log's wheelbase, before 'cannot decide'."""
    res = diagnose(short_log, None, shipped("f1tenth.toml"), plots=False, identify=False)
    assert res["verdict"] == "cannot decide" and "lasts" in res["reason"]
    named = [n for n in res.get("before_verdict", []) if "not the study's vehicle" in n]
    assert named, res.get("before_verdict")
    found = float(re.search(r"wheelbase ([0-9.]+) m from", named[0]).group(1))
    assert found == pytest.approx(SMALL_WHEELBASE, rel=0.1)
    assert "f1tenth.toml 0.32 m" in named[0]


def test_a_declared_vehicle_without_dimensions_gets_its_class_defaults_named_before_the_refusal(short_log, tmp_path):
    """Its own study without length and width: no mismatch, the robot class's default outline named."""
    res = diagnose(short_log, None, study(tmp_path, dimensions=False), plots=False, identify=False)
    assert res["verdict"] == "cannot decide"
    notes = res.get("before_verdict", [])
    assert not any("not the study's vehicle" in n or "more than 10 %" in n for n in notes), notes
    assert any("class's defaults" in n and "robot" in n for n in notes), notes


def test_a_steering_gain_that_moves_the_logs_wheelbase_15_percent_is_said_with_the_evidence(tmp_path):
    """The wheels turn 1.18 x the reading: the log turns like a 1.08 m machine, 15 % short of its
    study's 1.27 m, under the 30 % at which the study is another vehicle: said before any verdict
    with both wheelbases."""
    frame, _ = make_log(3, None, duration=25.0, vehicle="small_ackermann")
    log = tmp_path / "gain.parquet"
    read_through(frame, gain=1.18).to_parquet(log)
    res = diagnose(log, None, study(tmp_path), plots=False, identify=False)
    said = [n for n in res.get("before_verdict", []) if "more than 10 %" in n]
    assert said and not any("not the study's vehicle" in n for n in res["before_verdict"]), res.get("before_verdict")
    found = float(re.search(r"wheelbase of ([0-9.]+) m", said[0]).group(1))
    assert found == pytest.approx(SMALL_WHEELBASE / 1.18, rel=0.05)
    assert "1.27 m" in said[0] and "steering map" in said[0]
