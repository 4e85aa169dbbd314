"""Swaths parallel to a curved guidance line: spacing, inside the workable area, curvature within
the turn radius (judged by shapely's distances and circles through three points, not by the
planner's own curvature), the swath-frame projection of the mission metrics, and a short field
mission on curved swaths."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from shapely.geometry import LineString, Point, Polygon

from agrobot.fields.field import Field, FieldError, GuidanceLine
from agrobot.fields.planner.curved_swaths import curved_lines
from agrobot.fields.planner.pipeline import plan
from agrobot.fields.planner.settings import Settings

ROOT = Path(__file__).resolve().parents[1]


def arc_field(radius: float = 120.0) -> Field:
    """A 160 x 100 m field with an arc guidance line (centre above the field, concave up)."""
    th = np.linspace(math.radians(215), math.radians(325), 45)
    guide = np.c_[80 + radius * np.cos(th), 30 + radius + radius * np.sin(th)]
    return Field("arc", Polygon([(0, 0), (160, 0), (160, 100), (0, 100)]), None, "test", "local",
                 [GuidanceLine("arc", guide)])


def circle_curvature(xy: np.ndarray, base: float = 2.0) -> np.ndarray:
    """1 / the radius of the circle through points ``base`` metres apart along the line (4 A / abc)."""
    line = LineString(xy)
    s = np.arange(base, line.length - base, 0.5)
    if not len(s):
        return np.zeros(1)
    a, b, c = (np.array([line.interpolate(v).coords[0] for v in s + d]) for d in (-base, 0.0, base))
    area2 = np.abs((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))
    sides = np.hypot(*(b - a).T) * np.hypot(*(c - b).T) * np.hypot(*(c - a).T)
    return 2 * area2 / np.maximum(sides, 1e-12)


def test_curved_swaths_keep_their_spacing_stay_workable_and_bend_no_tighter_than_the_turn_radius():
    settings = Settings(swath_pattern="curved")
    p = plan(arc_field(), settings)
    lines: dict[int, list] = {}
    for cell in p.cells:
        for sw in cell.swaths:
            lines.setdefault(sw.line, []).append(LineString(sw.points))
    assert len(lines) >= 25
    checked = 0
    for k in sorted(lines):
        if k + 1 not in lines:
            continue
        for one in lines[k]:
            for s in np.arange(0.0, one.length, 1.0):
                q = one.interpolate(s)
                for other in lines[k + 1]:
                    foot = other.project(q)
                    if 1.0 < foot < other.length - 1.0:     # the perpendicular lands on the other swath
                        assert other.distance(q) == pytest.approx(settings.spacing, abs=0.02)
                        checked += 1
    assert checked > 1000
    workable = p.workable.buffer(1e-6)
    for sw in p.swaths:
        assert workable.contains(LineString(sw.points))
        assert circle_curvature(sw.points).max() <= 1.0 / settings.turn_radius


def test_offsets_past_the_centre_of_a_tight_curve_are_cut_where_they_bend_too_much():
    """A 15 m arc in a 60 m field: offsets towards its centre reach radii under R = 4 m and fold
    into cusps; what is kept bends no tighter than R and does not cross itself."""
    th = np.linspace(math.radians(200), math.radians(340), 60)
    guide = np.c_[30 + 15 * np.cos(th), 20 + 15 * np.sin(th)]
    region = Polygon([(0, 0), (60, 0), (60, 40), (0, 40)])
    lines, along = curved_lines(region, guide, 2.95, 3.0, 4.0)
    swaths = [sw for line in lines for sw in line]
    assert len(swaths) > 10
    near = region.buffer(1.5, join_style="mitre", mitre_limit=3.0).buffer(1e-6)   # the strip reaches w/2 out
    for sw in swaths:
        g = LineString(sw.points)
        assert g.is_simple and near.contains(g)
        if g.length > 4.5:
            assert circle_curvature(sw.points).max() <= 1 / 4.0
    # the offsets beyond the centre are cut in two there (a cusp), not kept whole
    centre = Point(30, 20)
    assert any(len(line) == 2 and all(centre.distance(LineString(sw.points)) < 10 for sw in line) for line in lines)
    # along the guidance line: increasing along every swath (they are oriented the same way)
    for sw in swaths:
        assert along(sw.end) >= along(sw.start)


def test_the_swath_frame_projection_agrees_with_shapely_on_a_polyline():
    from agrobot.analysis.field_tracks import station

    rng = np.random.default_rng(3)
    th = np.linspace(-0.5, 1.2, 40)
    line = np.c_[50 * np.cos(th), 50 * np.sin(th)]
    pts = line[5:35] + rng.normal(0, 0.5, (30, 2))
    along, across = station(line, pts[:, 0], pts[:, 1])
    g = LineString(line)
    for (x, y), a, c in zip(pts, along, across):
        assert a == pytest.approx(g.project(Point(x, y)), abs=1e-6)
        assert abs(c) == pytest.approx(g.distance(Point(x, y)), abs=1e-6)
        assert math.copysign(1, c) == (1 if math.hypot(x, y) < 50 else -1)     # left of a CCW arc: inside
    # a straight swath: its infinite line beyond the ends
    a, c = station(np.array([[0.0, 0.0], [10.0, 0.0]]), np.array([-3.0, 14.0]), np.array([1.0, -2.0]))
    assert a.tolist() == [-3.0, 14.0] and c.tolist() == [1.0, -2.0]


def test_a_curved_pattern_needs_a_guidance_line_and_a_known_name():
    f = arc_field()
    f.lines = []
    with pytest.raises(FieldError, match="swath_pattern = 'curved': the field has no guidance line"):
        plan(f, Settings(swath_pattern="curved"))
    with pytest.raises(FieldError, match="swath_pattern = 'wavy': expected straight or curved"):
        plan(arc_field(), Settings(swath_pattern="wavy"))


def test_a_field_mission_on_curved_swaths_keeps_the_implement_within_3_cm():
    from agrobot.orchestrator.runner import run_study
    from agrobot.orchestrator.study import Study

    study = Study.load(ROOT / "studies" / "field_coverage.toml", [
        "field.path=fields/curved_field.geojson", "field.swath_pattern=curved", "field.max_swaths=2",
        "field.headland_work=0", "field.order=boustrophedon", "study.stop_time=200"])
    m = run_study(study, None, plots=False).metrics
    assert m["swath_time_s"] > 10
    assert m["implement_xte_p95_m"] <= 0.03


def test_pass_to_pass_gaps_are_taken_only_where_both_passes_were_driven():
    """A line split by a hole: its two parts' tracks are not interpolated across the hole (a curved
    neighbour would be measured against the chord)."""
    from agrobot.analysis.field_tracks import _gap

    one_along = np.r_[np.arange(0.0, 20.0, 0.1), np.arange(40.0, 60.0, 0.1)]
    one = (one_along, np.where(one_along < 30, 0.0, 1.0))
    other = (np.arange(0.0, 60.0, 0.1), np.full(600, 3.0))
    gaps = _gap(one, other)
    assert len(gaps) == 40                  # 0..19 and 40..59: none in the hole
    assert set(np.round(gaps, 9)) == {3.0, 2.0}
