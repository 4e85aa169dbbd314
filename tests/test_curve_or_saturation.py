"""A steering-ratio curve against tyre saturation on a car driven into its tyres: the curve bends
the yaw gain with delta, the saturation with a_y = v r; turns at one speed have a_y a function of
delta (collinear: no fit tells the two apart), turns at several speeds do not.

Independent truth: harness.truth_tractor's "car_hard" (the passenger car at 15-35 m/s, |a_y| to
10 m/s2), its tyres saturating as F = C alpha / (1 + |alpha| / alpha_s) (alpha_s 6 deg), its
wheel-angle sensor reading a ratio curve c = -8 1/rad2 (the wheels turn delta (1 + c delta^2):
8 % less at 0.1 rad); one speed is the driving plan's segments all at 25 m/s."""
from __future__ import annotations

import pytest

from agrobot.diagnosis.baseline import baseline_from_study
from agrobot.diagnosis.candidates import Replay
from agrobot.diagnosis.curve_or_saturation import COLLINEAR, turn_collinearity
from agrobot.diagnosis.selection import Selector
from agrobot.orchestrator.study import Study
from harness.hidden_effects import BASELINES
from harness.truth_tractor import make_log

MAPS = ("steering_gain", "steering_ratio_curve")
PLANTED = {"alpha_s": 0.105, "ratio_curvature": -8.0}


def replay(speeds=None) -> Replay:
    frame, _ = make_log(1101, "tyre_saturation+steering_ratio_curve", duration=120.0, vehicle="car_hard",
                        values=PLANTED, speeds=speeds)
    frame = frame.drop(columns=["x", "y", "delta_cmd"])
    return Replay(frame, baseline_from_study(Study.load(BASELINES["car"])))


def test_turns_at_one_speed_are_collinear_and_at_three_they_are_not():
    """At 25 m/s only, a_ss = v^2 delta / (L + K v^2) is delta x one constant: correlation 1; at 15, 25 and
    35 m/s one delta has three a_ss (the harness's cycle of speeds), the correlation below COLLINEAR."""
    one = turn_collinearity(replay((25.0,)))
    three = turn_collinearity(replay())
    assert one is not None and one.collinear and one.correlation > 0.999, one
    assert three is not None and not three.collinear and three.correlation < COLLINEAR, three
    assert three.speeds[1] - three.speeds[0] > 10.0 > one.speeds[1] - one.speeds[0], (one, three)


def test_a_curve_on_a_car_saturating_at_one_speed_cannot_be_told_from_the_saturation():
    """The planted curve and saturation driven at 25 m/s only: whatever the fits, the curve is not named
    alone; it is tied with tyre_saturation as "cannot decide", the reason naming the turns' collinearity
    and its correlation."""
    selector = Selector(replay((25.0,)), 0.05, screen=False,
                        saturation={"friction": 1.0, "shape": 1.3, "held_out_gain": 0.2})
    selector.catalogue = [e for e in selector.catalogue if e.id in MAPS + ("tyre_saturation",)]
    sel = selector.run()
    maps = {f.effect.id for f in sel.effects} & set(MAPS)
    ties = {t["effects"][0]: t for t in sel.inconclusive if t.get("undecided") and t["effects"][1] == "tyre_saturation"}
    assert "steering_ratio_curve" in maps, (maps, sel.trace)
    assert "steering_ratio_curve" in ties, (sel.inconclusive, sel.trace)
    why = ties["steering_ratio_curve"]["why"]
    assert "collinear in delta and a_y" in why and "correlate at 1.000" in why, why


@pytest.mark.slow
def test_a_curve_on_a_car_saturating_at_three_speeds_is_tied_by_the_fit_not_the_driving():
    """The same car driven at 15, 25 and 35 m/s: its turns are not collinear, so a tie is not the driving's
    to blame. The catalogue's Magic Formula tyre fitted beside the curve does not follow this truth's tyre
    (F = C alpha / (1 + |alpha| / alpha_s) bends from the smallest slip): no curve is concluded alone, and
    the tie says that the turns would separate the two and that the joint fit does not."""
    selector = Selector(replay(), 0.05, screen=False,
                        saturation={"friction": 1.0, "shape": 1.3, "held_out_gain": 0.2})
    selector.catalogue = [e for e in selector.catalogue if e.id in MAPS + ("tyre_saturation",)]
    sel = selector.run()
    maps = {f.effect.id for f in sel.effects} & set(MAPS)
    ties = {t["effects"][0]: t for t in sel.inconclusive if t.get("undecided") and t["effects"][1] == "tyre_saturation"}
    assert maps <= set(ties), (maps, sel.inconclusive, sel.trace)
    why = ties["steering_ratio_curve"]["why"]
    assert "its turns are not collinear" in why and "the tie is the joint fit's" in why, why
