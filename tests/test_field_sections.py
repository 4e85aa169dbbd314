"""Section control in the driven mission: the implement's sections switch from its own simulated pose
(trailed, off-tracking) against the ground it has worked; the mission's as-applied map and figures come
from what was driven. Checked against a second method: a 3 cm raster of the implement's swept area,
each cell worked where it lies in the step of a recorded pose (its along-track stretch to the next
pose, in that pose's frame) within a section that was on; and against the overlap the route designs
in between passes without sections, in closed form."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from shapely import contains_xy

from agrobot.analysis.field_tracks import _samples, _shape, mission
from agrobot.components.field_route import section_mask
from agrobot.orchestrator.cli import main
from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.study import Study

ROOT = Path(__file__).resolve().parents[1]
STUDY = ROOT / "studies" / "field_coverage.toml"
WIDTH, SECTIONS, OVERLAP = 3.0, 6, 0.6           # sections of 0.5 m; passes overlap by more than one section


def quad_field(path: Path) -> Path:
    """A 0.17 ha quadrilateral with a slanted edge (UTM 32N)."""
    pts = [[0, 0], [40, 0], [46, 40], [0, 44], [0, 0]]
    ring = [[300000.0 + x, 5700000.0 + y] for x, y in pts]
    path.write_text(json.dumps({"type": "FeatureCollection", "crs": {"type": "name", "properties": {"name": "EPSG:32632"}},
                                "features": [{"type": "Feature", "properties": {"name": "quad"},
                                              "geometry": {"type": "Polygon", "coordinates": [ring]}}]}))
    return path


def overrides(field: Path) -> list[str]:
    return [f"field.path={field}", "field.max_swaths=3", "field.headland_work=0", "field.settle=2",
            f"field.overlap={OVERLAP}", f"field.sections={SECTIONS}"]


@pytest.fixture(scope="module")
def driven(tmp_path_factory):
    field = quad_field(tmp_path_factory.mktemp("sections") / "quad.geojson")
    study = Study.load(STUDY, overrides(field))
    return study, run_study(study, None, plots=False)


def raster_times_worked(s, cell: float, box) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, y, times worked) of cells: a cell counts once per recorded step whose along-track stretch
    [0, d_i) in pose i's frame holds it, within a section on at pose i."""
    from scipy.spatial import cKDTree

    x, y, h = s["ix"].to_numpy(), s["iy"].to_numpy(), s["ih"].to_numpy()
    on = section_mask(s["mask0"].to_numpy(), s["mask1"].to_numpy(), SECTIONS)
    d = np.append(np.hypot(np.diff(x), np.diff(y)), 0.0)
    minx, miny, maxx, maxy = box
    gx, gy = np.meshgrid(np.arange(minx, maxx, cell) + cell / 2, np.arange(miny, maxy, cell) + cell / 2)
    gx, gy = gx.ravel(), gy.ravel()
    count = np.zeros(len(gx), int)
    live = np.flatnonzero(on.any(axis=1) & (d > 1e-6))
    tree = cKDTree(np.column_stack([gx, gy]))
    edges = -WIDTH / 2 + np.arange(SECTIONS + 1) * WIDTH / SECTIONS
    for i in live:
        near = np.asarray(tree.query_ball_point([x[i], y[i]], WIDTH / 2 + d[i] + cell), int)
        if not len(near):
            continue
        dx, dy = gx[near] - x[i], gy[near] - y[i]
        along = dx * np.cos(h[i]) + dy * np.sin(h[i])
        across = -dx * np.sin(h[i]) + dy * np.cos(h[i])
        j = np.clip(np.searchsorted(edges, across, side="right") - 1, 0, SECTIONS - 1)
        hit = (along >= 0) & (along < d[i]) & (np.abs(across) <= WIDTH / 2) & on[i, j]
        count[near[hit]] += 1
    return gx, gy, count


@pytest.mark.slow
def test_the_driven_as_applied_map_agrees_with_a_raster_of_the_swept_area(driven):
    study, res = driven
    m = res.metrics
    field, plan, conv, _ = mission(study)
    s = _samples(res.frame, study)
    boundary = _shape(field.boundary, conv)
    on = section_mask(s["mask0"].to_numpy(), s["mask1"].to_numpy(), SECTIONS)
    assert on.any() and not on[s["working"].to_numpy() > 0.5].all(), "sections should switch off somewhere"
    cell = 0.03
    pad = WIDTH
    box = (s["ix"].min() - pad, s["iy"].min() - pad, s["ix"].max() + pad, s["iy"].max() + pad)
    gx, gy, count = raster_times_worked(s, cell, box)
    inside = contains_xy(boundary, gx, gy)
    covered = np.sum((count > 0) & inside) * cell ** 2
    overlap = np.sum(np.maximum(count - 1, 0)[inside]) * cell ** 2
    assert m["field_coverage_share"] * m["field_area_m2"] == pytest.approx(covered, rel=0.01)
    assert m["field_overlap_share"] * m["field_area_m2"] == pytest.approx(overlap, rel=0.25, abs=0.5)
    assert m["applied_outside_m2"] == pytest.approx(np.sum((count > 0) & ~inside) * cell ** 2, abs=0.5)


@pytest.mark.slow
def test_sections_take_the_designed_overlap_away_and_match_the_plan(driven):
    """Without sections two adjacent passes overlap by OVERLAP along their common length (closed
    form; the route's skip order drives lines 4, 0 and 5); with sections of 0.5 m the outermost section, wholly over the worked pass, is off, so
    the driven overlap is a fraction of it, and coverage and overlap are close to the plan's."""
    study, res = driven
    m = res.metrics
    _, plan, _, _ = mission(study)
    by_line = {sw.line: sw for sw in plan.swaths}               # skip order: lines 4, 0, 5 (4 and 5 adjacent)
    pairs = [(by_line[k], by_line[k + 1]) for k in by_line if k + 1 in by_line]
    assert pairs, sorted(by_line)
    designed = sum(OVERLAP * min(np.hypot(*(a.end - a.start)), np.hypot(*(b.end - b.start))) for a, b in pairs)
    assert m["field_overlap_share"] * m["field_area_m2"] < 0.35 * designed
    assert m["field_coverage_share"] == pytest.approx(m["plan_field_coverage_share"], abs=0.005)
    assert abs(m["field_overlap_share"] - m["plan_field_overlap_share"]) < 0.003
    assert m["sections"] == SECTIONS


@pytest.mark.parametrize("setting,named", [
    ("field.sections=100", "sections = 100"), ("field.sections=2.5", "sections = 2.5"),
    ("field.section_on_delay=-0.1", "got -0.1"), ("field.section_off_delay=30", "section_off_delay = 30"),
])
def test_bad_section_settings_exit_2_naming_the_value(tmp_path, capsys, setting, named):
    field = quad_field(tmp_path / "quad.geojson")
    out = tmp_path / "out"
    code = main(["run", str(STUDY), "--out", str(out), "--set", f"field.path={field}", "--set", "field.max_swaths=1",
                 "--set", setting])
    err = capsys.readouterr().err
    assert code == 2 and named in err and "Traceback" not in err, err[-500:]
    assert not out.exists()
