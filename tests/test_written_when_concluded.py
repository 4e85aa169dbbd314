"""What identify could not conclude is not written as a value: extended_study.toml leaves out the
cornering stiffnesses when no single understeer gradient K is concluded and a friction known only
as "at least" its class's top, and says so; no steady-state gain curve is drawn from a withheld K;
the characteristic speed set by a K not identified is not identified either.

Independent truth: hand-made identification reports of the F1TENTH study's car (the quantities an
identification of it would report), one with K withheld and the friction on its class's top."""
from __future__ import annotations

import math

import numpy as np
import pytest

from agrobot.identification.driving import DrivingLog
from agrobot.identification.from_log import write_extended_study
from agrobot.identification.ordinary_driving import _steady_gain, _understeer
from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study
from tests.vehicle_logs import ROOT_STUDIES


def _q(value, identifiable=True, **more):
    return {"value": value, "std": 0.1 * abs(value), "interval": [0.8 * value, 1.2 * value], "unit": "1",
            "identifiable": identifiable, **more}


def report(withheld: bool, at_least: bool) -> dict:
    K = _q(0.03, identifiable=not withheld, **({"withheld": True, "note": "no single value"} if withheld else {}))
    friction = _q(1.8, identifiable=not at_least, bounds=[0.3, 1.8], **({"at_least": True} if at_least else {}))
    return {"understeer_gradient": K, "cornering_stiffness": {"front": _q(40.0), "rear": _q(80.0)},
            "parameters": {"delay": _q(0.05)}, "tyre_saturation": {"found": True,
                                                                   "parameters": {"friction": friction,
                                                                                  "shape": _q(1.5)}}}


@pytest.mark.parametrize("withheld,at_least", [(True, True), (False, False)])
def test_extended_study_leaves_out_what_was_not_concluded(tmp_path, withheld, at_least):
    rep = report(withheld, at_least)
    assert write_extended_study(rep, Study.load(ROOT_STUDIES / "f1tenth.toml"), tmp_path, "gen.csv")
    text = (tmp_path / "extended_study.toml").read_text()
    assert ("C_f" in text) is not withheld and ("tyre_friction" in text) is not at_least
    left = " ".join(rep.get("extended_study_left_out", []))
    assert ("C_f, C_r" in left and "no single K" in left) is withheld
    assert ("tyre_friction (identified at least 1.8" in left) is at_least


def test_a_friction_per_axle_is_written_as_the_fronts_with_the_ratio(tmp_path):
    """identify kept a rear / front friction ratio of 1.4 (identification.axle_friction): its friction
    1.8 is the front axle's, so the study's plant gets it with the shape and the ratio
    (tyre_friction_ratio: the rear's peak 1.4 x 1.8 F_zr) beside the stiffnesses, and nothing is left out."""
    rep = report(False, False)
    rep["tyre_saturation"]["parameters"]["friction_ratio"] = _q(1.4)
    assert write_extended_study(rep, Study.load(ROOT_STUDIES / "f1tenth.toml"), tmp_path, "gen.csv")
    extended = Study.load(tmp_path / "extended_study.toml")
    plant = build_system(resolve(extended)).nodes["car"].component
    assert (plant.p["tyre_friction"], plant.p["tyre_shape"], plant.p["tyre_friction_ratio"]) == (1.8, 1.5, 1.4)
    assert plant.p["C_f"] == 40.0 and not rep.get("extended_study_left_out")


def test_no_gain_curve_from_a_withheld_k():
    t = np.arange(0, 10, 0.1)
    log = DrivingLog(t, np.zeros_like(t), np.full_like(t, 2.0), np.zeros_like(t), np.zeros(len(t), int), 0.1, "delta")
    notes: list[str] = []
    gain = _steady_gain(log, 0.5, (0.03, 0.003, {"withheld": True}), 0.32, (1.0, 0.0), notes)
    assert gain["rows"] == [] and "no single K" in gain["note"] and any("no single K" in n for n in notes)
    kept = _steady_gain(log, 0.5, (0.03, 0.003, {"identifiable": True}), 0.32, (1.0, 0.0), [])
    assert len(kept["rows"]) == 12 and kept["rows"][0]["gain"] == pytest.approx(
        kept["rows"][0]["speed"] / (0.32 + 0.03 * kept["rows"][0]["speed"] ** 2))


class _Fit:
    """A fit's values and an interval of 10 % per stiffness (the FitResult calls _understeer reads)."""

    values = {"c_f": 5.0, "c_r": 10.0}

    def interval_of(self, grad):
        return math.hypot(grad["c_f"] * 0.5, grad["c_r"] * 1.0)

    def at_bound(self, p):
        return None


def test_a_characteristic_speed_set_by_an_unidentified_k_is_not_identified():
    class P:
        name = "c_f"
    *_, K, char = _understeer(_Fit(), [P()], 0.32, alike="one speed (1.3-1.3 m/s)")
    assert not K["identifiable"] and not char["identifiable"] and "one speed" in char["note"]
    *_, K, char = _understeer(_Fit(), [P()], 0.32)
    assert K["identifiable"] and char["identifiable"]
    assert char["value"] == pytest.approx(math.sqrt(0.32 / ((1 / 5 - 1 / 10) / 9.81)))


def test_the_diagnosis_carries_a_friction_known_only_as_at_least(monkeypatch):
    """identify's friction on its class's top reaches the diagnosis flagged, not as a plain number."""
    import pandas as pd

    from agrobot.diagnosis import pipeline
    from agrobot.diagnosis.baseline import baseline_from_study

    study = Study.load(ROOT_STUDIES / "f1tenth.toml")
    rep = report(withheld=False, at_least=True) | {
        "held_out_fit": {"value": 90.0}, "final_model": "tyre_saturation", "input": "delta", "delay": _q(0.05)}
    rep["tyre_saturation"] |= {"why_not": [], "held_out_gain": 0.1}
    monkeypatch.setattr(pipeline, "identify_driving", lambda *a, **k: rep)
    monkeypatch.setattr(pipeline, "require_causal", lambda *a, **k: None)
    got = pipeline.identified_vehicle(pd.DataFrame({"t": [0.0, 1.0]}), "gen.csv", study, baseline_from_study(study))
    assert got["identified"]["tyre_saturation"]["friction_at_least"] is True
