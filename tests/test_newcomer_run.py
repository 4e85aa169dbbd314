"""What a newcomer meets on a first run through the shipped studies and the docs: no note about an
input the study's author left open on purpose, counts printed with their noun's number, a sweep too
short for its own bounds refused before its first point, a saved fields result loaded with its track."""
from __future__ import annotations

import math
import types

import numpy as np
import pytest

from agrobot.components.models.figure8_path import Figure8Path
from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.mcap_out import LiveView
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study
from agrobot.studies import shipped
from tests.commands import cli, refused

STUDIES = sorted(p.name for p in shipped().glob("*.toml"))


@pytest.mark.parametrize("name", STUDIES)
def test_a_shipped_study_says_no_held_input_note(name):
    """Every input a shipped study leaves open is named in its [study] allow_unconnected (its
    author's choice, recorded in run.json): a newcomer's run prints no 'is unconnected' note."""
    system = build_system(resolve(Study.load(shipped(name))))
    assert system.held_lines() == []


def test_the_live_view_counts_with_the_noun_in_its_number(tmp_path):
    """One viewer is '1 viewer', one instant '1 instant', one message '1 message'; none or two take the plural."""
    one = types.SimpleNamespace(sent=1, url="ws://127.0.0.1:1", max_viewers=1,
                                viewers={"foxglove.sdk.v1": 1, "dropped": 1, "closed_slow": 1})
    said = LiveView.report.fget(one)
    assert said.startswith("1 instant sent to ws://127.0.0.1:1; 1 viewer (1 foxglove.sdk.v1)"), said
    assert "1 message dropped" in said and "1 viewer closed" in said and "viewers" not in said.split("(")[0]
    two = types.SimpleNamespace(sent=2, url="u", max_viewers=2, viewers={})
    assert LiveView.report.fget(two) == "2 instants sent to u; 0 viewers"
    # the line the run prints as it starts serving, with --live-viewers 1
    done = cli("run", shipped("figure8.toml"), "--out", tmp_path / "run", "--no-plots", "--live", "127.0.0.1:0",
               "--live-viewers", "1", "--set", "study.stop_time=20", timeout=120)
    assert done.returncode == 0, done.stderr
    assert "to at most 1 viewer (" in done.stdout and "1 viewers" not in done.stdout, done.stdout


def test_a_sweep_too_short_for_a_bound_is_refused_before_any_point_runs(tmp_path):
    """speed_sweep.toml cut to 30 s: the figure-8's reference (2 m/s, 8 s ramp, then 5 s settling)
    reaches no straight before it ends, so euclid_max_straight has no value in any point. Refused
    after the nominal run, naming the file, study.stop_time and the length that reaches a straight."""
    out = tmp_path / "short"
    done = cli("sweep", shipped("speed_sweep.toml"), "--out", out, "--engine", "python", "--workers", "1",
               "--no-progress", "--set", "study.stop_time=30", timeout=300)
    said = refused(done, str(shipped("speed_sweep.toml")), "study.stop_time = 30 s", "euclid_max_straight",
                   "--set study.stop_time=")
    need = float(said.rsplit("--set study.stop_time=", 1)[1].split()[0])
    # the reference (2 m/s, ramp T = 8 s: s = v (t - T/2) past it) is settled at T + 5 s = 13 s; the
    # first straight after that starts where the path's own segment label turns 0 (Figure8Path)
    path, v, ramp = Figure8Path(10.0, 20.0), 2.0, 8.0
    s = next(s for s in np.arange(v * (13.0 - ramp / 2), 1000.0, 0.01) if path.pose(s)[4] == 0)
    assert need == math.ceil(ramp / 2 + s / v + 1.0), said
    assert not (out / "points").exists() or not any((out / "points").iterdir())
    assert not (out / "nominal").exists()
