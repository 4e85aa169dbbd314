"""A car driven hard, beyond its tyres' linear range: a friction fitted beside a shape on its bound
is not judged (no "lateral acceleration overstated" claim on a value not concluded), and a
steering map read there competes with the tyres' saturation.

Independent truth: the judged tyre effect is built as pipeline.finding_json writes it, with the
shape on its lower bound (the flag a fitted value on the edge of its range carries) and a friction
whose force (mu x the shape's share) is above a car's class top 1.3; the same friction with a free
shape is judged, as before."""
from __future__ import annotations

import pytest

from agrobot.diagnosis.baseline import baseline_from_study
from agrobot.diagnosis.candidates import Replay
from agrobot.diagnosis.selection import Selector
from agrobot.diagnosis.verdict import conclude
from agrobot.identification.vehicle import Vehicle
from agrobot.orchestrator.study import Study
from harness.hidden_effects import BASELINES
from harness.truth_tractor import make_log
from tests.test_tyre_bounds_verdict import tyre

MAPS = ("steering_gain", "steering_ratio_curve")

CAR = Vehicle.from_table({"class": "car", "wheelbase": 2.4, "length": 4.1, "width": 1.7})


def test_a_friction_beside_a_shape_on_its_bound_is_not_judged_implausible():
    """mu 2.0 at shape 0.5 (on its bound) reaches 2.0 sin(pi / 4) = 1.41 > 1.3: not concluded, so no
    claim that a scale is overstated; mu 2.0 at shape 1.3 (free, its whole mu) is judged implausible."""
    held = tyre(2.0, 0.5, shape_edge="lower")
    v = conclude([held], None, [], [], [], CAR, 2.4, 1.07, 40.0)
    assert "overstated" not in v["statement"] and v["status"] == "conclusive", v
    assert "not concluded" in v["statement"] and "fitted with tyre_shape on its bound" in v["statement"]
    free = tyre(2.0, 1.3)
    v = conclude([free], None, [], [], [], CAR, 2.4, 1.07, 40.0)
    assert v["status"] == "implausible" and "overstated" in v["statement"], v


@pytest.mark.slow
def test_a_car_driven_into_its_tyres_saturation_gets_no_steering_map_verdict():
    """The passenger car driven hard (harness.truth_tractor "car_hard": 15-35 m/s, |a_y| to 10 m/s2)
    with tyres that saturate (F = C alpha / (1 + |alpha| / alpha_s), alpha_s 6 deg) and its road-wheel
    angle measured (no command): no steering map is planted, so none the selection keeps may stand
    alone: each is tied with tyre_saturation as "cannot decide". Identify's keeping the saturation
    (the pipeline runs it first) is given as a tyre of friction 1, shape 1.3 to start from."""
    frame, _ = make_log(1101, "tyre_saturation", duration=120.0, vehicle="car_hard", values={"alpha_s": 0.105})
    frame = frame.drop(columns=["x", "y", "delta_cmd"])
    selector = Selector(Replay(frame, baseline_from_study(Study.load(BASELINES["car"]))), 0.05, screen=False,
                        saturation={"friction": 1.0, "shape": 1.3, "held_out_gain": 0.2})
    selector.catalogue = [e for e in selector.catalogue if e.id in MAPS + ("tyre_saturation",)]
    sel = selector.run()
    maps = {f.effect.id for f in sel.effects} & set(MAPS)
    undecided = {t["effects"][0] for t in sel.inconclusive if t.get("undecided") and t["effects"][1] == "tyre_saturation"}
    assert maps <= undecided, (maps, sel.inconclusive, sel.trace)
