"""The selection's linearised screen (diagnosis.screen) on generated logs with a known hidden
effect: a pair without support is not fitted and the screen says so, a pair holding the hidden
effect is always fitted, and the linearised fall in RSS is the fitted one for a small effect."""
from __future__ import annotations

import math

import pytest

from agrobot.diagnosis import selection
from agrobot.diagnosis.candidates import Replay, fit_baseline, uncertain
from agrobot.diagnosis.pipeline import baseline_from_study, load_study
from agrobot.diagnosis.screen import Screen
from agrobot.studies import shipped
from harness.truth_tractor import make_log

BIAS = 0.003          # rad/s: a small gyro bias (the truth draws 0.01-0.03)


def _judged(effect, values=None):
    """(replay, selector with the baseline fitted, baseline fit) of a 60 s steering and yaw log."""
    frame, truth = make_log(1000, effect, duration=60.0, values=values)
    replay = Replay(frame.drop(columns=["x", "y"]), baseline_from_study(load_study(shipped() / "figure8.toml")))
    sel = selection.Selector(replay)
    base, sel.sigma = fit_baseline(replay)
    sel.screen = Screen(replay, sel.sigma, selection.STRONG)
    return replay, sel, base


@pytest.fixture(scope="module")
def clean():
    return _judged(None)


@pytest.fixture(scope="module")
def biased():
    return _judged("yaw_rate_bias", {"bias": BIAS})


def _effect(sel, name):
    return next(e for e in sel.catalogue if e.id == name)


def _fitted_pair(replay, sel, base, a, b):
    """The pair's dBIC as Selector.pair scores it, from the real joint fit."""
    stages, related = selection.group(set(a.stages) | set(b.stages), [], replay.stages, replay.side_slip_block)
    fit = selection._refit(replay, base.values, related + [a, b], stages, sel.sigma, [{}])
    judged = selection._judge(a, fit, base, stages, sel.base_values, sel.min_gain)
    return judged.delta_bic + len(b.parameters) * math.log(max(sum(fit.n_eff[s] for s in stages), 2.0))


def test_a_pair_without_support_is_not_fitted_and_the_trace_says_so(clean, monkeypatch):
    replay, sel, base = clean
    a, b = _effect(sel, "gyro_scale"), _effect(sel, "speed_scale")
    # the truth: on a log without fault the joint fit of the two scales is not supported
    assert _fitted_pair(replay, sel, base, a, b) >= selection.STRONG

    def no_fit(*args, **kwargs):
        raise AssertionError("a screened-out pair was fitted")
    sel.catalogue = [a, b]
    monkeypatch.setattr(sel, "misfit_stages", lambda model: ["yaw"])
    monkeypatch.setattr(selection, "_refit", no_fit)
    assert sel.pair(base, [], set()) is None
    (line,) = sel.screen.lines()
    assert "1 of 1 not fitted" in line
    screened = line.split("not fitted")[1].split("; fitted:")[0]
    assert "gyro_scale + speed_scale (linearised dBIC" in screened


def test_every_pair_with_the_hidden_effect_is_fitted(biased):
    replay, sel, base = biased
    bias = _effect(sel, "yaw_rate_bias")
    others = [e for e in sel.catalogue if e is not bias and "yaw" in e.stages and e.id != "tyre_saturation"]
    assert len(others) >= 5
    for other in others:
        stages, related = selection.group(set(bias.stages) | set(other.stages), [], replay.stages,
                                          replay.side_slip_block)
        assert sel.screen.pair(base.values, related, other, bias, stages, sel.catalogue), other.id


def test_the_linearised_fall_is_the_fitted_fall_for_a_small_effect(biased):
    """A gyro bias adds b to the yaw rate, so the yaw residual is linear in it; the refitted
    cornering and relaxation scales move by O(b) from the baseline's optimum, their curvature a
    second-order term: the Gauss-Newton step's fall in RSS is the fitted one to a few per cent
    (5 % allowed). A wrong normalisation, a missing refitted parameter or a wrong column would miss
    it by far more (the fall is 20-30 % of the yaw stage's RSS)."""
    replay, sel, base = biased
    bias = _effect(sel, "yaw_rate_bias")
    stages = ("yaw",)
    refitted = list(uncertain(replay, "yaw"))
    predicted = sel.screen.judge(base.values, refitted, [bias], stages).falls["yaw"]
    fit = selection._refit(replay, base.values, [bias], stages, sel.sigma, [{}])
    fitted = 1.0 - fit.rss["yaw"] / base.rss["yaw"]
    assert fit.values["yaw_rate_bias"] == pytest.approx(BIAS, abs=0.001)      # the fit found the planted bias
    assert fitted > 0.1
    assert predicted == pytest.approx(fitted, rel=0.05)
