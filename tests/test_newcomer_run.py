"""What a newcomer meets on a first run through the shipped studies and the docs: no note about an
input the study's author left open on purpose, counts printed with their noun's number, a sweep too
short for its own bounds refused before its first point, a saved fields result loaded with its track."""
from __future__ import annotations

import types

import pytest

from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.mcap_out import LiveView
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study
from agrobot.studies import shipped
from tests.commands import cli

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
