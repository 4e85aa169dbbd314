"""identify names a study whose wheelbase disagrees with the log's turns by more than 30 % before
its results, as diagnose does before its verdict: a steering map's gain fitted on the wrong
wheelbase (1.5 x on a 2 m study for a 1.27 m machine) is otherwise read as the vehicle's.

Truth: the small Ackermann machine (harness.truth_tractor, wheelbase 1.27 m, kinematic regime),
identified against its own baseline study and against the same study scaled to 2 m
(harness.vehicle_classes.study)."""
from __future__ import annotations

import re

import pytest

from agrobot import api
from harness.truth_tractor import SMALL_WHEELBASE, make_log
from harness.vehicle_classes import study


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    folder = tmp_path_factory.mktemp("mismatch")
    frame, _ = make_log(3, None, duration=90.0, vehicle="small_ackermann")
    log = folder / "small.csv"
    frame.to_csv(log, index=False)
    return log, study(folder), study(folder, wheelbase=2.0)


def test_a_study_of_another_wheelbase_is_named_first_with_the_logs(small):
    log, _, long_study = small
    rep = api.identify(str(log), study=str(long_study), plots=False).report
    first = rep["notes"][0]
    assert first.startswith("before the results: the log's turns are not the study's vehicle"), rep["notes"]
    found = float(re.search(r"wheelbase ([0-9.]+) m from", first).group(1))
    assert found == pytest.approx(SMALL_WHEELBASE, rel=0.05)
    assert "small_ackermann_2.toml 2 m" in first and rep["study_mismatch"] in first


def test_the_vehicles_own_study_gets_no_such_note(small):
    log, own, _ = small
    rep = api.identify(str(log), study=str(own), plots=False).report
    assert "study_mismatch" not in rep and not any("not the study's vehicle" in n for n in rep["notes"]), rep["notes"]


def test_the_command_line_says_it_before_the_steering_map(small, cli, tmp_path):
    log, _, long_study = small
    run = cli("identify", log, "--study", long_study, "--out", tmp_path / "out", "--no-plots")
    assert run.returncode == 0, run.stderr
    said = run.stdout.find("not the study's vehicle")
    assert 0 <= said < run.stdout.find("steering map:"), run.stdout
    assert "warning: the log's turns are not the study's vehicle" in run.stderr


def test_the_help_names_the_wheelbase_identify_stands_on_without_one_given(small, cli):
    """Without --wheelbase identify stands on the study's [vehicle] wheelbase (2 m here), and --help
    says so."""
    log, _, long_study = small
    shown = " ".join(cli("identify", "--help").stdout.split())
    assert "default: the study's [vehicle] wheelbase, else its yaw plant's l_f + l_r, else 1.4" in shown, shown
    rep = api.identify(str(log), study=str(long_study), plots=False).report
    assert rep["vehicle"]["wheelbase"] == pytest.approx(2.0) and "[vehicle] table" in rep["vehicle"]["wheelbase_from"]
