"""identify's steering-geometry choice is a field of its report, and the diagnosis reads the field,
not the wording of identify's note about it (the note stays, for the reader).

Truth: harness.truth_tractor's paper tractor, whose single-track equations are driven by the wheel
angle w itself (no tangent), steered to 0.39 rad (99th percentile of |delta|), where tan w exceeds w
by 5 %: identify compares both geometries and keeps w, passing over tan."""
from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from agrobot.diagnosis import pipeline
from agrobot.diagnosis.baseline import baseline_from_study, geometry_choice, identify_note
from agrobot.identification.ordinary_driving import LARGE_ANGLE, identify_driving
from agrobot.orchestrator.study import load_study
from agrobot.studies import shipped
from harness.truth_tractor import make_log


@pytest.fixture(scope="module")
def drive():
    frame, _ = make_log(1, None, duration=120.0, vehicle="tractor")
    return frame, identify_driving(frame, "tractor.csv")


def reworded(report: dict) -> dict:
    """The report with its geometry note in other words (and no 'steering geometry:' prefix)."""
    out = copy.deepcopy(report)
    out["notes"] = [n.replace("steering geometry:", "the yaw plant's input -").replace("passed over", "rejected")
                    for n in out["notes"]]
    return out


def test_the_report_holds_the_choice_as_a_field(drive):
    frame, rep = drive
    choice = rep["steering_geometry_choice"]
    truth_reach = float(np.percentile(np.abs(frame["delta"][frame["v"] > 0.5]), 99))
    assert truth_reach > LARGE_ANGLE                        # both geometries are tried
    assert choice["how"] == "compared"
    assert choice["value"] == rep["steering_geometry"] == "w" and choice["passed_over"] == "tan"
    assert choice["reach"] == pytest.approx(truth_reach, rel=0.1)
    assert choice["rms"]["w"] < choice["rms"]["tan"]
    assert any(n.startswith("steering geometry:") for n in rep["notes"])     # the text stays for humans


def test_the_diagnosis_takes_the_geometry_from_the_field_whatever_the_note_says(drive, monkeypatch):
    _, rep = drive
    changed = reworded(rep)
    assert not any(n.startswith("steering geometry:") for n in changed["notes"])
    note = identify_note(changed)
    rms = rep["steering_geometry_choice"]["rms"]
    assert "driven by w" in note and "passed over: tan w" in note
    assert f"{rms['w']:.3g}" in note and f"{rms['tan']:.3g}" in note
    monkeypatch.setattr(pipeline, "identify_driving", lambda *a, **k: copy.deepcopy(changed))
    study = load_study(shipped("figure8.toml"))
    base = baseline_from_study(study)
    mine = pipeline.identified_vehicle(drive[0], "tractor.csv", study, base)["identified"]
    assert mine["steering_geometry"] == "w" and mine["steering_geometry_note"] == note
    says = geometry_choice(base, None, "", mine["steering_geometry"], mine["steering_geometry_note"])
    assert says["value"] == "w" and "as identify chose on this log" in says["from"]
    assert "passed over: tan w" in says["from"]


def test_a_field_without_a_note_still_says_why():
    """Each way identify chooses, from the field alone (no notes at all)."""
    small = {"steering_geometry_choice": {"value": "w", "how": "small_angles", "reach": 0.1, "threshold": LARGE_ANGLE,
                                          "passed_over": "tan"}, "notes": []}
    assert "0.1 rad" in identify_note(small) and f"{100 * (math.tan(LARGE_ANGLE) / LARGE_ANGLE - 1):.0f} %" in \
        identify_note(small)
    option = {"steering_geometry_choice": {"value": "tan", "how": "option", "passed_over": "w"}, "notes": []}
    assert "--steering-geometry tan" in identify_note(option)
    assert "r = v tan(delta) / L" in identify_note({"steering_geometry_choice": {"value": "tan", "how": "kinematic"}})
