"""What a command shows when it ends and while it works: key figures judged against the bounds the
analysis declares (or the study's), the sweep's percentiles and failures grouped by reason (exit 2
when every point failed for one reason), progress in the unit of the work."""
from __future__ import annotations

import io
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from agrobot.orchestrator.key_figures import parse_bound, run_table
from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.study import load_study
from tests import commands

ROOT = Path(__file__).resolve().parent.parent
CMD = [sys.executable, "-m", "agrobot"]


@pytest.mark.parametrize("text, op, value", [("< 0.40", "<", 0.40), (">= 0.99", ">=", 0.99), ("0", "==", 0.0),
                                              ("<= 0.05 (RTK class +-0.025)", "<=", 0.05), ("<1e-3", "<", 1e-3)])
def test_a_statement_that_begins_with_a_comparison_is_a_bound(text, op, value):
    bound = parse_bound(text, "paper")
    assert (bound.op, bound.value) == (op, value)
    assert parse_bound("steady-state error seen", "paper") is None and parse_bound("0.3x", "study") is None
    assert parse_bound("< 0.40", "paper").holds(0.39) and not parse_bound("< 0.40", "paper").holds(0.40)
    assert not parse_bound("< 0.40", "paper").holds(float("nan"))


def test_pure_pursuit_fails_the_papers_straight_bound_on_screen_and_the_study_can_tighten_it():
    """The paper's 0.40 m on straights (section VI-B), declared by the analysis: pure pursuit's
    error is above it (FAIL), the paper's law is below it (pass); a study's bound is judged too."""
    pursuit = run_study(load_study(ROOT / "studies" / "figure8_pure_pursuit.toml"), None, plots=False)
    paper = run_study(load_study(ROOT / "studies" / "figure8.toml", ['study.bounds.euclid_max_curved="< 0.1"']),
                      None, plots=False)
    assert pursuit.metrics["euclid_max_straight"] > 0.40 > paper.metrics["euclid_max_straight"]
    row = next(line for line in pursuit.summary.splitlines() if line.startswith("euclid_max_straight "))
    assert "< 0.40 (paper)" in row and " FAIL  " in row and row.endswith("m above the bound")   # with its reason
    assert [f.split(" =")[0] for f in pursuit.failed_bounds] == ["euclid_max_straight"]
    row = next(line for line in paper.summary.splitlines() if line.startswith("euclid_max_straight "))
    assert row.endswith("pass")
    row = next(line for line in paper.summary.splitlines() if line.startswith("euclid_max_curved "))
    assert "< 0.1 (study)" in row and "FAIL" in row.split() and "above the bound" in row
    table, failed = run_table({"a": 0.5}, None, {})
    assert "a" in table and not failed               # a study without an analysis: its numbers, no judgement


def _sweep_study(tmp_path: Path, fail_times: list[float]) -> Path:
    path = tmp_path / "sweep.toml"
    path.write_text(f"""
[study]
name = "toy_sweep"
stop_time = 1.0
base_step = 0.05
seed = 1

[components.f]
type = "tests.toy_components:FailAt"
parameters = {{ fail_time = 5.0 }}

[sweep]
mode = "grid"
[sweep.parameters]
"f.fail_time" = {fail_times}
""")
    return path


@pytest.mark.slow
def test_a_sweep_whose_points_all_fail_for_one_reason_exits_2_and_says_it(tmp_path):
    study = _sweep_study(tmp_path, [0.2, 0.4, 0.6])          # each fails, at its own instant, for one reason
    proc = subprocess.run(CMD + ["sweep", str(study), "--out", str(tmp_path / "s"), "--workers", "1", "--no-progress"],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2, proc.stderr
    assert "error: every point failed: f: deliberate failure" in proc.stderr and "Traceback" not in proc.stderr
    assert "3 x f: deliberate failure  (p0000, p0001, p0002)" in proc.stdout
    mixed = _sweep_study(tmp_path, [0.2, 3.0, 0.6, "abc"])
    proc = subprocess.run(CMD + ["sweep", str(mixed), "--out", str(tmp_path / "m"), "--workers", "1", "--no-progress",
                                 "--no-plots"], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2 and "f.fail_time" in proc.stderr        # a value refused before any point runs
    mixed.write_text(mixed.read_text().replace(", 'abc'", ""))
    proc = subprocess.run(CMD + ["sweep", str(mixed), "--out", str(tmp_path / "m"), "--workers", "1", "--no-progress",
                                 "--no-plots"], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 1, proc.stderr
    assert "3 of 3 points, 1 completed, 2 failed" in proc.stdout
    assert "2 x f: deliberate failure  (p0000, p0002)" in proc.stdout


def test_a_sweep_ends_with_the_percentiles_of_its_key_figures_and_their_bounds(tmp_path):
    from agrobot.orchestrator.study import Study
    from agrobot.orchestrator.sweep import SweepRun, sweep_summary

    study = Study.load(ROOT / "studies" / "robustness.toml", ["sweep.samples=4", "study.stop_time=40"])
    table = SweepRun(study, tmp_path / "r").run(2, progress=False)
    text, reasons = sweep_summary(study, table)
    assert not reasons and "4 of 4 points, 4 completed, 0 failed" in text
    row = next(line for line in text.splitlines() if line.startswith("euclid_max_straight "))
    x = table["euclid_max_straight"].to_numpy()
    p50, p95 = np.percentile(x, 50), np.percentile(x, 95)
    printed = [float(v) for v in row.split()[2:5]]
    assert printed == pytest.approx([p50, p95, x.max()], rel=1e-3)
    inside = int((x < 0.40).sum())
    assert "< 0.40 (paper)" in row and row.endswith(f"{inside} of 4 ({100 * inside / 4:.0f}%)")
    assert "within both of the paper's bounds:" in text          # the robustness analysis's own line


def test_progress_is_told_in_the_unit_a_component_reports(monkeypatch, capsys):
    """A component reporting (done, total, unit) sets the progress line; the field route reports
    metres of its route."""
    from agrobot.orchestrator.build import build_system
    from agrobot.orchestrator.engine import Simulation
    from agrobot.orchestrator.observers import Progress
    from agrobot.orchestrator.resolver import resolve
    from agrobot.orchestrator.study import parse_study
    from tests import toy_components

    class Walker(toy_components.FailAt):
        def run_progress(self):
            return 2.0 * self.y["value"], 2.0, "m"

    monkeypatch.setattr(toy_components, "Walker", Walker, raising=False)
    study = parse_study({"study": {"name": "w", "stop_time": 1.0, "base_step": 0.05, "seed": 1},
                         "components": {"w": {"type": "tests.toy_components:Walker", "parameters": {"fail_time": 9.0}}}})
    sim = Simulation(build_system(resolve(study)))
    sim.add_observer(Progress(sim.n_steps, sim.h, every=0.0, first=0.0))
    sim.start()
    for k in (5, 10, 20):
        sim.advance(k)
    lines = [line for line in capsys.readouterr().err.splitlines() if line.startswith("progress:")]
    assert lines[0].startswith("progress: w 0.4 of 2 m (20%)") and lines[-1].startswith("progress: w 1.9 of 2 m (95%)")
    field = load_study(ROOT / "studies" / "field_coverage.toml", ["field.max_swaths=2"])
    route = build_system(resolve(field)).nodes["field"].component
    route.initialize(0.0, 0.05)
    done, total, unit = route.run_progress()
    assert (done, unit) == (0.0, "m") and total == pytest.approx(float(route.end)) and total > 100


def test_a_step_that_lasts_says_what_it_does_and_how_far_it_is(monkeypatch):
    from agrobot.orchestrator import observers

    class Kept(io.StringIO):
        def close(self):                 # the stage closes the terminal stream it opened
            pass

    out = Kept()
    monkeypatch.setattr(observers, "_terminal", lambda: out)
    with observers.Stage("compiling", first=0.01, every=0.01) as stage:
        observers.report_progress(3, 11, "FMUs")
        end = time.time() + 10
        while not stage.printed and time.time() < end:
            time.sleep(0.01)
    text = out.getvalue()
    assert "compiling: 3 of 11 FMUs ..." in text and "compiling: done in" in text
    quiet = Kept()
    monkeypatch.setattr(observers, "_terminal", lambda: quiet)
    with observers.Stage("quick", first=60.0):
        pass
    assert quiet.getvalue() == ""


def test_of_nested_steps_only_the_innermost_speaks_and_every_tool_runs_inside_one(monkeypatch):
    from agrobot.orchestrator import cli, observers

    class Kept(io.StringIO):
        def close(self):
            pass

    out = Kept()
    monkeypatch.setattr(observers, "_terminal", lambda: out)
    with observers.Stage("plan", first=0.1, every=0.01) as outer:
        with observers.Stage("placing swaths", first=0.01, every=0.01) as inner:
            end = time.time() + 10
            while not inner.printed and time.time() < end:
                time.sleep(0.01)
            time.sleep(0.3)                                          # the outer's time is long due
            shown, outer_spoke = out.getvalue(), outer.printed     # while the inner step runs
    assert "placing swaths ..." in shown and "plan ..." not in shown and not outer_spoke
    # a registered command (not run or sweep) is handed its arguments inside a stage named after it
    seen = []

    def tool(args):
        seen.append(list(observers._STAGES))
        return 0

    handler = cli._in_stage("identify", tool)
    assert handler(None) == 0 and [s.what for s in seen[0]] == ["identify"] and observers._STAGES == []
    parser = cli.build_parser()
    assert parser.parse_args(["run", "x.toml", "--out", "o"]).handler is cli._run


def test_a_real_time_run_that_misses_deadlines_warns_on_screen(tmp_path):
    """The command's own words: pacing statistics and a warning, both from metrics.json's counts."""
    import json

    proc = commands.cli("run", "studies/figure8_hardware_layout.toml", "--out", tmp_path / "rt", "--no-plots",
                        "--set", "study.realtime=true", "--set", "study.stop_time=2",
                        "--set", "study.realtime_tolerance=-0.0", "--set", 'study.analysis=""', timeout=120)
    assert proc.returncode == 0, proc.stderr
    rt = json.loads((tmp_path / "rt" / "metrics.json").read_text())["realtime"]
    assert rt["steps"] == 41
    assert f"41 steps of 50 ms; {rt['deadline_misses']} started more than" in proc.stdout
    assert ("warning: real time was not kept" in proc.stderr) == (rt["deadline_misses"] > 0)
    assert "{" not in proc.stdout                    # a table, not raw JSON
