"""The diagnosis' least-squares search (diagnosis.weighted_search) on a generated car log with a planted
antenna lever arm, fitted on the side-slip block (yaw, position, speed) as the selection fits it: a
search again at new stage levels started from the kept residuals and Jacobian lands where a fresh
search does with fewer replays, and the search's stopping tolerance leaves the lever arm where
scipy's default tolerances put it, a small fraction of its interval away, near the planted truth; a
fit asked for again is recalled (diagnosis.fit_memo), not searched, as a copy of its own."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import agrobot.diagnosis.weighted_search as weighted_search
from agrobot.diagnosis.baseline import baseline_from_study
from agrobot.diagnosis.candidates import Replay, _fit, fit_baseline, refit_free
from agrobot.diagnosis.catalogue import CATALOGUE
from agrobot.diagnosis.fit_memo import forget
from agrobot.diagnosis.weighted_search import WeightedSearch
from agrobot.orchestrator.study import load_study
from harness.truth_tractor import make_log

ROOT = Path(__file__).resolve().parent.parent
LEVER = next(e for e in CATALOGUE if e.id == "antenna_lever_arm")


@pytest.fixture(scope="module")
def case():
    """(replay, the baseline fit, its levels, the truth) of a 60 s car log with a lever arm."""
    frame, truth = make_log(4, "antenna_lever_arm", duration=60.0, vehicle="car")
    replay = Replay(frame, baseline_from_study(load_study(ROOT / "studies" / "passenger_car.toml")))
    assert len(replay.side_slip_block) == 3           # the block whose fits are weighed again
    base, sigma = fit_baseline(replay)
    return replay, base, sigma, truth


class Counted:
    """The replay, its batched residual calls counted."""

    def __init__(self, replay) -> None:
        self.replay, self.calls = replay, 0

    def residuals_many(self, *args):
        self.calls += 1
        return self.replay.residuals_many(*args)


def test_search_again_at_new_levels_starts_from_the_kept_residuals(case):
    replay, base, sigma, _ = case
    free = refit_free(replay, replay.side_slip_block, [LEVER])

    def values_of(x):
        return {**base.values, **{p.name: float(xi) * p.scale for p, xi in zip(free, x)}}
    lo, hi = np.array([p.lower / p.scale for p in free]), np.array([p.upper / p.scale for p in free])
    x0 = np.array([base.values[p.name] / p.scale for p in free])
    levels = {s: 1.5 * v if s == "position" else v for s, v in sigma.items()}     # the track weighed anew
    warm_replay, cold_replay = Counted(replay), Counted(replay)
    warm = WeightedSearch(warm_replay, replay.side_slip_block, values_of, lo, hi)
    first = warm.search(x0, sigma)
    before = warm_replay.calls
    again = warm.search(first.x, levels, after=first)
    fresh = WeightedSearch(cold_replay, replay.side_slip_block, values_of, lo, hi).search(first.x, levels)
    np.testing.assert_allclose(again.x, fresh.x, rtol=1e-9, atol=1e-12)
    assert again.cost == pytest.approx(fresh.cost, rel=1e-12)
    # the start's residuals (one call per stage) and Jacobian (one batched call per stage) not replayed
    assert warm_replay.calls - before == cold_replay.calls - 2 * len(replay.side_slip_block)


def test_stopping_tolerance_leaves_the_lever_arm_where_the_default_puts_it(case, monkeypatch):
    replay, base, sigma, truth = case
    free = refit_free(replay, replay.side_slip_block, [LEVER])
    ours = _fit(replay, dict(base.values), free, replay.side_slip_block, [{}], sigma)
    monkeypatch.setattr(weighted_search, "FTOL", 1e-8)            # scipy's defaults
    monkeypatch.setattr(weighted_search, "XTOL", 1e-8)
    forget(replay)                                    # searched again, not recalled
    tight = _fit(replay, dict(base.values), free, replay.side_slip_block, [{}], sigma)
    for name, planted in (("antenna_forward", truth["forward"]), ("antenna_left", truth["left"])):
        sd = ours.std(name)
        assert abs(ours.values[name] - tight.values[name]) < 0.05 * sd
        assert abs(ours.values[name] - planted) < 3.0 * sd


def test_a_fit_asked_for_again_is_recalled_not_searched(case, monkeypatch):
    replay, base, sigma, _ = case
    free = refit_free(replay, ("yaw",), [])
    first = _fit(replay, dict(base.values), free, ("yaw",), [{}], {"yaw": 2 * sigma["yaw"]})

    def searched(*args, **kwargs):
        raise AssertionError("searched again")
    monkeypatch.setattr(weighted_search, "least_squares", searched)
    first.values[free[0].name] = -1.0                  # what a caller changes in its copy
    again = _fit(replay, dict(base.values), free, ("yaw",), [{}], {"yaw": 2 * sigma["yaw"]})
    assert again.values[free[0].name] > 0 and again.rss == first.rss
    with pytest.raises(AssertionError, match="searched again"):     # another fit is searched
        _fit(replay, dict(base.values), free, ("yaw",), [{}], {"yaw": 3 * sigma["yaw"]})
