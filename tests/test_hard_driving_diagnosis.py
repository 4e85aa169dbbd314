"""A car driven hard, beyond its tyres' linear range: a friction fitted beside a shape on its bound
is not judged (no "lateral acceleration overstated" claim on a value not concluded), and a
steering map read there competes with the tyres' saturation.

Independent truth: the judged tyre effect is built as pipeline.finding_json writes it, with the
shape on its lower bound (the flag a fitted value on the edge of its range carries) and a friction
whose force (mu x the shape's share) is above a car's class top 1.3; the same friction with a free
shape is judged, as before."""
from __future__ import annotations

from agrobot.diagnosis.verdict import conclude
from agrobot.identification.vehicle import Vehicle
from tests.test_tyre_bounds_verdict import tyre

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
