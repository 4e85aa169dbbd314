"""The whole field, worked as farmers work it: coverage of the whole field (every piece of a split
inner field, the headland passes driven first or last), section control and its as-applied map,
obstacles, the route order with the user's start and end, and bad input refused naming it.

Areas are checked against a second method: a 0.5 m raster of the field, a cell worked where a
working pose of the path (sampled every 0.25 m) lies within half the working width of it."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.spatial import cKDTree
from shapely.geometry import Point, Polygon

from agrobot.components.field_route import settings_of
from agrobot.fields import read_fields
from agrobot.fields.field import Field
from agrobot.fields.obstacles import circle, with_obstacles
from agrobot.fields.planner import HEADLAND, SWATH, TRANSIT, TURN, Settings, plan
from agrobot.fields.planner.applied import applied_outside, as_applied, crossings
from agrobot.fields.planner.curves import connect
from agrobot.fields.planner.optimise import move_costs
from agrobot.fields.planner.sections import SectionControl, SectionLayout
from agrobot.fields.planner.turns import length_of
from agrobot.fields.planner.types import WORKING
from agrobot.orchestrator.cli import main

PARCEL = "tests/data/fields2cover_data/test.json"     # Fields2Cover's test parcel, 3.6 ha


def parcel() -> Field:
    return read_fields(PARCEL)[0]


@pytest.fixture(scope="module")
def parcel_plan():
    return plan(parcel(), Settings())


def raster_cover(p, field: Polygon, cell: float = 0.5) -> float:
    """Share of ``field`` within w/2 of a working pose (second method: no strips, no union)."""
    from shapely import contains_xy

    w = p.settings.working_width
    poses = []
    for k in np.flatnonzero(np.isin(p.path.kinds, WORKING)):
        a = p.path.starts[k]
        b = p.path.starts[k + 1] if k + 1 < len(p.path) else p.path.length
        r = p.path.evaluate(np.append(np.arange(a, b, 0.25), b))
        poses.append(np.column_stack([r["x"], r["y"]]))
    tree = cKDTree(np.vstack(poses))
    minx, miny, maxx, maxy = field.bounds
    gx, gy = np.meshgrid(np.arange(minx, maxx, cell) + cell / 2, np.arange(miny, maxy, cell) + cell / 2)
    inside = contains_xy(field, gx, gy)
    d, _ = tree.query(np.column_stack([gx[inside], gy[inside]]))
    return float(np.mean(d <= 0.5 * w + 0.02))


def dumbbell() -> Field:
    """Two 100 x 80 m blocks joined by a 40 m long, 24 m wide neck: the inner field falls apart."""
    pts = [(0, 0), (100, 0), (100, 28), (140, 28), (140, 0), (240, 0), (240, 80), (140, 80), (140, 52), (100, 52),
           (100, 80), (0, 80)]
    return Field("dumbbell", Polygon(pts), None, "generated", "local metres")


# --- every square metre -------------------------------------------------------------------------------------
def test_the_whole_field_of_a_real_parcel_is_covered_and_never_crossed(parcel_plan):
    p = parcel_plan
    a = as_applied(p)
    assert a.field_coverage_share >= 0.99
    assert a.field_coverage_share == pytest.approx(a.covered / p.field.boundary.area)
    assert a.field_coverage_share == pytest.approx(raster_cover(p, p.field.boundary), abs=0.004)
    assert crossings(p) == 0
    assert applied_outside(a, p.field.boundary) < 1.0         # m^2: the implement keeps inside the field


@pytest.mark.slow
def test_every_piece_of_a_split_inner_field_is_worked_and_joined_inside_the_field():
    f = dumbbell()
    p = plan(f, Settings(order="skip"))
    assert len(p.pieces) == 2
    worked = {c.piece for c in p.cells}
    assert worked == {0, 1}
    for k, piece in enumerate(p.pieces):                       # each piece's swaths fill it
        inside = [sw for c in p.cells if c.piece == k for sw in c.swaths]
        assert sum(sw.length for sw in inside) * p.settings.spacing >= 0.9 * piece.area
    a = as_applied(p)
    largest_only = p.pieces[0].area / f.boundary.area
    assert a.field_coverage_share > largest_only + 0.1
    assert a.field_coverage_share == pytest.approx(raster_cover(p, f.boundary), abs=0.005)
    assert crossings(p) == 0


@pytest.mark.parametrize("order", ["first", "last"])
def test_the_headland_passes_are_driven_first_or_last(order):
    f = parcel()
    p = plan(f, Settings(headland_order=order, working_width=6.0, leftover_passes=False))   # (those come after all)
    kinds = [seg.kind for seg in p.path.segments if seg.kind in WORKING]
    first_swath, last_swath = kinds.index(SWATH), len(kinds) - 1 - kinds[::-1].index(SWATH)
    if order == "first":
        assert kinds[0] == HEADLAND and HEADLAND not in kinds[first_swath:]
    else:
        assert kinds[-1] == HEADLAND and HEADLAND not in kinds[:last_swath]
    assert kinds.count(HEADLAND) >= p.headland_passes
    assert settings_of({"headland_order": order}).headland_order == order      # the route component's parameter
    assert crossings(p) == 0


# --- section control -------------------------------------------------------------------------------------
def test_sections_reduce_the_overlap_and_keep_the_covered_area(parcel_plan):
    p = parcel_plan
    whole, sections = as_applied(p), as_applied(p, 6)
    assert sections.overlap < 0.75 * whole.overlap
    assert sections.covered == pytest.approx(whole.covered, rel=0.003)
    # what the overlap cannot go below: adjacent passes overlap by design (Settings.overlap) along every swath
    designed = p.settings.overlap * sum(seg.length for seg in p.path.segments if seg.kind == SWATH)
    assert sections.overlap >= 0.5 * designed


def test_a_section_switches_off_over_worked_ground_after_its_latency_or_at_the_edge_when_it_looks_ahead():
    field = Polygon([(0, -10), (60, -10), (60, 10), (0, 10)])
    layout = SectionLayout(3.0, 3)
    v, dt, off_delay, on_delay = 2.0, 0.01, 0.4, 0.3
    edge = 30.0
    for look_ahead, expected in ((False, edge + v * off_delay), (True, edge)):
        control = SectionControl(field, layout, on_delay=on_delay, off_delay=off_delay, look_ahead=look_ahead)
        control.map.paint(*np.meshgrid(np.arange(edge, 60, 0.05), np.arange(-2.0, 2.0, 0.05)), -1e6)  # worked
        off_at = on_at = None
        for k in range(int(50 / (v * dt))):
            x = 1.0 + v * k * dt
            state = control.step(k * dt, x, x, 0.0, 0.0, v, True)
            if on_at is None and state.all():
                on_at = x
            if on_at is not None and off_at is None and not state.any():
                off_at = x
        assert on_at == pytest.approx(1.0 + v * on_delay, abs=0.05)      # from rest: the latency either way
        assert off_at == pytest.approx(expected, abs=0.15)


@pytest.mark.slow     # 5 CPU s
def test_the_as_applied_map_is_written_with_the_plan(tmp_path, capsys):
    out = tmp_path / "plan"
    assert main(["plan", PARCEL, "--width", "6", "--sections", "4", "--leftover-passes", "off", "--out", str(out)]) == 0
    assert "note: leftover passes off" in capsys.readouterr().out          # the choice printed, and its option
    assert any(n.startswith("leftover passes off") for n in json.loads((out / "plan.json").read_text())["notes"])
    summary = json.loads((out / "plan.json").read_text())["as_applied"]
    doc = json.loads((out / "as_applied.geojson").read_text())
    covered = [f for f in doc["features"] if f["properties"]["kind"] == "covered"]
    assert len(covered) == 1 and covered[0]["properties"]["area_m2"] == pytest.approx(summary["covered_ha"] * 1e4, rel=1e-3)
    assert summary["sections"] == 4 and summary["boundary_crossings"] == 0
    assert (out / "as_applied.png").stat().st_size > 10_000


# --- obstacles ---------------------------------------------------------------------------------------------
@pytest.mark.slow     # 5 CPU s
def test_an_obstacle_is_never_crossed_by_the_tractor_or_the_implement():
    pole = circle("pole", 30.0, 40.0, 3.0, "test")
    f = with_obstacles(parcel(), [pole])
    p = plan(f, Settings(working_width=6.0))
    s = np.arange(0.0, p.path.length, 0.25)
    r = p.path.evaluate(s)
    centre = Point(30.0, 40.0)
    nearest = min(centre.distance(Point(x, y)) for x, y in zip(r["x"], r["y"]))
    assert nearest >= 3.0 + p.settings.half_width                # the tractor's side keeps off it
    for sections in (0, 4):
        a = as_applied(p, sections)
        assert sum(st.intersection(pole.shape).area for st in a.strips) < 0.01
    assert crossings(p) == 0


# --- bad input ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("args, named", [
    (["--obstacle", "5000,0,2"], "lies outside the field"),
    (["--obstacle", "30,40,-1"], "radius = -1 m"),
    (["--sections", "100"], "sections = 100"),
    (["--sections", "-3"], "sections = -3"),
    (["--start", "5000,0"], "start_point = (5000, 0) m"),
])
def test_bad_whole_field_input_exits_2_naming_the_value_and_writes_nothing(tmp_path, capsys, args, named):
    out = tmp_path / "out"
    code = main(["plan", PARCEL, "--width", "6", "--max-swaths", "3", "--out", str(out), *args])
    err = capsys.readouterr().err
    assert code == 2 and named in err and "Traceback" not in err
    assert not out.exists()


# --- the route -------------------------------------------------------------------------------------------
def test_the_closed_form_turn_estimates_agree_with_the_turns_solved():
    limits = Settings().limits
    rng = np.random.default_rng(3)
    a = np.zeros((40, 3))
    b = np.column_stack([rng.uniform(20, 60, 40), rng.uniform(-40, 40, 40), rng.uniform(-math.pi, math.pi, 40)])
    estimate = np.diag(move_costs(a, b, limits))
    solved = np.array([length_of(connect(a[i], b[i], limits)) for i in range(40)])
    assert np.allclose(estimate, solved, rtol=0.02, atol=0.05)


def test_the_optimised_order_drives_no_more_than_the_patterns_and_starts_and_ends_where_asked():
    f = parcel()
    common = dict(working_width=6.0, headland_work=False, headland_passes=4)     # one headland for every order
    idle = {}
    for order in ("boustrophedon", "skip", "optimised"):
        d = plan(f, Settings(order=order, **common)).path.distances()
        idle[order] = d[TURN] + d[TRANSIT]
    assert idle["optimised"] <= min(idle["boustrophedon"], idle["skip"]) + 1e-6
    start, end = (-60.0, 20.0), (80.0, -40.0)
    p = plan(f, Settings(order="optimised", start_point=start, end_point=end, **common))
    x0, y0, _ = p.path.start_pose()
    last = p.path.segments[-1].points[-1]
    assert (x0, y0) == pytest.approx(start, abs=1e-6)
    assert tuple(last[:2]) == pytest.approx(end, abs=0.01)
    assert crossings(p) == 0


# --- what is left ----------------------------------------------------------------------------------------------
def test_what_a_plan_leaves_is_named_with_its_area_and_why(parcel_plan):
    """The parcel's leftovers, named piece by piece, add up to the field a second method finds
    unworked (the 0.5 m raster of the working poses); the sharp corners are named as corners a turn
    cannot reach (their centres outside the workable field)."""
    from agrobot.fields.planner.leftovers import leftovers

    p = parcel_plan
    named, slivers = leftovers(p, as_applied(p).shape)
    field = p.field.boundary
    unworked = (1.0 - raster_cover(p, field)) * field.area
    assert sum(x.area for x in named) + slivers == pytest.approx(unworked, rel=0.25, abs=10.0)
    assert named and all(x.why and x.area >= 1.0 and x.width > 0 for x in named)
    corners = [x for x in named if x.kind == "corner"]
    assert corners
    assert not any(p.workable.contains(Point(x.centroid)) for x in corners)


def test_the_neck_between_two_pieces_is_named_with_its_area_and_the_pass_that_would_work_it():
    """Two 60 x 50 m halves joined by a neck 14 m wide and 20 m long, 2 headland passes of 3 m: the
    inner field's neck is 2 m wide (14 - 2 x 6); with the headland band and the two halves' inner
    rectangles worked, what is left is the neck's band, 32 x 2 m (known by hand), between the pieces,
    narrower than one pass, whose medial axis (y = 25, 32 m) keeps the tractor inside the field."""
    from types import SimpleNamespace

    from agrobot.fields.planner.leftovers import leftovers

    field = Polygon([(0, 0), (60, 0), (60, 18), (80, 18), (80, 0), (140, 0), (140, 50), (80, 50), (80, 32), (60, 32),
                     (60, 50), (0, 50)])
    w, n = 3.0, 2
    pieces = Polygon([(6, 6), (54, 6), (54, 44), (6, 44)]).union(Polygon([(86, 6), (134, 6), (134, 44), (86, 44)]))
    band = field.difference(field.buffer(-n * w, join_style="mitre"))
    p = SimpleNamespace(field=SimpleNamespace(boundary=field), settings=Settings(working_width=w), inner=pieces,
                        headland_passes=n, workable=field)
    named, slivers = leftovers(p, band.union(pieces))
    assert slivers == pytest.approx(0.0, abs=1e-6)
    (neck,) = named
    assert neck.kind == "between pieces"
    assert neck.area == pytest.approx(32 * 2, rel=1e-6)
    assert neck.width == pytest.approx(2.0, abs=0.05)
    assert neck.pass_m == pytest.approx(32.0, abs=0.1)
    assert "medial axis" in neck.why and neck.centroid == pytest.approx((70.0, 25.0))
