"""identify takes the vehicle it is given: a wheelbase given with the recording (--wheelbase) is
the one the kinematic model uses, and the report says where it came from; --course-speed sets the
speed above which the GNSS course measures the yaw. Truth: the small Ackermann machine
(harness.small_ackermann: wheelbase 1.27 m, gain 0.85), identified with no study, where the
paper tractor's 1.4 m would scale its gain by 1.4 / 1.27."""
from __future__ import annotations

import pytest

from agrobot import api
from agrobot.orchestrator.study import StudyError
from agrobot.measurements.options import ImportOptions
from harness.small_ackermann import make_small_log


@pytest.fixture(scope="module")
def small_csv(tmp_path_factory):
    frame, truth = make_small_log(1, duration=120.0)
    path = tmp_path_factory.mktemp("declared") / "small.csv"
    frame.to_csv(path, index=False)
    return path, frame, truth


def test_a_wheelbase_given_with_the_recording_is_the_one_used(small_csv):
    path, frame, truth = small_csv
    csv = path.with_name("no_positions.csv")
    frame.drop(columns=["x", "y"]).to_csv(csv, index=False)
    rep = api.identify(str(csv), recording=ImportOptions(wheelbase=truth["wheelbase"]), plots=False).report
    assert rep["vehicle"]["wheelbase"] == pytest.approx(truth["wheelbase"])
    assert "--wheelbase" in rep["vehicle"]["wheelbase_from"]
    gain = rep["steering_map"]["gain"]
    assert gain["interval"][0] <= truth["gain"] <= gain["interval"][1], gain
    assert any(n.startswith(f"wheelbase {truth['wheelbase']:.3g} m") for n in rep["notes"])


def test_without_one_the_report_says_the_paper_tractor_was_assumed(small_csv):
    path, frame, _ = small_csv
    csv = path.with_name("no_positions_2.csv")
    frame.drop(columns=["x", "y"]).to_csv(csv, index=False)
    rep = api.identify(str(csv), plots=False).report
    assert rep["vehicle"]["wheelbase"] == pytest.approx(1.4)
    assert "paper tractor" in rep["vehicle"]["wheelbase_from"] and "--wheelbase" in rep["vehicle"]["wheelbase_from"]


def test_course_speed_sets_the_course_floor(small_csv):
    """Positions only (no gyro, no heading): the course is read above --course-speed, so driving
    below the default 1 m/s is used when 0.5 is given."""
    path, frame, truth = small_csv
    csv = path.with_name("positions_only.csv")
    frame.drop(columns=["heading"]).to_csv(csv, index=False)
    rep = api.identify(str(csv), recording=ImportOptions(wheelbase=truth["wheelbase"]), plots=False,
                       course_speed=0.5).report
    assert 0.5 <= rep["segments"]["min_speed"] < 1.0
    with pytest.raises(StudyError, match="--course-speed"):
        api.identify(str(csv), course_speed=-1.0, plots=False)
