"""What the route leaves, worked by passes of their own (fields.planner.leftover_passes) or named
with why (fields.planner.leftovers).

Coverage is checked against a second method: the trailed implement simulated behind the planned
path (its axle a drawbar L behind a hitch c behind the tractor's rear axle, pulled along: the
discrete tractrix), lowered while the ground under it is on a working segment, its width rastered
on a 0.25 m grid; and against the closed form of a rounded corner, (R + d)^2 (1 - pi/4) left beyond
a pass whose strip's outer edge rounds a right angle at R + d."""
from __future__ import annotations

import math
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest
from shapely import contains_xy
from shapely.geometry import Polygon

from agrobot.fields.field import Field
from agrobot.fields.planner import Settings, plan
from agrobot.fields.planner.applied import as_applied, crossings
from agrobot.fields.planner.leftover_passes import axis_passes
from agrobot.fields.planner.leftovers import leftovers
from agrobot.fields.planner.types import SWATH, WORKING

CORNER = 1.0 - math.pi / 4          # what a right angle rounded at radius r leaves: r^2 (1 - pi/4)


WIDE = Settings(working_width=6.0)  # three headland passes: a quick plan


def rectangle() -> Field:
    return Field("rectangle", Polygon([(0, 0), (90, 0), (90, 60), (0, 60)]), None, "generated", "local metres")


@pytest.fixture(scope="module")
def plans():
    f = rectangle()
    return plan(f, replace(WIDE, leftover_passes=False)), plan(f, WIDE)


def implement_cover(p, field: Polygon, cell: float = 0.25) -> float:
    """Share of ``field`` the trailed implement works: simulated behind the path every 5 cm, working
    where the path position it has reached (c + L behind the tractor) is on a swath or headland pass."""
    s = p.settings
    d = np.arange(0.0, p.path.length, 0.05)
    r = p.path.evaluate(d)
    x, y, h = r["x"], r["y"], r["heading"]
    hx, hy = x - s.hitch_offset * np.cos(h), y - s.hitch_offset * np.sin(h)
    qx, qy = np.empty_like(hx), np.empty_like(hy)
    qx[0], qy[0] = hx[0] - s.drawbar * math.cos(h[0]), hy[0] - s.drawbar * math.sin(h[0])
    for i in range(1, len(d)):                                  # the drawbar pulled towards the hitch, length L
        vx, vy = hx[i] - qx[i - 1], hy[i] - qy[i - 1]
        n = math.hypot(vx, vy)
        qx[i], qy[i] = hx[i] - s.drawbar * vx / n, hy[i] - s.drawbar * vy / n
    lowered = np.isin(p.path.evaluate(d - s.hitch_offset - s.drawbar)["kind"], WORKING) & (d >= s.hitch_offset + s.drawbar)
    heading = np.arctan2(hy - qy, hx - qx)
    minx, miny, maxx, maxy = field.bounds
    gx, gy = np.meshgrid(np.arange(minx, maxx, cell) + cell / 2, np.arange(miny, maxy, cell) + cell / 2)
    inside = contains_xy(field, gx, gy)
    worked = np.zeros(gx.shape, bool)
    ix = ((qx[lowered] - minx) / cell).astype(int)
    iy = ((qy[lowered] - miny) / cell).astype(int)
    across = np.arange(-0.5 * s.working_width, 0.5 * s.working_width + 1e-9, 0.5 * cell)
    for t in across:                                             # the implement's width, across its heading
        cx = qx[lowered] - t * np.sin(heading[lowered])
        cy = qy[lowered] + t * np.cos(heading[lowered])
        ix, iy = np.floor((cx - minx) / cell).astype(int), np.floor((cy - miny) / cell).astype(int)
        ok = (ix >= 0) & (iy >= 0) & (ix < gx.shape[1]) & (iy < gx.shape[0])
        worked[iy[ok], ix[ok]] = True
    return float(worked[inside].mean())


def test_the_corners_are_worked_by_passes_of_their_own_and_only_their_tips_are_left(plans):
    """A 90 x 60 m field, a 6 m implement: with parallel headland corners the outer pass's strip rounds each corner at
    R + (n - 1/2) w and leaves (R + (n - 1/2) w)^2 (1 - pi/4) of it; the corner passes at the turn
    radius R leave about (R + w/2)^2 (1 - pi/4). The implement simulated behind the path finds that."""
    off, on = plans
    f = rectangle().boundary
    s, n = on.settings, on.headland_passes
    assert off.headland_passes == n
    R, w = s.turn_radius, s.working_width
    left_off = (1.0 - implement_cover(off, f)) * f.area
    left_on = (1.0 - implement_cover(on, f)) * f.area
    assert left_off == pytest.approx(4 * (R + (n - 0.5) * w) ** 2 * CORNER, rel=0.2)
    assert left_on <= 2.0 * 4 * (R + 0.5 * w) ** 2 * CORNER                      # the tips a forward pass cannot reach
    assert left_on < 0.25 * left_off
    assert 1.0 - left_on / f.area >= 0.99
    assert crossings(on) == 0
    # the passes are driven after the rest, as swaths of the route, and the plan says so
    extra = on.leftover_passes
    assert len(on.swaths) == len(off.swaths) and off.leftover_passes == ()
    first = max(sw.index for sw in off.swaths)
    assert len(extra) >= 4 and all(sw.index > first for sw in extra)
    last = [seg for seg in on.path.segments if seg.kind == SWATH][-len(extra):]
    assert [seg.index for seg in last] == [sw.line for sw in extra]
    assert any("leftover passes (--leftover-passes off" in note for note in on.notes)
    assert any("leftover passes off" in note for note in off.notes)


def test_what_the_corner_passes_leave_is_named_as_corners_with_why(plans):
    _, on = plans
    a = as_applied(on)
    named, slivers = leftovers(on, a.shape)
    f = rectangle().boundary
    unworked = (1.0 - implement_cover(on, f)) * f.area
    assert named and all(x.kind == "corner" and x.why for x in named)
    assert sum(x.area for x in named) + slivers == pytest.approx(unworked, rel=0.5, abs=10.0)
    corners = [(0, 0), (90, 0), (90, 60), (0, 60)]
    for x in named:                                               # each at a corner of the field
        assert min(math.hypot(x.centroid[0] - cx, x.centroid[1] - cy) for cx, cy in corners) < R_TIP(on)


def R_TIP(p) -> float:
    """How far from its corner a tip left beyond a pass at R can reach: the outer edge's arc at
    R + w/2 touches the sides R + w/2 from the corner."""
    return p.settings.turn_radius + 0.5 * p.settings.working_width + 1.0


def test_a_neck_left_between_pieces_gets_passes_along_its_medial_axis_and_a_too_wide_one_none():
    """The neck of two 60 x 50 m halves (hand-built, as in test_whole_field), 14 m wide: a band
    32 x 2 m at y = 25 is worked by one straight pass along y = 25, its run-in and run-out (8.1 m)
    inside the field; a band 5 m across by two, w - overlap apart about y = 25 (2.95 m: 5 <= 3 + 2.95);
    a band 13 m across (over 3 + 3 x 2.95, four passes) gets none."""
    field = Polygon([(0, 0), (60, 0), (60, 18), (80, 18), (80, 0), (140, 0), (140, 50), (80, 50), (80, 32), (60, 32),
                     (60, 50), (0, 50)])
    s = Settings()
    inside = field.buffer(-s.half_width)
    owner = SimpleNamespace(settings=s)

    def band(half: float) -> Polygon:
        return Polygon([(54, 25 - half), (86, 25 - half), (86, 25 + half), (54, 25 + half)])

    (line,), rest = axis_passes(owner, band(1.0), inside)
    assert sorted(line[:, 0]) == pytest.approx([54.0, 86.0], abs=0.05)
    assert line[:, 1] == pytest.approx([25.0, 25.0], abs=0.05)
    assert rest.area < 0.05 * band(1.0).area
    two, rest = axis_passes(owner, band(2.5), inside)
    assert sorted(float(p[0, 1]) for p in two) == pytest.approx([25 - 1.475, 25 + 1.475], abs=0.05)
    assert rest.area < 0.05 * band(2.5).area
    none, rest = axis_passes(owner, band(6.5), inside)
    assert none == [] and rest.area == pytest.approx(band(6.5).area)


def test_a_mission_takes_the_leftover_passes_from_its_route_parameter():
    """field.leftover_passes in a study reaches the planner (0: named only); its default is the
    planner's."""
    from agrobot.components.field_route import FieldRoute, settings_of

    default = next(v.start for v in FieldRoute("field", {}).variables if v.name == "leftover_passes")
    assert bool(default) is Settings().leftover_passes is True
    assert settings_of({"leftover_passes": 0.0}).leftover_passes is False
    assert settings_of({"leftover_passes": 1.0}).leftover_passes is True


def test_a_leftover_passes_value_other_than_0_or_1_exits_2_naming_it(cli, tmp_path):
    res = cli("run", "studies/field_plot_mounted.toml", "--out", str(tmp_path / "out"),
              "--set", "field.leftover_passes=2", "--set", "study.stop_time=1")
    assert res.returncode == 2 and "leftover_passes = 2" in res.stderr and "Traceback" not in res.stderr, res.stderr
    assert not (tmp_path / "out").exists()
