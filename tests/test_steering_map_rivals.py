"""A steering map's rivals on generated logs with a known truth: the track's side-slip driven through
the map (a gain error is no antenna lever arm), and a steering offset against a side slope on a log
driven along one heading (harness.steering_maps plants the map, harness.truth_tractor drives the car);
and the pair screen that rules such rivals out counts a measurement by its own updates."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from agrobot.diagnosis.baseline import baseline_from_study
from agrobot.diagnosis.candidates import Replay
from agrobot.diagnosis.selection import Selector
from agrobot.orchestrator.study import Study
from harness.diagnosis_classes import class_log
from harness.hidden_effects import BASELINES
from harness.steering_maps import read_through
from harness.truth_tractor import make_log


def test_the_tracks_side_slip_follows_the_wheels_a_steering_gain_turns():
    """A car whose wheels turn 0.8 x the reading slips its rear axle 0.8 x as much as the reading says;
    the replay at the truth's stiffnesses and gain follows the truth's own lateral velocity (logged,
    never fitted to) within a tenth; the reading's side-slip is a quarter off."""
    frame, truth = make_log(1001, None, duration=60.0, vehicle="car", lateral=True)
    frame = read_through(frame, gain=0.8)
    baseline = baseline_from_study(Study.load(BASELINES["car"]))
    replay = Replay(frame.drop(columns=["vy", "beta"]), baseline)
    p = baseline.tractor
    v = {**baseline.values, "cornering_front_scale": truth["C_f"] / p.C_f, "cornering_rear_scale": truth["C_r"] / p.C_r}
    rear = frame["vy"].to_numpy() - p.l_r * frame["yaw_rate"].to_numpy()
    keep = replay.scored("yaw")

    def off(gain: float) -> float:
        err = (replay.lateral({**v, "steering_gain": gain}) - rear)[keep]
        return float(np.sqrt(np.mean(err ** 2)) / np.sqrt(np.mean(rear[keep] ** 2)))

    assert off(0.8) < 0.1, off(0.8)
    assert off(1.0) > 0.2, off(1.0)
    track = replay.predicted_many("position", [{**v, "steering_gain": 0.8}, {**v, "steering_gain": 1.0}])
    assert np.max(np.abs(track[0] - track[1])) > 0.1          # the batched track reads the map too


def selected(frame, study: Path, ids: tuple[str, ...]):
    """The selection on ``frame`` with only the effects ``ids`` as candidates."""
    selector = Selector(Replay(frame, baseline_from_study(Study.load(study))), 0.05, screen=False)
    selector.catalogue = [e for e in selector.catalogue if e.id in ids]
    return selector.run()


def test_an_offset_on_one_heading_is_named_before_a_slope_that_only_ties_it(tmp_path):
    """A car driven along one heading (within 25 deg) with its steering zero off by the planted offset:
    a side slope's pull across that heading is the offset's (its fall line unresolved; its dBIC 2 below
    the offset's on this log); the offset, one parameter, is named with its value and the slope
    reported as not told apart."""
    frame, truth = class_log("steering_map_offset", 1002, "car", 120.0)
    sel = selected(frame, BASELINES["car"], ("side_slope", "steering_offset"))
    assert [f.effect.id for f in sel.effects] == ["steering_offset"], sel.trace
    offset = sel.effects[0].fit.values["steer_angle_offset"]
    assert abs(offset - truth["map_offset"]) < 0.15 * abs(truth["map_offset"]), (offset, truth["map_offset"])
    assert [t["effects"] for t in sel.inconclusive] == [["steering_offset", "side_slope"]]


def test_a_slope_driven_on_every_heading_stays_a_slope():
    """The tractor turns round on its field: the planted slope's pull reverses with the heading, which
    no offset does; the slope is named, with no tie."""
    frame, truth = make_log(1001, "side_slope", duration=90.0)
    sel = selected(frame, BASELINES["tractor"], ("side_slope", "steering_offset"))
    assert [f.effect.id for f in sel.effects] == ["side_slope"], sel.trace
    assert not sel.inconclusive



class HeldReading:
    """A replay stand-in: white residuals r0 - p x, 400 rows, of a measurement with 100 updates of its own."""

    def __init__(self) -> None:
        rng = np.random.default_rng(7)
        self.r0, self.x = rng.standard_normal(400), rng.standard_normal(400)

    def residuals(self, stage, values, part):
        return self.r0 - values["p"] * self.x

    def residuals_many(self, stage, sets, part):
        return [self.residuals(stage, v, part) for v in sets]

    def updates(self, stage):
        return 100


def test_the_screen_counts_a_measurement_by_its_own_updates():
    """400 rows of white residuals hold 400 effective samples by their autocorrelation, but the
    measurement updated 100 times: the pair screen counts 100, as the fits do (estimation.effective_size)."""
    from types import SimpleNamespace

    from agrobot.diagnosis.screen import Screen
    from agrobot.estimation import Parameter

    candidate = SimpleNamespace(id="p", parameters=(Parameter("p", "1", 1.0, -1.0, 1.0),))
    screened = Screen(HeldReading(), {"yaw": 1.0}, -10.0).judge({"p": 0.0}, [], [candidate], ("yaw",))
    assert screened.sizes["yaw"] == 100.0, screened.sizes
