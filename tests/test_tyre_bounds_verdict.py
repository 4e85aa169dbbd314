"""A tyre fit on its bounds in the verdict: a friction on its upper limit is said as "at least" that
limit and judged as such, not "not identifiable"; a shape on its bound leaves the saturation
standing but none of its values concluded; tyre saturation identify keeps only in the hardest turns is left to the diagnosis's own
gate; tyres whose force limit is below the log's turns are not its tyres; a generated car whose friction is beyond its class's top is kept by diagnose because identify
keeps it "at least" that top, and is not kept without it.

Independent truth: the effect dicts are built as the pipeline builds them (pipeline.finding_json),
with the bound flags a fitted value on the edge of its searched range carries; the generated car is
the F1TENTH study simulated with tyres of friction 2.2 (shape 1.6) at 2, 3 and 4 m/s and full
steering (|a_y| to 16 m/s2; a scale car's friction range ends at 1.8)."""
from __future__ import annotations

import pandas as pd
import pytest

from agrobot.diagnosis.selection import Selector
from agrobot.diagnosis.verdict import conclude
from agrobot.identification.vehicle import Vehicle

SCALE_CAR = Vehicle.from_table({"class": "scale_car", "wheelbase": 0.32, "length": 0.55, "width": 0.3})


def tyre(friction, shape, friction_edge=None, shape_edge=None, eid="tyre_saturation"):
    """A judged tyre_saturation as pipeline.finding_json writes it (bounds: the class's friction
    limit 3.0, the shape's 0.5-1.95)."""
    fitted = {"tyre_friction": {"value": friction, "bounds": [0.05, 3.0], "unit": "1", "at_bound": friction_edge,
                                "secondary": False},
              "tyre_shape": {"value": shape, "bounds": [0.5, 1.95], "unit": "1", "at_bound": shape_edge,
                             "secondary": True}}
    edge = f"tyre_friction ended on its {friction_edge} bound" if friction_edge else None
    return {"id": eid, "parameters": {"tyre_friction": friction, "tyre_shape": shape},
            "parameters_display": {"tyre_friction [-]": friction, "tyre_shape [-]": shape},
            "fitted": fitted, "hypothesis": "the tyres saturate", "not_identifiable": edge}


def verdict(e, unidentifiable):
    return conclude([e], None, unidentifiable, [], [], SCALE_CAR, 0.32, 0.15, 3.0)


def test_a_friction_on_its_physical_limit_is_said_as_at_least_and_judged_as_that():
    e = tyre(3.0, 1.4, friction_edge="upper")
    v = verdict(e, [e])              # the pipeline lists a primary parameter on its bound as unidentifiable
    assert v["id"] == "tyre_saturation" and v["status"] != "not identifiable", v
    assert "tyre_friction [-] at least 3" in v["statement"]
    # at least 3 is more than tyres give on a scale car's ground (its class's top): the rule says what instead
    assert v["status"] == "implausible" and "above what tyres give" in v["statement"]


def test_without_the_at_least_rule_a_friction_on_its_limit_is_not_identifiable():
    e = tyre(3.0, 1.4, friction_edge="upper", eid="toy_tyre")       # an effect that does not read it as at least
    v = conclude([e], None, [e], [], [], SCALE_CAR, 0.32, 0.15, 3.0)
    assert v["status"] == "not identifiable"
    low = tyre(0.05, 1.4, friction_edge="lower")                     # at least is for the upper bound only
    assert verdict(low, [low])["status"] == "not identifiable"


def test_a_shape_on_its_bound_leaves_the_saturation_standing_but_no_value_concluded():
    e = tyre(0.83, 0.5, shape_edge="lower")
    v = verdict(e, [])
    assert v["id"] == "tyre_saturation" and v["status"] == "conclusive", v
    assert "its values are not concluded: tyre_shape ended on its lower bound 0.5" in v["statement"]
    assert "tyre_shape [-] not identifiable" in v["statement"] and "peak" in v["statement"]
    assert "tyre_friction [-] 0.83 (fitted with tyre_shape on its bound)" in v["statement"]
    free = verdict(tyre(0.83, 1.3), [])
    assert free["status"] == "conclusive" and "not concluded" not in free["statement"]
    assert "tyre_friction [-] 0.83, tyre_shape [-] 1.3" in free["statement"]


def test_tyres_that_cannot_carry_the_logs_turns_are_not_its_tyres():
    """A curve without a peak (shape 0.5) reaches mu sin(pi / 4) of the load: with mu 0.83, 5.76 m/s2,
    below a log turning at 7.4 m/s2 (99th percentile of |v r|) by more than the 10 % allowed; mu 1.0
    at shape 1.3 (a peak: the whole mu) carries 9.81 m/s2."""
    import math

    from agrobot.diagnosis.effects.tyre_saturation import LATERAL_KEY, TyreSaturation

    log = {LATERAL_KEY: 7.4}
    (why,) = TyreSaturation().contradicts({"tyre_friction": 0.83, "tyre_shape": 0.5}, log)
    assert f"at most {0.83 * 9.81 * math.sin(math.pi / 4):.3g} m/s2" in why and "7.4 m/s2" in why
    assert TyreSaturation().contradicts({"tyre_friction": 1.0, "tyre_shape": 1.3}, log) == []
    assert TyreSaturation().contradicts({"tyre_friction": 0.83, "tyre_shape": 0.5}, {LATERAL_KEY: 6.2}) == []


def selector(gain, min_gain=0.05):
    sel = Selector.__new__(Selector)
    sel.min_gain, sel.gate_note, sel._first = min_gain, "", {}
    sel.saturation = {"friction": 1.8, "friction_at_least": True, "shape": 0.4, "held_out_gain": gain}
    return sel


def test_saturation_identify_keeps_on_every_held_out_segment_is_tried_from_its_bound():
    sel = selector(0.36)
    said = sel.identify_keeps()
    assert said.startswith("tyre_saturation tried") and "friction at least 1.8" in said
    assert sel._first["tyre_saturation"] == {"tyre_friction": 1.8, "tyre_shape": 0.5}     # clipped into its range


def test_saturation_identify_keeps_only_in_the_hardest_turns_is_left_to_the_gate():
    sel = selector(-0.001)
    assert sel.identify_keeps() is None and sel._first == {}
    assert "-0.1 % < 5 %" in sel.gate_note and "gate decides" in sel.gate_note


@pytest.mark.slow
def test_a_car_past_its_tyres_bend_beyond_the_class_friction_keeps_saturation_through_identify(tmp_path):
    """About a minute: the log's own gate alone does not try saturation here (the baseline's shortfall at
    the top |a_y| is under 5 % of the yaw rate); identify's "at least 1.8", won on all its held-out
    segments, makes it a candidate, and the diagnosis keeps it with a friction at or beyond 1.8."""
    from agrobot.diagnosis.pipeline import diagnosis
    from agrobot.orchestrator.runner import simulate
    from agrobot.orchestrator.study import Study
    from tests.vehicle_logs import ROOT_STUDIES

    study = ROOT_STUDIES / "f1tenth.toml"
    st = Study.load(study).with_values({"study.stop_time": 120.0, "plan.duration": 120.0, "plan.speeds": [2.0, 3.0, 4.0],
                                        "plan.steer_scale": 1.0, "car.tyre_friction": 2.2, "car.tyre_shape": 1.6})
    rec, _ = simulate(st)
    f = rec.to_frame().iloc[::4].reset_index(drop=True)
    path = tmp_path / "friction_2.2.parquet"
    pd.DataFrame({"t": f["t"], "delta": f["steering.steer_angle_measured"], "v": f["plan.speed_cmd"],
                  "yaw_rate": f["gyro.yaw_rate_measured"]}).to_parquet(path)
    res, _ = diagnosis(path, study, plots=False, workers=1)
    kept = res["identified_vehicle"]["identified"]["tyre_saturation"]
    assert kept["friction_at_least"] and kept["friction"] == pytest.approx(1.8)
    assert res["selection_trace"][0].startswith("tyre_saturation tried: identify keeps it")
    tyres = next(e for e in res["effects"] if e["id"] == "tyre_saturation")
    assert 1.8 <= tyres["parameters"]["tyre_friction"] <= 2.6, tyres["parameters"]
    alone, _ = diagnosis(path, study, plots=False, workers=1, identify=False)
    assert "tyre_saturation" not in {e["id"] for e in alone["effects"]}, alone["selection_trace"][0]
