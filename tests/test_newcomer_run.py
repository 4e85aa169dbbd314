"""What a newcomer meets on a first run through the shipped studies and the docs: no note about an
input the study's author left open on purpose, counts printed with their noun's number, a sweep too
short for its own bounds refused before its first point, a saved fields result loaded with its track."""
from __future__ import annotations

import pytest

from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study
from agrobot.studies import shipped

STUDIES = sorted(p.name for p in shipped().glob("*.toml"))


@pytest.mark.parametrize("name", STUDIES)
def test_a_shipped_study_says_no_held_input_note(name):
    """Every input a shipped study leaves open is named in its [study] allow_unconnected (its
    author's choice, recorded in run.json): a newcomer's run prints no 'is unconnected' note."""
    system = build_system(resolve(Study.load(shipped(name))))
    assert system.held_lines() == []
