"""A circle test (a steady turn at a constant steering command) is judged, not refused: its
steady-state gain r / (v tan(u) / L) is reported with its interval, and the dynamics are said to
be not identifiable from it. Truth: harness.small_ackermann.make_circle_log (the gain from the
machine's steering map and understeer), on two runs, and the same circle with the command's sign
reversed (a servo mapping counted the other way)."""
from __future__ import annotations

import pytest

from agrobot.identification.ordinary_driving import identify_driving, summary
from agrobot.orchestrator.study import Study
from harness.small_ackermann import make_circle_log, write_study


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    return Study.load(write_study(tmp_path_factory.mktemp("circle")))


@pytest.mark.parametrize("seed", [1, 2])
def test_circle_gives_the_steady_state_gain(study, seed):
    frame, truth = make_circle_log(seed, command=0.2 + 0.05 * seed)
    rep = identify_driving(frame, f"circle_{seed}.csv", study)
    gain = rep["steady_turn_gain"]
    assert rep["final_model"] == "steady_turn"
    assert gain["interval"][0] <= truth["steady_gain"] <= gain["interval"][1], (gain, truth)
    assert rep["parameters"]["steer_gain"]["value"] == gain["value"]
    assert not rep["parameters"]["delay"]["identifiable"] and not rep["understeer_gradient"]["identifiable"]
    assert "not identifiable from a steady turn" in summary(rep)


def test_a_reversed_input_is_a_negative_gain_said_so(study):
    frame, truth = make_circle_log(3)
    frame["delta_cmd"] = -frame["delta_cmd"]
    gain = identify_driving(frame, "circle_reversed.csv", study)["steady_turn_gain"]
    assert gain["interval"][0] <= -truth["steady_gain"] <= gain["interval"][1]
    assert "against the steering input" in gain["note"]
