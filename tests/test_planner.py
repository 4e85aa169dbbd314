"""The coverage planner in stages (fields.planner): its layout (stages in their own modules, no
import circle), the lazily evaluated path and speed profile against second computations, the
route component's bounded window, angle objectives, values refused before any work, and the
plan's files written as one set."""
from __future__ import annotations

import ast
import json
import math
import subprocess
from pathlib import Path

import numpy as np
import pytest
from shapely.geometry import Polygon

from agrobot.components.field_route import FieldRoute, to_mission
from agrobot.fields import FieldError
from agrobot.fields.field import Field
from agrobot.fields.planner import HEADLAND, SWATH, TRANSIT, TURN, Settings, plan
from agrobot.fields.planner import objectives, route_order
from agrobot.fields.planner.curves import connect
from agrobot.fields.planner.sampling import ROUTE_STEP
from agrobot.orchestrator.cli import main
from tests.commands import cli

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "agrobot"          # the import root; its modules named here without "agrobot."
FAST = dict(working_width=6.0)              # a wide implement: few swaths, quick plans


def rectangle(name: str, width: float, height: float, angle_deg: float = 0.0, shear: float = 0.0) -> Field:
    c, s = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
    pts = [(0, 0), (width, 0), (width + shear, height), (shear, height)]
    return Field(name, Polygon([(c * x - s * y, s * x + c * y) for x, y in pts]), None, "generated", "local metres")


def write_geojson(path: Path, fields: dict[str, list]) -> Path:
    feats = [{"type": "Feature", "properties": {"name": name},
              "geometry": {"type": "Polygon", "coordinates": [ring + ring[:1]]}} for name, ring in fields.items()]
    path.write_text(json.dumps({"type": "FeatureCollection", "features": feats}))
    return path


def rect_ring(w: float, h: float) -> list:
    return [[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]]


@pytest.fixture(scope="module")
def small_plan():
    """A 120 x 80 m field with a 6 m implement: headland passes, skip order, transits."""
    return plan(rectangle("small", 120.0, 80.0, angle_deg=20.0), Settings(**FAST))


# --- layout ---------------------------------------------------------------------------------------------
def _imports(path: Path, package: str) -> set[str]:
    """Modules of ``package`` that the file imports (at the top or inside functions)."""
    tree = ast.parse(path.read_text())
    here = ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
    base = here.rsplit(".", 1)[0] if path.name != "__init__.py" else here
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                parts = base.split(".")
                mod = ".".join(parts[:len(parts) - node.level + 1] + ([node.module] if node.module else []))
            else:
                mod = (node.module or "").removeprefix("agrobot.")
            names = [f"{mod}.{a.name}" for a in node.names]
            out |= {n for n in [mod] + names if n.startswith(package)}
        elif isinstance(node, ast.Import):
            out |= {a.name.removeprefix("agrobot.") for a in node.names
                    if a.name.removeprefix("agrobot.").startswith(package)}
    return out


def test_the_planner_stages_are_modules_without_import_circles_or_crowding():
    files = sorted((PACKAGE / "fields").rglob("*.py"))
    modules = {".".join(f.relative_to(PACKAGE).with_suffix("").parts).removesuffix(".__init__"): f for f in files}
    for stage in ("headland", "decomposition", "swaths", "objectives", "route_order", "turns", "path", "speed"):
        assert f"fields.planner.{stage}" in modules
    graph = {m: {i for i in _imports(f, "fields") if i in modules and i != m} for m, f in modules.items()}
    # a package imports its own modules downward: its __init__ is not a dependency of them
    graph = {m: {i for i in deps if not m.startswith(i + ".")} for m, deps in graph.items()}
    state: dict[str, int] = {}

    def visit(m, trail):
        state[m] = 1
        for n in graph[m]:
            assert state.get(n) != 1, f"import circle: {' -> '.join(trail + [m, n])}"
            if n not in state:
                visit(n, trail + [m])
        state[m] = 2

    for m in graph:
        if m not in state:
            visit(m, [])
    for f in (PACKAGE / "fields" / "planner").glob("*.py"):
        assert len(f.read_text().splitlines()) <= 500, f
    # the route component reads a Path, not a command-line module
    assert not {i for i in _imports(PACKAGE / "components" / "field_route.py", "fields") if "cli" in i}


# --- the path and its speed ------------------------------------------------------------------------------
def test_the_lazy_path_agrees_with_resampling_its_joined_vertices(small_plan):
    """Second method: every segment's vertices joined and resampled on the grid by np.interp over
    their cumulative arc length (as a whole-route sampling would); heading from np.gradient."""
    path = small_plan.path
    v = np.vstack([seg.points for seg in path.segments])
    keep = np.concatenate([[True], np.hypot(*np.diff(v[:, :2], axis=0).T) > 1e-9])
    v = v[keep]
    s_raw = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(v[:, :2], axis=0).T))])
    s = np.arange(0.0, s_raw[-1], ROUTE_STEP)
    x, y = np.interp(s, s_raw, v[:, 0]), np.interp(s, s_raw, v[:, 1])
    r = path.grid(0, path.grid_size())
    assert len(r["s"]) == len(s) and path.length == pytest.approx(s_raw[-1], abs=1e-6)
    assert np.abs(r["x"] - x).max() < 1e-6 and np.abs(r["y"] - y).max() < 1e-6
    heading = np.unwrap(np.arctan2(np.gradient(y), np.gradient(x)))
    assert np.abs(r["heading"] - heading).max() < 1e-6
    # the kinds in driving order, and the distances by kind add up to the length
    kinds = set(r["kind"])
    assert {SWATH, TURN, HEADLAND, TRANSIT} <= kinds
    assert sum(path.distances().values()) == pytest.approx(path.length)
    # memory: the path keeps its vertices (straights by their ends), far fewer than the grid
    assert sum(len(seg.points) for seg in path.segments) < 0.5 * path.grid_size()


def _discrete_profile(target: np.ndarray, step: float, accel: float) -> np.ndarray:
    """The speed profile by forward and backward passes of v^2 <= v0^2 + 2 a ds on a grid."""
    v = target.astype(float).copy()
    v[0] = v[-1] = min(0.3, float(target.min()))
    for i in range(1, len(v)):
        v[i] = min(v[i], math.sqrt(v[i - 1] ** 2 + 2 * accel * step))
    for i in range(len(v) - 2, -1, -1):
        v[i] = min(v[i], math.sqrt(v[i + 1] ** 2 + 2 * accel * step))
    return v


def test_the_closed_form_speed_profile_agrees_with_the_grid_passes(small_plan):
    path, st = small_plan.path, small_plan.settings
    n = int(path.length / 0.002) + 1     # the grid's ramps start up to a step late: dv <= a step / v = 3 mm/s
    s = np.linspace(0.0, path.length, n)
    step = s[1]
    k = np.clip(np.searchsorted(path.starts, s, side="right") - 1, 0, len(path) - 1)
    target = np.where(np.isin(path.kinds[k], (SWATH, HEADLAND)), st.work_speed, st.turn_speed)
    v = _discrete_profile(target, step, st.acceleration)
    lazy = path.evaluate(s)["speed"]
    assert np.abs(lazy - v).max() < 0.005
    # the time in closed form against the sum of ds / v on the grid
    assert path.time() == pytest.approx(np.sum(step / v), rel=2e-3)
    assert lazy.max() == pytest.approx(st.work_speed) and lazy[0] == pytest.approx(0.3)


def test_the_route_component_evaluates_a_window_and_matches_a_whole_route_projection(small_plan):
    """The component's outputs, stepping along the route 0.3 m to its left, against a projection
    onto the whole route sampled on the grid (the window's second method); its arrays stay the
    size of the window whatever the route's length."""
    field = small_plan.field
    route = FieldRoute("field", {"path": "unused", "working_width": 6.0})
    route.path = small_plan.path
    from agrobot.components.field_route import RouteWindow, route_frame

    origin, rotation = route_frame(route.path)
    route.route = RouteWindow(route.path, origin, rotation)
    route.end = (route.route.size - 1) * ROUTE_STEP
    route.i_cg = route.i_impl = 0
    route.sections = None                 # no section control (initialize sets it from the parameters)
    whole = route.path.grid(0, route.path.grid_size())
    xy = to_mission(np.column_stack([whole["x"], whole["y"]]), origin, rotation)
    h = whole["heading"] - rotation
    largest = 0
    i = 0
    for k, s in enumerate(np.arange(1.0, route.path.length - 5.0, 0.7)):
        p = to_mission(route.path.position([s]), origin, rotation)[0]
        e = route.path.evaluate([s])
        left = p + 0.3 * np.array([-math.sin(e["heading"][0] - rotation), math.cos(e["heading"][0] - rotation)])
        route.u.update(x=left[0], y=left[1], implement_x=left[0], implement_y=left[1])
        route.step(0.05 * k, 0.05)
        a, b = max(0, i - 20), min(len(xy), i + 101)
        i = a + int(np.argmin(np.sum((xy[a:b] - left) ** 2, axis=1)))
        assert route.y["path_length"] == pytest.approx(whole["s"][i], abs=1e-9)
        assert route.y["x_ref"] == pytest.approx(xy[i, 0], abs=1e-9) and route.y["heading_ref"] == pytest.approx(h[i])
        assert route.y["segment"] == whole["kind"][i] and route.y["speed_ref"] == pytest.approx(whole["speed"][i])
        assert route.y["cross_track"] == pytest.approx(0.3, abs=0.02)
        largest = max(largest, len(route.route.x))
    assert largest <= (500.0 + 20.0) / ROUTE_STEP + 200 < route.route.size
    assert field.name == "small"


# --- stages -----------------------------------------------------------------------------------------------
def test_the_skip_pattern_found_by_bisection_is_the_linear_scans():
    """route_order.pattern bisects the quarter-spacing grid for the narrowest U-turn; the linear
    scan over the same grid (a second method) finds the same skip."""
    for width, radius in ((3.0, 4.0), (2.0, 2.5), (2.5, 6.0)):
        st = Settings(working_width=width, turn_radius=radius)
        spacing, limits = st.spacing, st.limits

        def csc(D):
            p = connect((0.0, 0.0, 0.0), (0.0, D, math.pi), limits, families=("LSL",))
            return p is not None and np.all(np.diff(p[:, 2]) >= -1e-9) and np.ptp(p[:, 2]) <= math.pi + 1e-6

        u, fits = spacing, csc(spacing)
        while not fits and u < 10 * radius + 10 * spacing:
            u += 0.25 * spacing
            fits = csc(u)
        order, skip, _ = route_order.pattern(st)
        assert order == "skip" and skip == max(2, math.ceil(u / spacing)), (width, radius)


def test_the_longest_edge_objective_drives_along_the_long_side_and_objectives_plug_in(monkeypatch):
    """A trapezoid whose longest edge (the top, 302.7 m) rises at atan(40 / 300) = 7.6 deg while the
    fewest swaths run along the bottom (0 deg): each objective picks its own."""
    corners = [(0.0, 0.0), (300.0, 0.0), (300.0, 100.0), (0.0, 60.0)]
    field = Field("trapezoid", Polygon(corners), None, "generated", "local metres")
    p = plan(field, Settings(**FAST, angle_objective="longest_edge", max_swaths=2))
    assert abs(math.degrees(p.angle) - math.degrees(math.atan2(40.0, 300.0))) <= 1.0
    assert "chosen: along the longest boundary edges" in p.angle_how
    fewest = plan(field, Settings(**FAST, max_swaths=2))
    assert math.degrees(fewest.angle) == pytest.approx(0.0) and "fewest swaths" in fewest.angle_how
    prefer = objectives.Objective("near_30", "near 30 deg", lambda region, deg, spacing: (abs(deg - 30.0),))
    monkeypatch.setitem(objectives.OBJECTIVES, "near_30", prefer)
    p = plan(field, Settings(**FAST, angle_objective="near_30", max_swaths=2))
    assert math.degrees(p.angle) == pytest.approx(30.0) and p.angle_how == "chosen: near 30 deg"
    with pytest.raises(FieldError, match="angle_objective = 'nowhere'"):
        plan(field, Settings(angle_objective="nowhere"))


def test_a_swath_is_a_polyline_and_a_route_a_sequence_of_typed_passes(small_plan):
    route = small_plan.route
    assert route.swaths and all(sw.points.shape[1] == 2 and len(sw.points) >= 2 for sw in route.swaths)
    sw = route.swaths[0]
    assert np.allclose(sw.reversed().start, sw.end) and sw.extended(1.0).length == pytest.approx(sw.length + 2.0)
    assert sum(len(c.swaths) for c in small_plan.cells) == len(route.swaths)
    kinds = [seg.kind for seg in small_plan.path.segments]
    assert kinds.count(SWATH) == len(route.swaths) + len(small_plan.leftover_passes) and kinds[0] == TURN


# --- values checked before any work -----------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["working_width", "turn_radius", "turn_speed", "drawbar", "work_speed", "settle",
                                  "driving_angle", "acceleration"])
@pytest.mark.parametrize("value", [math.inf, -math.inf, math.nan])
def test_an_infinite_or_nan_setting_is_refused_naming_it(name, value):
    with pytest.raises(FieldError, match=f"{name} = {value}: expected a finite number"):
        plan(rectangle("r", 300.0, 200.0), Settings(**{name: value}))


def _never(*args, **kwargs):
    raise AssertionError("work started before the values were checked")


@pytest.mark.parametrize("field,settings,expect", [
    (rectangle("far", 1e30, 1e30), Settings(), "beyond the Earth"),
    (rectangle("r", 300.0, 200.0), Settings(turn_radius=5000.0), "turn radius 5000 m"),
    (rectangle("r", 300.0, 200.0), Settings(turn_radius=500.0), "turn radius 500 m"),
    (rectangle("wide", 80000.0, 70000.0), Settings(), "more than the 20,000 planned at once"),
])
def test_a_field_beyond_the_earth_or_a_turn_radius_beyond_the_field_is_refused_before_work(monkeypatch, field,
                                                                                          settings, expect):
    monkeypatch.setattr(route_order, "pattern", _never)
    with pytest.raises(FieldError, match=expect):
        plan(field, settings)


@pytest.mark.parametrize("args,expect", [
    (("--width", "inf"), "argument --width: expected a finite number, got 'inf'"),
    (("--turn-radius", "inf"), "argument --turn-radius: expected a finite number"),
    (("--turn-speed", "inf"), "argument --turn-speed: expected a finite number"),
    (("--drawbar", "inf"), "argument --drawbar: expected a finite number"),
    (("--angle", "nan"), "argument --angle: expected a finite number, got 'nan'"),
    (("--angle=-inf",), "argument --angle: expected a finite number, got '-inf'"),
    (("--turn-radius", "500"), "turn radius 500 m"),
    (("--headland-passes", "-1"), "--headland-passes = -1: expected zero or more"),
])
def test_plan_refuses_bad_values_with_exit_2_naming_them(tmp_path, capsys, monkeypatch, args, expect):
    field = write_geojson(tmp_path / "rect.geojson", {"rect": rect_ring(300.0, 200.0)})
    monkeypatch.setattr(route_order, "pattern", _never)
    try:
        code = main(["plan", str(field), "--out", str(tmp_path / "out"), *args])
    except SystemExit as exc:                       # argparse
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2 and expect in err and "Traceback" not in err, err
    assert not (tmp_path / "out").exists()


# --- the files, as one set ---------------------------------------------------------------------------------------
def _plan_cli(*args: str) -> subprocess.CompletedProcess:
    return cli("plan", *args, timeout=300)


def test_plan_writes_its_files_as_one_set_and_an_interrupted_plan_keeps_the_earlier(tmp_path, capsys, monkeypatch):
    from agrobot.fields.planner import export

    source = write_geojson(tmp_path / "two.geojson", {"east": rect_ring(120.0, 80.0),
                                                    "west": [[-200.0, 0.0], [-60.0, 0.0], [-60.0, 90.0], [-200.0, 90.0]]})
    out = tmp_path / "plan"
    common = ["--width", "6", "--max-swaths", "2", "--out", str(out)]
    assert main(["plan", str(source), "--name", "east", *common]) == 0
    before = {f.name: f.read_bytes() for f in out.iterdir()}
    assert sorted(before) == ["as_applied.geojson", "as_applied.png", "plan.json", "plan.png", "route.csv",
                              "route.geojson"]

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(export, "draw_plan", interrupted)           # after route.csv, .geojson and plan.json
    assert main(["plan", str(source), "--name", "west", *common]) == 2          # an earlier plan: --overwrite
    assert "--overwrite" in capsys.readouterr().err
    assert main(["plan", str(source), "--name", "west", *common, "--overwrite"]) == 130
    assert {f.name: f.read_bytes() for f in out.iterdir()} == before
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".plan.")] == []      # nor a lock file
    monkeypatch.undo()
    assert main(["plan", str(source), "--name", "west", *common, "--overwrite"]) == 0
    assert json.loads((out / "plan.json").read_text())["field"] == "west"
    capsys.readouterr()
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "notes.txt").write_text("mine")
    assert main(["plan", str(source), "--width", "6", "--out", str(tmp_path / "other"), "--overwrite"]) == 2
    assert "not a plan" in capsys.readouterr().err and (tmp_path / "other" / "notes.txt").read_text() == "mine"


def test_plan_on_a_folder_names_the_files_it_could_not_read(tmp_path, capsys):
    folder = tmp_path / "farm"
    folder.mkdir()
    write_geojson(folder / "good.geojson", {"good": rect_ring(120.0, 80.0)})
    (folder / "broken.geojson").write_text("{ not json")
    out = tmp_path / "plan"
    assert main(["plan", str(folder), "--width", "6", "--max-swaths", "2", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "not read" in printed and "broken.geojson" in printed
    assert any("broken.geojson" in why for why in json.loads((out / "plan.json").read_text())["not_read"])


@pytest.mark.slow
def test_the_compact_route_file_reproduces_the_route_sampled_on_demand(tmp_path):
    """route.csv (points of the path at most about 0.3 m apart where it curves, straights by their
    ends, the speed ramps every 0.5 m), interpolated linearly, against --route-uniform at the
    trackers' 0.1 m: positions within the chord error of 0.3 m chords on a 4 m turn (0.3^2 / (8 x 4)
    = 3 mm), the speed within 6 cm/s (the chord of v = sqrt(0.3^2 + 2 a s) over the first 0.5 m, the
    steepest ramp: 5 cm/s)."""
    source = write_geojson(tmp_path / "f.geojson", {"f": rect_ring(120.0, 80.0)})
    compact, uniform = tmp_path / "compact", tmp_path / "uniform"
    assert _plan_cli(str(source), "--width", "6", "--out", str(compact)).returncode == 0
    res = _plan_cli(str(source), "--width", "6", "--out", str(uniform), "--route-uniform", "--route-step", "0.1")
    assert res.returncode == 0, res.stderr
    import pandas as pd

    c, u = pd.read_csv(compact / "route.csv"), pd.read_csv(uniform / "route.csv")
    assert len(c) < 0.2 * len(u)
    assert np.all(np.diff(u["s"]) <= 0.1 + 1e-4) and u["s"].iloc[-1] == pytest.approx(c["s"].iloc[-1])
    for col, tol in (("x", 0.004), ("y", 0.004), ("speed", 0.06)):
        assert np.abs(np.interp(u["s"], c["s"], c[col]) - u[col]).max() < tol, col
    doc = json.loads((compact / "route.geojson").read_text())
    kinds = [f["properties"]["kind"] for f in doc["features"]]
    summary = json.loads((compact / "plan.json").read_text())
    assert kinds.count("swath") == summary["swaths"] + summary["leftover_passes"]      # the leftovers' own passes too
