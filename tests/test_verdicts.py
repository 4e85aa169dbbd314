"""Verdicts an engineer would sign, checked piece by piece against independent equations and
generated cases (the end-to-end cases on simulated truths: tests/test_verdicts_truths.py)."""
from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from agrobot.diagnosis import verdict as verdict_module
from agrobot.diagnosis.catalogue import CATALOGUE, EFFECT_IDS
from agrobot.diagnosis.effect import Effect, Parameter
from agrobot.diagnosis.unexplained import signature
from agrobot.diagnosis.verdict import audit_findings, conclude, judge_values
from agrobot.estimation import Z95
from agrobot.identification.comparisons import course_bias, pair
from agrobot.identification.vehicle import Vehicle

CAR = Vehicle.from_table({"class": "car", "wheelbase": 2.97, "length": 4.9, "width": 1.9})


def effect(eid, **params):
    return {"id": eid, "parameters": params, "parameters_display": {f"{k} [SI]": v for k, v in params.items()},
            "hypothesis": "h", "not_identifiable": None}


def test_a_parameter_on_its_prior_bound_widens_to_its_limit_and_only_there_is_final():
    p = Parameter("k", "1", 0.1, -0.35, 0.8, limit=(-1.0, 2.0))
    w = p.widened(0.8)
    assert (w.lower, w.upper) == (-0.35, 2.0)
    assert p.widened(-0.35).lower == -1.0
    assert p.widened(0.3) is None                   # inside: nothing to widen
    assert w.widened(2.0) is None                   # on the physical limit: not identifiable, no further


def test_a_lever_arm_outside_the_outline_is_not_a_mounting_and_the_verdict_says_what_it_suggests():
    """The racecar case: 3.69 m forward on a 4.9 m car measured from the rear axle is inside; 6 m is
    not. At 20 m/s the lag that moves the track as far is (6 - l_r) / 20 s."""
    inside = effect("antenna_lever_arm", antenna_forward=3.69, antenna_left=0.0)
    outside = effect("antenna_lever_arm", antenna_forward=6.0, antenna_left=0.0)
    assert judge_values(inside, CAR, 2.97, 1.5, 20.0) == []
    notes = judge_values(outside, CAR, 2.97, 1.5, 20.0)
    assert len(notes) == 1 and "outside its outline" in notes[0]
    assert f"{(6.0 - 1.5) / 20:.2g} s" in notes[0]
    v = conclude([outside], None, [], [], [], CAR, 2.97, 1.5, 20.0)
    assert v["id"] == "antenna_lever_arm" and v["status"] == "implausible"
    assert "clock offset" in v["statement"]


@pytest.mark.parametrize("eid, params, words", [
    ("actuator_delay", {"command_delay": 0.9}, "longer than a human reaction"),
    ("tyre_saturation", {"tyre_friction": 1.8, "tyre_shape": 1.3}, "above what tyres give"),
    ("yaw_rate_bias", {"yaw_rate_bias": math.radians(3.0)}, "beyond what a gyro of this class"),
    ("gyro_scale", {"gyro_scale": 57.3}, "a unit or a channel is wrong"),
    ("steering_gain", {"steering_gain": 1 / 16.0}, "a steering ratio (1:16)"),
    ("steering_gain", {"steering_gain": math.pi / 180}, "in degrees where radians"),
    ("steering_gain", {"steering_gain": 2.5}, "another quantity"),
    ("steering_gain", {"steering_gain": 0.664}, "the log's steering (command or reading)"),
])
def test_values_no_vehicle_of_the_class_has_are_named(eid, params, words):
    notes = judge_values(effect(eid, **params), CAR, 2.97, 1.5, 20.0)
    assert any(words in n for n in notes), notes


@pytest.mark.parametrize("eid, params", [("actuator_delay", {"command_delay": 0.2}),
                                         ("tyre_saturation", {"tyre_friction": 1.0, "tyre_shape": 1.3}),
                                         ("yaw_rate_bias", {"yaw_rate_bias": math.radians(0.5)}),
                                         ("steering_gain", {"steering_gain": 1.25})])
def test_values_the_vehicle_can_have_pass(eid, params):
    assert judge_values(effect(eid, **params), CAR, 2.97, 1.5, 20.0) == []


def test_the_verdict_names_no_effect_id_each_effect_judges_itself():
    """verdict.py names no effect: no constant, comparison, branch or lookup on an effect's id; the
    rules, and the audit findings that can imitate an effect, are the effects' own."""
    tree = ast.parse(Path(verdict_module.__file__).read_text())
    named = [(n.lineno, n.value) for n in ast.walk(tree) if isinstance(n, ast.Constant) and n.value in EFFECT_IDS]
    assert not named, named


# what each unresolved audit finding kind keeps from being concluded, as the verdict's table held it
# when it lived in verdict.py (a recording's clock imitates delays and latencies, a scale a bias or a tyre)
IMITATED_BEFORE = {
    "clock_offset": {"gyro_filter", "actuator_delay", "gps_latency", "position_reference", "antenna_lever_arm", "steering_rate_limit"},
    "response_leads_input": {"gyro_filter", "actuator_delay", "gps_latency", "position_reference", "steering_rate_limit"},
    "stamp_vs_receive": {"gyro_filter", "actuator_delay", "gps_latency", "position_reference"},
    "gap_bridged": {"actuator_delay", "gps_latency", "steering_rate_limit"},
    "scale_disagreement": {"gyro_scale", "speed_scale", "yaw_rate_bias", "tyre_saturation",
                           "speed_dependent_cornering", "steering_ratio_curve"},
    "opposite_sign": {"gyro_scale", "speed_scale", "yaw_rate_bias", "steering_ratio_curve"},
    "position_is_estimate": set(),
    "mislabelled_channel": {"*"},
}


@pytest.mark.parametrize("kind", IMITATED_BEFORE)
def test_each_effect_names_the_audit_findings_that_imitate_it(kind):
    found = audit_findings({"audit": [{"kind": kind}]})[0]["imitates"]
    assert set(found) == IMITATED_BEFORE[kind] and len(found) == len(set(found))


class _Wobble(Effect):
    """A toy effect with its own rule, known to no catalogue file."""
    id = "toy_wobble"
    subsystem = "toy"
    stages = ("yaw",)
    parameters = (Parameter("wobble", "m", 0.1, 0.0, 5.0),)
    starts = ((0.0,),)
    threshold = hypothesis = experiment = "toy"

    def plausibility(self, values, ctx):
        if values["wobble"] > 0.1 * ctx.vehicle.width:
            return [f"a wobble of {values['wobble']:g} m is over a tenth of the {ctx.vehicle.width:g} m width"]
        return []


def test_an_effect_is_judged_by_its_own_rule_without_the_verdict_knowing_it():
    catalogue = CATALOGUE + (_Wobble(),)
    assert judge_values(effect("toy_wobble", wobble=0.1), CAR, 2.97, 1.5, 20.0, catalogue) == []
    v = conclude([effect("toy_wobble", wobble=0.5)], None, [], [], [], CAR, 2.97, 1.5, 20.0, catalogue=catalogue)
    assert v["status"] == "implausible"
    assert v["statement"].endswith("a wobble of 0.5 m is over a tenth of the 1.9 m width")
    # a catalogue effect's rule replaced by a subclass's: the subclass's rule judges
    lenient = type("Lenient", (type(next(e for e in CATALOGUE if e.id == "actuator_delay")),),
                   {"plausibility": lambda self, values, ctx: []})()
    assert judge_values(effect("actuator_delay", command_delay=0.9), CAR, 2.97, 1.5, 20.0, (lenient,)) == []
    # an effect without a rule of its own passes whatever it fitted; an id no catalogue holds is not judged
    assert judge_values(effect("speed_dependent_cornering", cornering_speed_slope=1.9), CAR, 2.97, 1.5, 20.0) == []
    assert judge_values(effect("toy_wobble", wobble=9.0), CAR, 2.97, 1.5, 20.0) == []


def test_an_unresolved_audit_finding_keeps_the_effects_it_imitates_from_being_concluded():
    attrs = {"audit": [{"kind": "clock_offset", "channels": ["delta_cmd"], "value": 0.9, "interval": [0.85, 0.95],
                        "unit": "s", "meaning": "steering reports reach the recorder late", "resolved": False},
                       {"kind": "gap_bridged", "channels": ["x"], "value": 1.0, "unit": "s", "resolved": True}]}
    audit = audit_findings(attrs)
    assert [f["kind"] for f in audit] == ["clock_offset", "gap_bridged"]
    delay = effect("actuator_delay", command_delay=0.9)
    offset = effect("steering_offset", steer_angle_offset=0.02)
    v = conclude([delay, offset], None, [], [], audit, CAR, 2.97, 1.5, 20.0)
    assert v["status"] == "not concluded" and "clock_offset" in v["statement"]
    assert delay["blocked_by"] == ["clock_offset"] and offset["blocked_by"] == []
    assert any("unresolved recording finding clock_offset 0.9 s" in b for b in v["bullets"])
    # resolved: concluded (and judged: 0.9 s is still longer than a human reaction)
    audit[0]["resolved"] = True
    assert conclude([effect("actuator_delay", command_delay=0.9)], None, [], [], audit, CAR, 2.97, 1.5,
                    20.0)["status"] == "implausible"
    assert audit_findings({}) == [] and audit_findings({"audit": ["junk", {"no": "kind"}]}) == []


def test_an_effect_unknown_to_the_verdict_is_blocked_by_the_finding_it_names():
    """A toy effect that a clock offset can imitate is not concluded while one stands, without the
    verdict knowing it."""
    toy = type("ClockedWobble", (_Wobble,), {"imitated_by": ("clock_offset",)})()
    catalogue = CATALOGUE + (toy,)
    audit = audit_findings({"audit": [{"kind": "clock_offset", "value": 0.3, "unit": "s"}]}, catalogue)
    assert "toy_wobble" in audit[0]["imitates"]
    v = conclude([effect("toy_wobble", wobble=0.05)], None, [], [], audit, CAR, 2.97, 1.5, 20.0, catalogue=catalogue)
    assert v["status"] == "not concluded" and "clock_offset" in v["statement"]
    # the same finding read with the catalogue whose effects do not name it: concluded
    assert conclude([effect("toy_wobble", wobble=0.05)], None, [], [], audit_findings(
        {"audit": [{"kind": "clock_offset"}]}), CAR, 2.97, 1.5, 20.0, catalogue=catalogue)["status"] == "conclusive"


def test_an_effect_on_its_physical_limit_is_the_verdict_not_none():
    e = effect("speed_dependent_cornering", cornering_speed_slope=2.0)
    e["not_identifiable"] = "cornering_speed_slope ended on its upper bound 2 s/m"
    v = conclude([e], None, [e], [], [], CAR, 2.97, 1.5, 20.0)
    assert v["id"] == "speed_dependent_cornering" and v["status"] == "not identifiable"
    assert conclude([], None, [], [], [], CAR, 2.97, 1.5, 20.0)["id"] == "none"


def test_two_estimates_disagree_only_when_their_intervals_do_not_overlap():
    agree = pair("K", "rad/(m/s2)", ("dynamic", 0.0027, 0.0004), ("steady", 0.0020, 0.0004), "x")
    differ = pair("K", "rad/(m/s2)", ("dynamic", 0.0027, 0.0002), ("steady", 0.0011, 0.0002), "structure")
    assert agree["agree"] and agree["suggests"] == ""
    assert not differ["agree"] and differ["suggests"] == "structure"
    assert differ["estimates"]["steady"]["interval"] == pytest.approx([0.0011 - Z95 * 0.0002, 0.0011 + Z95 * 0.0002])


def test_the_gyro_bias_from_the_gnss_course_of_a_circle():
    """A circle of radius 20 m at 4 m/s turns at 0.2 rad/s; a gyro reading 0.2 + 0.004 rad/s has a
    bias of 0.004 rad/s whatever the noise."""
    rng = np.random.default_rng(3)
    t = np.arange(0, 200, 0.05)
    psi = 0.2 * t
    x, y = 20 * np.sin(psi) + 0.01 * rng.standard_normal(len(t)), -20 * np.cos(psi) + 0.01 * rng.standard_normal(len(t))
    r = 0.2 + 0.004 + 0.005 * rng.standard_normal(len(t))
    b, sd = course_bias(t, x, y, r, np.full(len(t), 4.0), min_speed=0.5)
    assert b == pytest.approx(0.004, abs=5e-4)
    assert sd < 1e-3


@pytest.mark.parametrize("kind, sig, form", [("static_map", "lateral_acceleration", "lateral"),
                                             ("input_map", "delta", "angle"), ("fir", "delta", "lag"),
                                             ("static_map", "v", "speed"), ("input_gains", "v, yaw_rate", "gains"),
                                             ("static_map", "t", "drift")])
def test_an_unexplained_misfit_is_read_in_physical_terms_with_the_run_that_would_tell(kind, sig, form):
    s = signature({"kind": kind, "signal": sig})
    assert s["form"] == form and s["physical"] and s["experiment"]


def test_the_logs_wheelbase_from_its_kinematics_names_the_study_that_fits():
    """A 0.32 m car turning kinematically: r = v tan(delta) / L."""
    from agrobot.diagnosis.study_fit import log_vehicle, study_check

    rng = np.random.default_rng(1)
    t = np.arange(0, 60, 0.05)
    v = 2.0 + 0.5 * np.sin(0.1 * t)
    delta = 0.15 * np.sin(0.5 * t)
    frame = pd.DataFrame({"t": t, "v": v, "delta": delta,
                          "yaw_rate": v * np.tan(delta) / 0.32 + 0.002 * rng.standard_normal(len(t))})
    assert log_vehicle(frame)["wheelbase"] == pytest.approx(0.32, rel=0.03)
    mine, warning = study_check(frame, 1.4, "figure8.toml")
    assert "f1tenth.toml" in warning and "1.4 m" in warning
    assert study_check(frame, 0.33, "f1tenth.toml")[1] is None


def test_a_value_on_its_bound_counts_as_a_point():
    """A delay fitted on its bound 0 (no std) against a cross-correlation of -0.78 +- 0.02 s: they
    disagree (the response leads its input)."""
    c = pair("delay", "s", ("fit", 0.0, float("nan")), ("xcorr", -0.78, 0.01), "clock")
    assert not c["agree"] and c["estimates"]["fit"]["interval"] == [0.0, 0.0]


def test_a_position_that_is_an_estimate_renames_a_lever_arm_and_blocks_nothing():
    audit = audit_findings({"audit": [{"kind": "position_is_estimate", "channels": ["x", "y"],
                                       "meaning": "particle-filter pose", "resolved": False}]})
    v = conclude([effect("antenna_lever_arm", antenna_forward=0.28, antenna_left=-0.12)], None, [], [], audit,
                 Vehicle.from_table({"class": "scale_car", "length": 0.55, "width": 0.3}), 0.32, 0.21, 1.5)
    assert v["status"] == "conclusive"
    assert any("the point the estimate refers to" in b for b in v["bullets"])


class _Replay:
    """A replay whose yaw residual is known: 0.1 rad/s inside [10, 20] s, 0.3 rad/s elsewhere."""
    stages = ("yaw",)

    def residual_series(self, stage, values):
        t = np.arange(0.0, 40.0, 0.1)
        return t, np.where((t >= 10) & (t <= 20), 0.1, 0.3)


def _identified(rms, **more):
    return {"final_model": "linear", "tyre_saturation": None, "tyre_saturation_why_not": [],
            "parameters": {"steer_gain": {"value": 0.7, "interval": [0.65, 0.75], "unit": "1"},
                           "steer_offset": {"value": 0.01, "interval": [0.0, 0.02], "unit": "rad"}},
            "held_out_yaw": {"windows": [(10.0, 20.0)], "seconds": 10.0, "rms": rms}, **more}


def test_both_models_of_the_vehicle_are_scored_on_the_same_unseen_stretches_and_a_better_one_is_named():
    from agrobot.diagnosis.pipeline import agreement, same_stretches

    class Sel:
        first_step = ()

    better = _identified(0.05)
    same_stretches(better, _Replay(), {})
    assert better["held_out_yaw"]["diagnosis_rms"] == pytest.approx(0.1)     # only the window's samples
    (bullet,) = agreement(better, [], Sel())
    assert "better described by identify's model" in bullet and "steer_gain 0.7," in bullet
    assert f"steer_offset {math.degrees(0.01):.3g} deg)" in bullet                 # degrees at the edge
    assert f"{math.degrees(0.05):.3g} deg/s" in bullet and f"{math.degrees(0.1):.3g} deg/s" in bullet
    poorer = _identified(0.2)
    same_stretches(poorer, _Replay(), {})
    (bullet,) = agreement(poorer, [], Sel())
    assert "beyond what identify's single-track model holds" in bullet
    alike = _identified(0.098, tyre_saturation={"friction": 0.5, "held_out_gain": 0.2})
    same_stretches(alike, _Replay(), {})
    (bullet,) = agreement(alike, [], Sel())
    assert bullet.startswith("identify keeps tyre saturation") and "fit alike" in bullet
    assert agreement(_identified(0.098), [], Sel()) == []              # no diagnosis score: nothing claimed
    assert agreement(better, [], Sel(), floor=0.08) == []                # both within 1.5 x the floor: alike
