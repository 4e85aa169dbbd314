"""The Python API (agrobot.api) and its typed results: the "From Python" page runs as it stands,
and what it finds is checked against truths that do not come from the code under test (the
hidden effect of a generated log, the plant's own steady-state gain, the bounds as written)."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from tests.markdown_code import run_page

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    folder = tmp_path_factory.mktemp("from_python")
    return run_page(ROOT / "docs" / "from-python.md", folder), folder


@pytest.mark.slow
def test_the_from_python_page_runs_and_its_runs_are_what_the_study_says(session):
    ns, folder = session
    base, late = ns["base"], ns["late"]
    t = base.signals["t"].to_numpy()
    assert t[0] == 0.0 and t[-1] == pytest.approx(30.0) and np.allclose(np.diff(t), 0.01)
    # every bounded figure judged as its bound reads (paper: max distance on the curves < 0.60 m)
    curved = base.metrics["euclid_max_curved"]
    assert curved.bound == "< 0.60" and curved.source == "paper" and curved.passed == (curved.value < 0.60)
    assert set(base.failed) == {k for k, m in base.metrics.items() if m.passed is False}
    # the delayed command is in the signals: the steering command reaches the actuator one 50 ms sample late
    cmd, out = late.signals["mpc.steer_angle_cmd"].to_numpy(), late.signals["command_link.steer_angle_cmd_out"].to_numpy()
    assert np.allclose(out[1000:2000], cmd[995:1995])
    assert late.values["yaw_rate_rms_error"] != base.values["yaw_rate_rms_error"]
    assert (folder / "compare.png").stat().st_size > 10_000


@pytest.mark.slow
def test_identification_from_python_finds_the_plants_steady_state_gain(session):
    from agrobot.components.models.yaw_dynamics import TractorParameters

    ns, _ = session
    assert ns["experiment"].method == "study" and ns["from_log"].method == "multisine"
    fit = ns["from_log"].report["models"]["second_order"]
    p = TractorParameters()                    # the identification study's plant: the paper's table
    v, L = 2.0, p.l_f + p.l_r
    K = p.m * (p.l_r * p.C_r - p.l_f * p.C_f) / (L * p.C_f * p.C_r)      # understeer gradient [rad/(m/s2)]
    truth = v / (L + K * v ** 2)               # steady-state yaw rate per wheel angle (bicycle model)
    assert fit["num"][-1] / fit["den"][-1] == pytest.approx(truth, rel=0.15)


@pytest.mark.slow
def test_diagnosis_from_python_names_the_hidden_delay_and_writes_only_when_asked(session):
    ns, folder = session
    found, truth = ns["found"], ns["truth"]
    assert found.verdict == truth["effect"] == "actuator_delay"
    assert found.effects[0]["parameters"]["command_delay"] == pytest.approx(truth["delay"], abs=0.03)
    written = {p.name for p in (folder / "diagnosis").iterdir()}     # as diagnose --out writes it
    assert {"diagnosis.json", "report.md"} <= written and {p for p in written if p.endswith(".png")}
    assert json.loads((folder / "diagnosis" / "diagnosis.json").read_text())["verdict"] == "actuator_delay"
    assert not (folder / "diagnosis.json").exists()       # diagnose() without out= wrote nothing


def test_a_bad_log_gives_cannot_decide_in_memory_and_nothing_written(tmp_path):
    import agrobot

    log = tmp_path / "short.csv"
    log.write_text("t,delta_cmd,delta,v,yaw_rate,x,y\n0,0,0,1,0,0,0\n0.1,0,0,1,0,0.1,0\n")
    found = agrobot.diagnose(log)
    assert found.verdict == "cannot decide" and str(log) in found.reason
    assert sorted(p.name for p in tmp_path.iterdir()) == ["short.csv"]


def test_a_shipped_study_by_name_and_a_wrong_name_is_refused_by_name():
    import agrobot
    from agrobot.orchestrator.study import StudyError

    study = agrobot.load("figure8", set={"study.stop_time": 12.5, "tracker.lookahead": 1.5})
    assert study.study.stop_time == 12.5 and study.components["tracker"].parameters["lookahead"] == 1.5
    with pytest.raises(StudyError, match="figure9: no such study file, nor a shipped study .shipped: .*figure8"):
        agrobot.load("figure9")


def test_import_agrobot_stays_light():
    import subprocess
    import sys

    code = "import sys, agrobot; print(sorted(m for m in ('pandas', 'scipy', 'matplotlib', 'agrobot.api') if m in sys.modules))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.stdout.strip() == "[]", done.stdout + done.stderr


def test_plan_from_python_covers_a_rectangle_with_the_swaths_its_width_needs(tmp_path):
    """A 100 m x 80 m rectangle worked 3 m wide along its long side inside five headland passes: the
    inner field, 80 - 2 * 5 * 3 = 50 m across, takes about 50 / 3 swaths."""
    import agrobot

    field = tmp_path / "rect.geojson"
    ring = [[500_000 + x, 5_000_000 + y] for x, y in [(0, 0), (100, 0), (100, 80), (0, 80), (0, 0)]]   # UTM 33N, on its central meridian
    field.write_text(json.dumps({"type": "FeatureCollection", "features": [{"type": "Feature", "properties":
                     {"name": "rect"}, "geometry": {"type": "Polygon", "coordinates": [ring]}}]}))
    made = agrobot.plan(field, crs="EPSG:32633", working_width=3.0, driving_angle=0.0, headland_passes=5)
    s = made.summary
    assert s["area_ha"] == pytest.approx(0.8, rel=2e-3)          # the UTM scale factor 0.9996
    assert s["headland_passes"] == 5 and s["driving_angle_deg"] == 0.0
    assert math.floor(50 / 3.0) <= s["swaths"] <= math.ceil(50 / (3.0 - 0.05)) + 1
    route = made.route()
    assert set(route.columns) >= {"s", "x", "y", "heading", "speed", "kind"}
    assert not any(tmp_path.glob("*.png"))
    made.save(tmp_path / "plan")
    assert {"route.csv", "plan.json", "plan.png"} <= {p.name for p in (tmp_path / "plan").iterdir()}


def test_convert_from_python_reads_a_generated_drive_and_saves_it_as_the_command_does(tmp_path):
    """A 30 s NMEA drive east at 2 m/s (harness.generated_recordings): the GNSS speed is
    2 m/s, x grows by 2 m/s, y stays; nothing is written until save."""
    import agrobot
    from harness.generated_recordings import write_nmea

    nmea = write_nmea(tmp_path / "drive.nmea", 30.0)
    rec = agrobot.convert(nmea)
    log = rec.log
    assert sorted(p.name for p in tmp_path.iterdir()) == ["drive.nmea"]
    assert np.median(log["gnss_speed"]) == pytest.approx(2.0, abs=0.02)
    slope = np.polyfit(log["t"], log["x"], 1)[0]
    assert slope == pytest.approx(2.0, rel=0.01) and np.ptp(log["y"]) < 0.05
    rec.save(tmp_path / "drive.csv")
    assert json.loads((tmp_path / "drive.import.json").read_text())["used"] == rec.report["used"]
    assert len(np.loadtxt(tmp_path / "drive.csv", delimiter=",", skiprows=1, ndmin=2)) == len(log)
