"""A value on a bound is never concluded: the baseline refit widens a parameter that ended on its
prior range's edge to the physical limit, and says which parameters it moved and which ended on a
bound. The truth: a tractor log (harness.truth_tractor) whose rear stiffness the paper's baseline
puts on the prior edge of its scale (the yaw rate hardly fixes C_r: widened, it is still not pinned,
and is held at the study's)."""
from __future__ import annotations

from agrobot.diagnosis.baseline import baseline_from_study, refit_statement, refit_summary
from agrobot.diagnosis.candidates import Replay, fit_baseline, uncertain
from agrobot.diagnosis.catalogue import UNCERTAIN
from agrobot.orchestrator.study import Study
from harness.hidden_effects import BASELINES
from harness.truth_tractor import make_log


def test_the_baseline_refit_widens_a_prior_edge_and_says_what_it_moved_and_what_ended_on_a_bound():
    frame, _ = make_log(1000, "steering_offset", duration=120.0)
    baseline = baseline_from_study(Study.load(BASELINES["tractor"]))
    replay = Replay(frame, baseline)
    fit, _ = fit_baseline(replay)
    params = list(dict.fromkeys(p for s in replay.stages for p in uncertain(replay, s)))
    rows = {r["name"]: r for r in refit_summary(baseline.values, fit.values, params, replay.held_uncertain)}
    prior = {p.name: p for ps in UNCERTAIN.values() for p in ps}
    assert set(rows) == {p.name for p in params} | set(replay.held_uncertain) and any(r["moved"] for r in rows.values())
    for name, r in rows.items():
        span = prior[name].upper - prior[name].lower
        on_prior_edge = min(abs(r["value"] - prior[name].lower), abs(r["value"] - prior[name].upper)) <= 5e-3 * span
        # a value on the prior range's edge was searched again on the range widened to the limit
        assert not on_prior_edge or r["bounds"] != [prior[name].lower, prior[name].upper], r
    # C_r ended on its prior edge, was searched again out to its limit, and there the steering offset's
    # log does not pin it (its 95 % interval wider than half its value): held at the study's, and said
    assert "cornering_rear_scale" in replay.widened_uncertain
    assert rows["cornering_rear_scale"]["value"] == baseline.values["cornering_rear_scale"]
    text = refit_statement(list(rows.values()))
    assert "cornering_rear_scale (95 % interval" in text and "held at the study's (not pinned by the log)" in text
    assert ("ended on a bound" in text) == any(r["at_bound"] for r in rows.values())


def test_the_baseline_refit_does_not_take_up_a_steering_gain_as_tyres():
    """The tractor's wheels turn 1.27 x the reading (harness.diagnosis_classes, seed 1001): freed, the
    rear cornering scale takes the gain up as oversteer (0.12, an understeer gradient no vehicle of
    the class has); held at the study's it stays near the truth's (C_r 83 kN/rad against the study's
    90), and the refit says why."""
    from harness.diagnosis_classes import baseline_study, class_log

    frame, truth = class_log("steering_map_gain", 1001, "tractor", 120.0)
    baseline = baseline_from_study(Study.load(baseline_study("tractor", None)))
    replay = Replay(frame, baseline)
    fit, _ = fit_baseline(replay)
    truth_scale = truth["C_r"] / baseline.tractor.C_r
    assert abs(fit.values["cornering_rear_scale"] / truth_scale - 1.0) < 0.25
    assert replay.held_uncertain["cornering_rear_scale"].kind == "implausible for the vehicle"


def test_the_refits_holds_carry_their_rule_and_numbers_as_data():
    """A hold whose numbers hold a colon is grouped by its rule, not by where a string splits, and
    the summary is JSON as diagnosis.json writes it."""
    import json

    from agrobot.diagnosis.baseline import Hold

    why = {"cornering_front_scale": Hold("implausible for the vehicle", "at 0.5 and 2, K 30 deg/g: a steering map"),
           "cornering_rear_scale": Hold("implausible for the vehicle", "at 0.5 and 2, K 30 deg/g: a steering map")}
    rows = refit_summary({k: 1.0 for k in why}, {k: 1.0 for k in why}, [], why)
    json.dumps(rows)
    assert rows[0]["held"] == {"kind": "implausible for the vehicle", "detail": "at 0.5 and 2, K 30 deg/g: a steering map"}
    assert ("held at the study's (implausible for the vehicle: at 0.5 and 2, K 30 deg/g: a steering map): "
            "cornering_front_scale, cornering_rear_scale") in refit_statement(rows)
