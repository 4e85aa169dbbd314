"""Field missions. Coverage plans on every real field (copies in tests/data) (sections of
the large ones), continuous-curvature turns within the limits, the trailed implement's kinematics
against closed-form steady states, the whole guidance stack covering a real plot, the farmers'
metrics against a second computation, bad fields refused by name, sweeps over speed and angle."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from shapely import contains_xy
from shapely.geometry import LineString, Polygon
from shapely.ops import unary_union

from agrobot.components.field_route import FieldRoute, settings_of
from agrobot.components.trailed_implement import TrailedImplement
from agrobot.fields import FieldError, read_fields
from agrobot.fields.planner import HEADLAND, SWATH, TURN, Settings, plan
from agrobot.fields.planner.curves import Limits, connect, integrate
from agrobot.fields.planner.decomposition import cells as _cells
from agrobot.fields.planner.route_order import skip_order as _skip_order
from agrobot.fields.planner.swaths import swath_lines as _swath_lines
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.study import Study
from tests.commands import cli as _cli

ROOT = Path(__file__).resolve().parents[1]
REAL = ROOT / "tests" / "data"             # copies of the published real sets, with their licences (tests/data/README.md)
STUDIES = ROOT / "studies"
IAM_CSV = REAL / "iam_field_open_autonomous_tractor" / "datasets" / "iam_field" / "field_boundaries.csv"
SMALL_IMPLEMENT = dict(working_width=2.0, turn_radius=2.5, drawbar=0.0, settle=2.0)   # for the 0.15 ha plots


# every file of real fields; the settings that suit its fields; the fields it must refuse, and why
REAL_FIELD_FILES = {
    "fields2cover_data/test1.xml": ({}, {}),
    "fields2cover_data/Envelope.xml": ({}, {}),
    "fields2cover_data/envelope1.xml": ({}, {}),
    "fields2cover_data/test.json": ({}, {}),
    "fields2cover_data/test_2_cell.json": ({}, {}),
    # rings that touch themselves: repaired (fields.shapes.repaired_parts), then each strip too narrow to plan
    "fields2cover_data/strips.geojson": ({}, {"strips_1": "narrower than two working widths",
                                              "strips_2": "narrower than two working widths",
                                              "strips_3": "narrower than two working widths"}),
    "fields2cover_data/test_ring.json": ({}, {"Ring": "narrower than two working widths"}),
    "iam_field_open_autonomous_tractor/datasets/iam_field/field_boundaries.csv": (SMALL_IMPLEMENT, {}),
    "isoxml_dev4ag_timelogs/PARTFIELDS_TASKDATA.XML": ({}, {}),
    "isoxml_dev4ag_timelogs/TASKDATA.XML": ({}, {}),
}


def _check_route(p, settings: Settings) -> None:
    """What any route must be: continuous, inside the field by the tractor's half width, turns
    within the curvature and sharpness limits, swaths at the driving angle."""
    r = p.path.grid(0, p.path.grid_size())              # the route on the trackers' grid
    steps = np.hypot(np.diff(r["x"]), np.diff(r["y"]))
    assert steps.max() < 0.1 + 1e-6
    inside = p.field.boundary.buffer(-settings.half_width + 1e-6)
    assert contains_xy(inside, r["x"], r["y"]).all()
    limits = Limits.of(settings.turn_radius, settings.wheelbase, settings.steer_rate, settings.turn_speed)
    for seg in p.path.segments:
        if seg.kind == TURN and len(seg.points) > 2:
            k = seg.points[:, 3]
            assert np.abs(k).max() <= limits.kappa_max * (1 + 1e-9)
            ds = np.hypot(*np.diff(seg.points[:, :2], axis=0).T)
            ok = ds > 1e-6
            assert (np.abs(np.diff(k))[ok] / ds[ok]).max() <= limits.sigma * 1.01
    for a, b in ((sw.start, sw.end) for sw in p.swaths):
        heading = math.atan2(b[1] - a[1], b[0] - a[0])
        assert abs(math.sin(heading - p.angle)) < 1e-6


@pytest.mark.parametrize("name", sorted(REAL_FIELD_FILES))
def test_every_real_field_is_planned_or_refused_by_name(name):
    """Each field of the file: a section of 4 swaths (and its headland and turns) planned within
    the limits, or the expected refusal naming the file, the field and the reason."""
    overrides, refused = REAL_FIELD_FILES[name]
    settings = Settings(**overrides, max_swaths=4)
    fields = read_fields(REAL / name)
    assert fields
    for field in fields:
        if field.name in refused:
            with pytest.raises(FieldError) as err:
                plan(field, settings)
            assert refused[field.name] in str(err.value) and repr(field.name) in str(err.value)
            assert name.split("/")[-1] in str(err.value)
            continue
        p = plan(field, settings)
        assert 1 <= len(p.swaths) <= 4
        _check_route(p, settings)


def _planned_cover(p) -> tuple[float, float]:
    """(covered share, overlap share) of the workable area by the plan's own working strips."""
    w = p.settings.working_width
    strips = [LineString(s.points[:, :2]).buffer(0.5 * w, cap_style="flat") for s in p.path.segments
              if s.kind in (SWATH, HEADLAND)]
    union = unary_union(strips)
    covered = union.intersection(p.workable).area
    swept = sum(s.intersection(p.workable).area for s in strips)
    return covered / p.workable.area, (swept - covered) / p.workable.area


@pytest.mark.parametrize("file,name,overrides", [
    ("fields2cover_data/test.json", "test parcel", {}),
    ("isoxml_dev4ag_timelogs/TASKDATA.XML", " YmB4QHFgW", {}),              # a bay: several cells
    ("iam_field_open_autonomous_tractor/datasets/iam_field/field_boundaries.csv", "2024-paper-1-ro2-b-test",
     SMALL_IMPLEMENT),
])
def test_a_whole_plan_covers_the_workable_field(file, name, overrides):
    field = next(f for f in read_fields(REAL / file) if f.name == name)
    settings = Settings(**overrides, leftover_passes=False)     # the route's own cover (the leftovers': test_leftover_passes)
    p = plan(field, settings)
    _check_route(p, settings)
    covered, overlap = _planned_cover(p)
    assert covered >= 0.995 and overlap <= 0.05, (covered, overlap)
    assert p.workable.area <= field.boundary.area
    # the headland's outer pass is w/2 from the boundary and its corners round at R + (n - 1) w
    assert p.field.boundary.area - p.workable.area < field.boundary.length * 1e-3 + 400


@pytest.mark.slow
def test_a_field_with_a_bay_and_a_hole_is_split_into_cells_and_covered():
    """A U-shaped field (a bay cut into its top) with a pond: the lines crossing the bay or the
    pond give two swaths each, the planner splits them into cells, each swath is driven once,
    the whole stays inside the field (round the pond too) and covers the workable area."""
    from agrobot.fields.field import Field

    outer = [(0, 0), (300, 0), (300, 200), (190, 200), (190, 100), (110, 100), (110, 200), (0, 200)]
    pond = [(50, 40), (80, 40), (80, 55), (50, 55)]
    field = Field("bay and pond", Polygon(outer, [pond]), None, "synthetic", "local metres")
    settings = Settings(driving_angle=0.0, working_width=6.0)       # east-west: across the bay and the pond
    p = plan(field, settings)
    _check_route(p, settings)
    lines = _swath_lines(p.inner, p.angle, settings.working_width - settings.overlap, settings.working_width)
    cells = _cells(lines, p.angle)
    assert len(cells) >= 5 and f"in {len(cells)} cells" in p.order_how        # below, round the pond, two arms
    assert sum(len(c.swaths) for c in cells) == sum(len(segs) for segs in lines) == len(p.swaths)
    covered, overlap = _planned_cover(p)
    assert covered >= 0.99 and overlap <= 0.05, (covered, overlap)


def _min_width(poly: Polygon) -> float:
    """Rotating calipers on the convex hull: the smallest over hull edges of the farthest vertex."""
    hull = np.asarray(poly.convex_hull.exterior.coords)[:-1]
    best = math.inf
    for i in range(len(hull)):
        a, b = hull[i], hull[(i + 1) % len(hull)]
        n = np.array([-(b - a)[1], (b - a)[0]]) / np.hypot(*(b - a))
        best = min(best, float(np.max(np.abs((hull - a) @ n))))
    return best


@pytest.mark.parametrize("file", ["fields2cover_data/test1.xml", "fields2cover_data/test.json",
                                  "isoxml_dev4ag_timelogs/PARTFIELDS_TASKDATA.XML"])
def test_the_chosen_angle_gives_the_fewest_swaths_by_rotating_calipers(file):
    """Fields2Cover's N-swath objective: the fewest swaths are ceil(min width / spacing) of the
    inner field, the minimal width found by rotating calipers (a second method; the planner
    searches angles in 1 degree steps, so it may need one swath more)."""
    field = max(read_fields(REAL / file), key=lambda f: f.boundary.area if f.area_ha < 20 else 0)
    p = plan(field, Settings(max_swaths=2))
    spacing = p.settings.working_width - p.settings.overlap
    count = len(_swath_lines(p.inner, p.angle, spacing, p.settings.working_width))
    fewest = math.ceil(_min_width(p.inner) / spacing)
    assert fewest <= count <= fewest + 1, (count, fewest)


# --- turns ----------------------------------------------------------------------------------------------
def test_a_u_turn_is_continuous_curvature_within_the_limits_and_lands_on_the_pose():
    limits = Limits.of(4.0, 1.4, math.radians(30), 1.0)
    for D in (9.0, 12.0, 20.0):
        path = connect((0.0, 0.0, 0.0), (0.0, D, math.pi), limits)
        assert path is not None
        assert np.allclose(path[-1, :2], (0.0, D), atol=2e-3)
        assert abs(math.remainder(path[-1, 2] - math.pi, 2 * math.pi)) < 1e-3
        k = path[:, 3]
        assert abs(k[0]) < 1e-9 and abs(k[-1]) < 1e-9                 # straight in, straight out
        ds = np.hypot(*np.diff(path[:, :2], axis=0).T)
        assert np.abs(k).max() <= limits.kappa_max + 1e-9
        assert (np.abs(np.diff(k)) / ds).max() <= limits.sigma * 1.001
        # the integrated heading is the integral of the curvature (trapezoid) along the path
        assert np.allclose(path[1:, 2] - path[0, 2], np.cumsum(0.5 * (k[1:] + k[:-1]) * ds), atol=1e-6)
        # longer than the Dubins U-turn of the same radius (pi R + the straight), by the clothoids
        dubins = math.pi * 4.0 + (D - 8.0)
        length = ds.sum()
        assert dubins < length < dubins + 2 * limits.kappa_max / limits.sigma + 1.0, (D, length, dubins)


def test_the_integrator_is_exact_on_an_arc():
    R, theta = 5.0, 2.0
    p = integrate([(R * theta, 1 / R, 1 / R)])
    assert np.allclose(p[-1, :2], (R * math.sin(theta), R * (1 - math.cos(theta))), atol=1e-9)


@pytest.mark.parametrize("n,s", [(12, 3), (13, 3), (20, 4), (7, 2), (30, 3)])
def test_skip_order_visits_every_swath_once_and_moves_at_least_s_lines(n, s):
    order = _skip_order(n, s)
    assert sorted(order) == list(range(n))
    moves = np.abs(np.diff(order))
    assert moves.min() >= s - 1 and np.mean(moves >= s) >= 0.8, (order, moves)
    if n % (2 * s) == 0:
        assert moves.min() >= s


# --- the trailed implement ----------------------------------------------------------------------------------
def _drive_implement(params: dict, R: float | None, v: float, seconds: float, pull=(0.0, 0.0),
                     dt: float = 0.002) -> TrailedImplement:
    """The implement behind a rear axle moving at v on a circle of radius R (None: straight east);
    the inputs are held over each step (co-simulation), an O(dt) error: a short step."""
    imp = TrailedImplement("implement", {**params, "internal_step": dt})
    for i in range(int(seconds / dt) + 1):
        t = i * dt
        if R is None:
            psi, gamma, x, y = 0.0, 0.0, v * t, 0.0
        else:
            psi, gamma = v * t / R, v / R
            x, y = R * math.sin(psi), R * (1 - math.cos(psi))
        imp.u.update(x_rear=x, y_rear=y, vel_east_rear=v * math.cos(psi), vel_north_rear=v * math.sin(psi),
                     heading=psi, yaw_rate=gamma, cross_track=0.0, active=0.0,
                     slope_pull_east=pull[0], slope_pull_north=pull[1])
        if i == 0:
            imp.initialize(0.0, dt)
        else:
            imp.step(t, dt)
    return imp


@pytest.mark.parametrize("R,c,L", [(4.0, 0.6, 2.5), (8.0, 1.0, 3.0), (6.0, 0.0, 2.0)])
def test_the_implement_settles_on_the_steady_turning_radius(R, c, L):
    """Rear axle on a circle of radius R, hitch c behind it, drawbar L: the implement's axle
    settles on radius sqrt(R^2 + c^2 - L^2) about the same centre (the hitch is on radius
    sqrt(R^2 + c^2) and the drawbar is tangent to the implement's circle)."""
    imp = _drive_implement({"hitch_offset": c, "drawbar": L}, R, 1.0, 60.0)
    radius = math.hypot(imp.y["x"], imp.y["y"] - R)
    assert radius == pytest.approx(math.sqrt(R * R + c * c - L * L), abs=1e-3)
    assert Settings(turn_radius=R, hitch_offset=c, drawbar=L).implement_radius == pytest.approx(radius, abs=1e-3)


def test_on_a_side_slope_a_passive_implement_runs_L_beta_downhill_and_the_side_shift_holds_it():
    """Straight east, the fall line south: the slip beta = m g sin(phi) / C_i puts the
    implement's axle L sin(beta) south of the hitch's track (steady state of its yaw equation)."""
    phi, m, C, L = math.radians(8.0), 900.0, 35000.0, 3.0
    pull = 9.81 * math.sin(phi)
    params = {"hitch_offset": 0.6, "drawbar": L, "mass": m, "cornering_stiffness": C}
    imp = _drive_implement(params, None, 2.0, 60.0, pull=(0.0, -pull))
    beta = m * pull / C
    assert imp.y["y"] == pytest.approx(-L * math.sin(beta), rel=1e-3)
    # the side-shift on its own cross-track error brings the tools back
    imp = TrailedImplement("implement", {**params, "side_shift_gain": 1.0, "side_shift_integral": 0.5})
    dt = 0.01
    for i in range(3001):
        t = i * dt
        imp.u.update(x_rear=2.0 * t, y_rear=0.0, vel_east_rear=2.0, vel_north_rear=0.0, heading=0.0, yaw_rate=0.0,
                     cross_track=imp.y["y"], active=1.0, slope_pull_east=0.0, slope_pull_north=-pull)
        imp.initialize(0.0, dt) if i == 0 else imp.step(t, dt)
    assert abs(imp.y["y"]) < 1e-3 and imp.y["side_shift"] == pytest.approx(L * math.sin(beta), rel=0.02)


def test_a_field_file_is_found_beside_the_study_that_names_it(tmp_path, monkeypatch):
    """A relative field path is looked for beside the study file, then beside the files it
    extends, then in the working folder; one found nowhere is named in the error."""
    import shutil

    monkeypatch.chdir(tmp_path)                                      # not the project's folder
    mine = tmp_path / "farm"
    mine.mkdir()
    shutil.copy(STUDIES / "fields" / "iam_field_boundaries.csv", mine / "plots.csv")
    child = mine / "my_plot.toml"
    child.write_text(f'extends = "{STUDIES / "field_plot_mounted.toml"}"\n'
                     '[components.field]\nparameters = { path = "plots.csv" }\n')
    assert resolve(Study.load(child)).parameters("field")["path"] == str((mine / "plots.csv").resolve())
    inherits = mine / "inherits.toml"                                # the parent's own field, beside the parent
    inherits.write_text(f'extends = "{STUDIES / "field_plot_mounted.toml"}"\n')
    assert resolve(Study.load(inherits)).parameters("field")["path"] == str(STUDIES / "fields" / "iam_field_boundaries.csv")
    missing = Study.load(child, ["field.path=nowhere.geojson"])
    assert resolve(missing).parameters("field")["path"] == "nowhere.geojson"
    res = _cli("run", str(child), "--out", str(tmp_path / "out"), "--set", "field.path=nowhere.geojson")
    assert res.returncode == 2 and "nowhere.geojson" in res.stderr and "Traceback" not in res.stderr


def test_the_route_component_takes_every_planner_setting():
    defaults = {v.name: v.start for v in FieldRoute.variables if v.causality == "parameter"}
    assert settings_of(defaults) == Settings()


# --- whole missions -----------------------------------------------------------------------------------------
def _run(study: str, *overrides: str):
    return run_study(Study.load(STUDIES / study, list(overrides)), None, plots=False)


@pytest.mark.slow
def test_a_real_plot_is_covered_by_the_guidance_stack():
    """The IAM plot (shipped in studies/fields), whole, at 2 m/s with RTK noise: the farmers' bars (coverage, overlap, RTK-class errors)."""
    m = _run("field_plot_mounted.toml").metrics
    assert m["route_done_share"] > 0.99
    assert m["coverage_share"] >= 0.99 and m["overlap_share"] <= 0.05, (m["coverage_share"], m["overlap_share"])
    assert m["boundary_crossings"] == 0
    assert m["implement_xte_p95_m"] <= 0.05 and m["tractor_xte_p95_m"] <= 0.05
    assert m["pass_to_pass_p95_m"] <= 0.05


def test_the_coverage_metric_agrees_with_a_monte_carlo_count():
    """covered and overlap areas (shapely on the swept strips) against a second method: 2 M
    random points counting the strips each lies in (a grid would alias the 5 cm overlaps)."""
    from agrobot.analysis.field_tracks import _samples, _shape, _strips, mission

    overrides = ["field.max_swaths=3", "field.headland_work=0"]
    res = _run("field_plot_mounted.toml", *overrides)
    study = Study.load(STUDIES / "field_plot_mounted.toml", overrides)
    field, p, conv, _ = mission(study)
    strips = _strips(_samples(res.frame, study), p.settings.working_width)
    assert len(strips) == 3
    minx, miny, maxx, maxy = unary_union(strips).bounds
    rng = np.random.default_rng(27)
    n = 2_000_000
    px, py = rng.uniform(minx, maxx, n), rng.uniform(miny, maxy, n)
    cell = (maxx - minx) * (maxy - miny) / n
    count = sum(contains_xy(st, px, py).astype(int) for st in strips)
    inside = contains_xy(_shape(p.workable, conv), px, py)
    covered = np.sum((count > 0) & inside) * cell
    overlap = np.sum(np.where(inside, np.maximum(count - 1, 0), 0)) * cell
    m = res.metrics
    assert m["covered_area_m2"] == pytest.approx(covered, rel=0.01)
    assert m["overlap_area_m2"] == pytest.approx(overlap, rel=0.1)
    assert m["overlap_area_m2"] > 0.5                  # adjacent passes overlap by the planned 5 cm


@pytest.mark.parametrize("path,extra", [
    ("fields2cover_data/test1.xml", ()),
    ("isoxml_dev4ag_timelogs/PARTFIELDS_TASKDATA.XML", ("field.name=NO_Warschau_Simple",)),
    ("isoxml_dev4ag_timelogs/TASKDATA.XML", ("field.name=euDZYo7",)),             # a bay: two cells
    ("fields2cover_data/test_2_cell.json", ("field.name=field1",)),
])
@pytest.mark.slow
def test_field_coverage_runs_a_section_of_each_real_field_file(path, extra):
    """--set field.path=... runs any field: 3 swaths of each with the trailed implement."""
    m = _run("field_coverage.toml", f"field.path={REAL / path}", "field.max_swaths=3", *extra).metrics
    assert m["route_done_share"] > 0.99 and m["boundary_crossings"] == 0
    assert m["implement_xte_p95_m"] <= 0.05, m["implement_xte_p95_m"]
    assert m["swath_time_s"] > 0 and m["turn_time_s"] > 0


@pytest.mark.slow
def test_the_side_slope_option_tilts_tractor_and_implement():
    """tractor.slope_angle alone moves the implement too (wired from the tractor): passive, it
    hangs downhill by more than L beta; the side-shift brings it back within RTK class."""
    common = ("field.max_swaths=2", "field.headland_work=0", "tractor.slope_angle=10 deg",
              "tractor.slope_downhill_heading=-90 deg")
    passive = _run("field_coverage.toml", *common, "implement.side_shift_gain=0", "implement.side_shift_integral=0")
    beta = 800.0 * 9.81 * math.sin(math.radians(10.0)) / 40000.0
    assert passive.metrics["implement_xte_rms_m"] > 2.5 * beta
    held = _run("field_coverage.toml", *common).metrics
    assert held["implement_xte_p95_m"] <= 0.05


# --- command line: plan, bad fields, sweeps --------------------------------------------------------------------


@pytest.mark.slow
def test_plan_command_writes_the_route_and_its_figures(tmp_path):
    out = tmp_path / "plan"
    res = _cli("plan", str(STUDIES / "fields" / "iam_field_boundaries.csv"), "--crs", "EPSG:6677", "--out", str(out),
               "--width", "2", "--turn-radius", "2.5", "--drawbar", "0", "--settle", "2")
    assert res.returncode == 0, res.stderr
    summary = json.loads((out / "plan.json").read_text())
    route = np.genfromtxt(out / "route.csv", delimiter=",", names=True, dtype=None, encoding=None)
    # a turn into every swath but the first, and into each pass of its own for what the route leaves
    assert summary["swaths"] >= 5 and summary["turns"] == summary["swaths"] + summary["leftover_passes"] - 1
    assert summary["distance_m"] == pytest.approx(float(route["s"][-1]), abs=0.2)
    doc = json.loads((out / "route.geojson").read_text())
    lon, lat = np.array(doc["features"][0]["geometry"]["coordinates"]).T
    assert 139 < lon.mean() < 141 and 35 < lat.mean() < 37            # Japan: the CRS was used
    assert (out / "plan.png").stat().st_size > 10_000


@pytest.mark.parametrize("args,expect", [
    (("{real}/fields2cover_data/strips.geojson", "--name", "strips_1"), ("strips_1", "narrower than two working widths")),
    (("{studies}/fields/iam_field_boundaries.csv", "--crs", "EPSG:6677"), ("narrower than two working widths",)),
    (("{studies}/fields/test_parcel.json", "--headland-passes", "1"), ("do not fit the headland", "1 headland pass")),
    (("{studies}/fields/iam_field_boundaries.csv", "--crs", "EPSG:99999"), ("EPSG:99999",)),
])
def test_bad_fields_exit_2_naming_the_field_and_the_value(tmp_path, args, expect):
    args = (args[0].format(real=REAL, studies=STUDIES),) + args[1:]
    out = tmp_path / "plan"
    res = _cli("plan", *args, "--out", str(out))
    assert res.returncode == 2, (res.returncode, res.stderr)
    for text in expect:
        assert text in res.stderr, res.stderr
    assert "Traceback" not in res.stderr
    assert not out.exists() or not any(out.iterdir())


@pytest.mark.slow
def test_an_agopengps_field_is_driven_along_its_ab_line(tmp_path):
    """A farmer's AgOpenGPS folder (written from a real partfield): --set field.path=FOLDER runs it,
    and field.guidance_line takes the driving angle from its AB line."""
    from tests.test_other_data import write_agopengps

    real = next(f for f in read_fields(REAL / "isoxml_dev4ag_timelogs" / "PARTFIELDS_TASKDATA.XML")
                if f.name == "SW_Curitiba_Simple")
    c = np.asarray(real.boundary.centroid.coords)[0]
    folder = write_agopengps(tmp_path / "Curitiba", real, [("AB 30", np.array([c, c + [86.6, 50.0]]))])
    p = plan(read_fields(folder)[0], Settings(guidance_line="AB 30", max_swaths=2))
    assert p.angle == pytest.approx(math.radians(30.0), abs=1e-4) and "AB line 'AB 30'" in p.angle_how
    with pytest.raises(FieldError, match="no such guidance line .*'AB 30'"):
        plan(read_fields(folder)[0], Settings(guidance_line="AB 99"))
    m = _run("field_coverage.toml", f"field.path={folder}", "field.guidance_line=AB 30", "field.max_swaths=3").metrics
    assert m["route_done_share"] > 0.99 and m["boundary_crossings"] == 0 and m["implement_xte_p95_m"] <= 0.05


def test_a_bad_field_in_a_study_exits_2_before_anything_is_written(tmp_path):
    out = tmp_path / "run"
    res = _cli("run", str(STUDIES / "field_coverage.toml"), "--out", str(out),
               "--set", f"field.path={STUDIES / 'fields' / 'iam_field_boundaries.csv'}", "--set", "field.crs=EPSG:6677")
    assert res.returncode == 2, res.stderr
    assert "field" in res.stderr and "narrower than two working widths" in res.stderr
    assert not out.exists()


@pytest.mark.slow
@pytest.mark.parametrize("scheduler", [None, "local"], ids=["pool", "dask"])
def test_a_speed_and_angle_sweep_of_a_field_mission_runs(tmp_path, scheduler):
    """The shipped sweep, cut to 2 x 2 points, on the process pool and on a local Dask cluster
    (a real scheduler and workers)."""
    text = (STUDIES / "field_speed_sweep.toml").read_text()
    text = text.replace('extends = "field_plot_mounted.toml"', f'extends = "{STUDIES / "field_plot_mounted.toml"}"')
    text = text.replace('{ start = 1.0, stop = 3.0, step = 1.0 }', '[1.5, 3.0]')
    study = tmp_path / "sweep.toml"
    study.write_text(text + '\n[components.field.parameters]\nmax_swaths = 3\nheadland_work = 0\n')
    out = tmp_path / "out"
    res = _cli("sweep", str(study), "--out", str(out), "--workers", "2", *(["--scheduler", scheduler] if scheduler else []))
    assert res.returncode == 0, res.stderr
    import pandas as pd

    table = pd.read_parquet(out / "results.parquet")
    assert len(table) == 4 and (table["status"] == "completed").all()
    assert (table["boundary_crossings"] == 0).all() and (table["implement_xte_p95_m"] <= 0.05).all()
    fast = table["field.work_speed"] == 3.0
    # faster is shorter on the swaths, for each angle
    for angle, g in table.groupby("field.driving_angle"):
        assert g.loc[fast[g.index], "swath_time_s"].iloc[0] < g.loc[~fast[g.index], "swath_time_s"].iloc[0]
