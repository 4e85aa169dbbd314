"""A trailed implement on a side slope: its steady hang behind a tractor that holds its line (a
closed form derived here against the plant and the implement run together), and a slope mission
on a generated non-rectangular field whose implement and tractor hold 2.5 cm on the swaths."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from agrobot.components.models.terrain import GRAVITY
from agrobot.components.models.yaw_dynamics import TractorParameters
from agrobot.components.trailed_implement import TrailedImplement
from agrobot.components.tractor_yaw_plant import TractorYawPlant
from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.study import Study
from tests.test_slope_margins import trimmed

ROOT = Path(__file__).resolve().parents[1]
DEG = math.pi / 180.0
SLOPE, DT = 10 * DEG, 0.01


def test_behind_a_tractor_on_a_side_slope_the_implement_hangs_L_beta_plus_the_crab_angle_downhill():
    """Closed form. The tractor holds its CG on a line across the slope (fall line south): its tyres
    carry m g sin(phi), the rear ones l_f / L of it at the slip angle F_r / C_r, so the body crabs at
    alpha = k g sin(phi) (k = m l_f / (L C_r)), nose uphill, and the hitch, l_r + c behind the CG, runs
    (l_r + c) sin(alpha) downhill of the CG's line. Behind it the implement's tyres hold its pull
    m_i g sin(phi) at the slip beta = m_i g sin(phi) / C_i, so its axle runs L sin(beta) further down:

        d = -(L sin(beta) + (l_r + c) sin(alpha))      (9.5 cm on 10 deg with the field studies' values)

    Checked on the nonlinear plant trimmed on the slope (test_slope_margins.trimmed) with the passive
    implement behind it."""
    c, L, m_i, C_i, v = 0.6, 2.5, 800.0, 40000.0, 2.0
    params = {"model": "rlf", "slope_angle": SLOPE, "slope_downhill_heading": -90 * DEG}
    p = TractorParameters.of(TractorYawPlant("t", params).p)
    alpha = p.m * p.l_f / ((p.l_f + p.l_r) * p.C_r) * GRAVITY * math.sin(SLOPE)
    beta = m_i * GRAVITY * math.sin(SLOPE) / C_i
    expected = -(L * math.sin(beta) + (p.l_r + c) * math.sin(alpha))

    def drive(delta, psi0, seconds=30.0):
        plant = plant_of()
        plant.psi = psi0
        imp = TrailedImplement("implement", {"hitch_offset": c, "drawbar": L, "mass": m_i, "cornering_stiffness": C_i})
        wired = ("x_rear", "y_rear", "vel_east_rear", "vel_north_rear", "heading", "yaw_rate", "slope_pull_east",
                 "slope_pull_north")
        rows = []
        for k in range(int(seconds / DT)):
            plant.u.update(steer_angle=delta, speed=v)
            plant.step(k * DT, DT)
            imp.u.update({name: plant.y[name] for name in wired})
            if k == 0:
                imp.initialize(0.0, DT)
            imp.step(k * DT, DT)
            rows.append((plant.psi, plant.y["y_cg"], imp.y["y"]))
        return np.array(rows)

    def plant_of():
        plant = TractorYawPlant("tractor", params)
        plant.initialize(0.0, DT)
        return plant
    b, psi0 = trimmed(plant_of, v)
    run = drive(b, psi0)
    tail = run[-500:]
    assert np.ptp(tail[:, 1]) < 1e-3                                    # the CG holds its line
    hang = float(np.mean(tail[:, 2] - tail[:, 1]))
    assert hang == pytest.approx(expected, rel=0.02), (hang, expected)
    assert abs(hang) > 1.08 * L * math.sin(beta)                         # the crab angle's share shows


def trapezoid(path: Path) -> Path:
    """A 0.32 ha quadrilateral, two of its edges slanted (UTM 32N): swaths of different lengths,
    turns between them."""
    pts = [[0, 0], [60, 0], [68, 52], [0, 48], [0, 0]]
    ring = [[300000.0 + x, 5700000.0 + y] for x, y in pts]
    path.write_text(json.dumps({"type": "FeatureCollection", "crs": {"type": "name", "properties": {"name": "EPSG:32632"}},
                                "features": [{"type": "Feature", "properties": {"name": "trapezoid"},
                                              "geometry": {"type": "Polygon", "coordinates": [ring]}}]}))
    return path


@pytest.mark.slow
def test_a_slope_mission_on_a_trapezoid_holds_2_5_cm_on_the_swaths(tmp_path):
    """Three swaths of a generated trapezoid across a 10 deg side slope, turns between them, RTK
    noise, the antenna 2.5 m up (studies/field_coverage.toml): the tractor's and the implement's
    cross-track P95 on the swaths (turns excluded, as the metrics' names say) within 2.5 cm. The
    implement swings onto the line after each turn; with the side-shift's integral slower than it
    settles (k_i = 0.5 1/s: (1 + k_p) / k_i = 4 s > L / v = 1.25 s) its integral carries the swing into the
    swath and the same mission gives 3.9 cm (checked by hand: docs/slopes-and-outages.md)."""
    field = trapezoid(tmp_path / "trapezoid.geojson")
    study = Study.load(ROOT / "studies" / "field_coverage.toml",
                       [f"field.path={field}", "field.max_swaths=3", "field.headland_work=0",
                        "tractor.slope_angle=10 deg", "tractor.slope_downhill_heading=-90 deg"])
    m = run_study(study, None, plots=False).metrics
    assert m["route_done_share"] > 0.99
    assert m["tractor_xte_swaths_p95_m"] <= 0.025 and m["implement_xte_swaths_p95_m"] <= 0.025, m
