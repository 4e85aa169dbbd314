"""A tyre fit on its bounds in the verdict: a friction on its upper bound is said as "at least" that
bound and the saturation stands; a shape on its bound leaves the saturation undecided; tyre
saturation identify keeps only in the hardest turns is left to the diagnosis's own gate.

Independent truth: the effect dicts are built as the pipeline builds them (pipeline.finding_json),
with the bound flags a fitted value on the edge of its searched range carries."""
from __future__ import annotations

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


def test_a_friction_on_the_class_top_is_said_as_at_least_and_the_saturation_stands():
    top = SCALE_CAR.friction_range[1]
    e = tyre(top, 1.4, friction_edge="upper")
    e["fitted"]["tyre_friction"]["bounds"] = list(SCALE_CAR.friction_range)
    v = verdict(e, [e])              # the pipeline lists a primary parameter on its bound as unidentifiable
    assert v["id"] == "tyre_saturation" and v["status"] == "conclusive", v
    assert f"tyre_friction [-] at least {top:.4g}" in v["statement"]


def test_a_friction_on_the_class_top_is_not_widened_beyond_it():
    """The selection widens a parameter on its prior bound to its physical limit, but not a friction
    on the class's top (there the verdict says "at least"); the shape on its bound has no wider limit."""
    from agrobot.diagnosis.effects.tyre_saturation import TyreSaturation
    from agrobot.diagnosis.selection import _bounded, widened

    effect = TyreSaturation()
    top = SCALE_CAR.friction_range[1]
    effect.parameters = (_bounded(effect.parameters[0], SCALE_CAR.friction_range, (0.05, 3.0)), effect.parameters[1])
    assert widened(effect, {"tyre_friction": top, "tyre_shape": 1.3}) is None
    low = widened(effect, {"tyre_friction": SCALE_CAR.friction_range[0], "tyre_shape": 1.3})
    assert low is not None and low.parameters[0].lower == 0.05


def test_without_the_at_least_rule_a_friction_on_its_limit_is_not_identifiable():
    e = tyre(3.0, 1.4, friction_edge="upper", eid="toy_tyre")       # an effect that does not read it as at least
    v = conclude([e], None, [e], [], [], SCALE_CAR, 0.32, 0.15, 3.0)
    assert v["status"] == "not identifiable"
    low = tyre(0.05, 1.4, friction_edge="lower")                     # at least is for the upper bound only
    assert verdict(low, [low])["status"] == "not identifiable"


def test_a_shape_on_its_bound_leaves_the_saturation_undecided_and_says_why():
    e = tyre(0.83, 0.5, shape_edge="lower")
    v = verdict(e, [])
    assert v["id"] == "tyre_saturation" and v["status"] == "cannot decide", v
    assert "tyre_shape ended on its lower bound 0.5" in v["statement"]
    assert "tyre_shape [-] not identifiable" in v["statement"] and "peak" in v["statement"]
    assert verdict(tyre(0.83, 1.3), [])["status"] == "conclusive"


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
