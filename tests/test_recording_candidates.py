"""A recording finding is a candidate like any effect: the import audit's 'the yaw rate answers
the steering before it' (response_leads_input) on a log whose steering channels are stamped late
(harness.truth_tractor's steering_clock, drawn there, 0.75 s on this seed) is not a refusal in
the diagnosis but the start of its steering_clock fit, and once the fit explains it the finding is
resolved; identify, which has no such candidate, still refuses the log and the diagnosis says why."""
from __future__ import annotations

import pytest

from harness.hidden_effects import BASELINES, recovered
from agrobot.diagnosis.pipeline import diagnose, explained_findings
from harness.truth_tractor import make_log


def test_a_lead_is_explained_only_by_a_clock_at_least_that_late():
    def lead():
        return [{"kind": "response_leads_input", "value": 0.68, "resolved": False, "meaning": "m"}]

    clock = [{"id": "steering_clock", "parameters": {"steering_clock": 0.75}}]
    (f,) = explained_findings(lead(), clock)
    assert f["resolved"] and "stamped 0.750 s late" in f["meaning"] and "+0.070 s of it the vehicle's own" in f["meaning"]
    clock[0]["parameters"]["steering_clock"] = 0.4              # too early to explain a 0.68 s lead
    assert not explained_findings(lead(), clock)[0]["resolved"]
    assert not explained_findings(lead(), [])[0]["resolved"]


@pytest.mark.slow
def test_steering_stamped_late_is_named_as_the_clock_it_is(tmp_path):
    frame, truth = make_log(1000, "steering_clock")
    assert truth["steering_clock"] > 0.5                      # late enough that the response leads its input
    log = tmp_path / "late_steering.parquet"
    frame.to_parquet(log)
    result = diagnose(log, None, BASELINES["tractor"])
    assert result["verdict"] == "steering_clock" and result["verdict_status"] == "conclusive", result.get("reason")
    (e,) = [e for e in result["effects"] if e["id"] == "steering_clock"]
    est, true, tol = recovered("steering_clock", truth, e["parameters"])
    assert abs(est - true) <= tol, (est, true)
    (lead,) = [f for f in result["audit"] if f["kind"] == "response_leads_input"]
    assert lead["resolved"] and "explained by the diagnosis" in lead["meaning"]
    assert any("started at" in line and "response_leads_input" in line for line in result["selection_trace"])
    why = result["identified_vehicle"]["why_not"]
    assert "BEFORE the steering" in why
