"""``tune``: gains proposed for a perturbed tractor meet their predicted margins in simulation and
the paper's bounds; the proposal is a study that extends the original; bad options exit 2."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from agrobot.analysis.margins_simulation import simulated_run
from agrobot.analysis.tune import Targets, propose
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.study import Study
from tests.commands import cli

ROOT = Path(__file__).resolve().parents[1]
FIGURE8 = ROOT / "studies" / "figure8.toml"
PERTURBED = """# the figure-8 on a tractor with 30 % softer front tyres and 0.1 s more delay in the steering
extends = "{figure8}"

[study]
name = "figure8_perturbed"

[components.tractor]
parameters = {{ cornering_scale_front = 0.7 }}

[components.steering]
parameters = {{ command_delay = 0.1 }}
"""


@pytest.fixture
def perturbed(tmp_path) -> Path:
    path = tmp_path / "perturbed.toml"
    path.write_text(PERTURBED.format(figure8=FIGURE8.as_posix()))
    return path


@pytest.mark.slow
def test_tuned_gains_for_a_perturbed_tractor_hold_their_margins_and_the_bounds(perturbed, tmp_path):
    """Targets: 0.3 s delay margin, 45 deg, 6 dB (a coarse grid, for time). Predicted margins meet
    them; in simulation the loop holds with the 0.3 s extra delay the target asks and with 0.8 x the
    predicted delay margin (the tolerance of tests/test_margins.py); the tuned figure-8 stays within
    the paper's 0.40 / 0.60 m."""
    targets = Targets(delay=0.3, phase_deg=45.0, gain_db=6.0)
    proposal = propose(Study.load(perturbed), targets, grid=0.5)
    point = proposal.after.points[0]
    whole = point.loops["whole loop"]
    assert whole.delay >= 0.3 and whole.phase_deg >= 45.0 and whole.gain_db >= 6.0
    an = proposal.after.anatomy
    assert an.own_delay == pytest.approx(0.1)
    tuned_file = tmp_path / "tuned.toml"
    tuned_file.write_text(proposal.text)
    tuned = Study.load(tuned_file)
    assert tuned.to_data()["components"] == proposal.study.to_data()["components"]
    assert simulated_run(tuned, an, an.own_delay + targets.delay, 80.0).stable
    assert simulated_run(tuned, an, an.own_delay + 0.8 * whole.delay, 80.0).stable
    m = run_study(tuned, None, plots=False).metrics
    assert m["euclid_max_straight"] < 0.40 and m["euclid_max_curved"] < 0.60, m


@pytest.mark.slow
def test_tune_writes_a_small_study_that_extends_the_original(perturbed, tmp_path):
    out = tmp_path / "tuned.toml"
    proc = subprocess.run([sys.executable, "-m", "agrobot", "tune", str(perturbed), "--out", str(out),
                           "--no-simulation", "--delay-margin", "0.2", "--grid", "0.5"], cwd=ROOT, capture_output=True, text=True,
                          timeout=900)
    assert proc.returncode == 0, proc.stderr
    text = out.read_text()
    assert f'extends = "{perturbed.resolve().as_posix()}"' in text and "lookahead" in text and len(text) < 1500
    assert "delay margin [s]" in proc.stdout and "proposed" in proc.stdout
    tuned = Study.load(out)
    assert resolve(tuned).parameters("tracker")["lookahead"] > 0.4


def test_identified_model_becomes_plant_and_controller_model(tmp_path):
    from agrobot.analysis.tune import identified_values

    ident = tmp_path / "identification.json"
    ident.write_text(json.dumps({"models": {"second_order": {"num": [250.0], "den": [1.0, 9.0, 220.0]}}}))
    values = identified_values(Study.load(FIGURE8), ident, "second_order")
    assert values == {"tractor.model": "transfer_function", "tractor.tf_num": [250.0], "tractor.tf_den": [1.0, 9.0, 220.0],
                      "mpc.num": [250.0], "mpc.den": [1.0, 9.0, 220.0]}


@pytest.mark.parametrize("args, words", [
    (["--out", "{tmp}/t.txt"], ["--out", ".toml"]),
    (["--out", "{tmp}/t.toml", "--delay-margin", "-1"], ["--delay-margin", ">= 0"]),
    (["--out", "{tmp}/t.toml", "--identified", "{tmp}/none.json"], ["--identified", "not found"]),
    (["--out", "{tmp}/t.toml", "--identified", "{tmp}/ident.json", "--model", "bicycle"], ["no model 'bicycle'", "second_order"]),
    pytest.param(["--out", "{tmp}/t.toml", "--delay-margin", "3", "--grid", "0.25"], ["no gains", "lower"],
                 marks=pytest.mark.slow),
    (["--out", "{tmp}/t.toml", "--grid", "0"], ["--grid"]),
])
def test_tune_bad_options_exit_2_with_a_message(tmp_path, args, words):
    (tmp_path / "ident.json").write_text(json.dumps({"models": {"second_order": {"num": [291.0], "den": [1, 10.9, 242]}}}))
    argv = [a.replace("{tmp}", str(tmp_path)) for a in args]
    proc = cli("tune", "studies/figure8.toml", *argv, "--no-simulation", timeout=900)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    for word in words:
        assert word in proc.stderr, proc.stderr
    assert not (tmp_path / "t.toml").exists()
