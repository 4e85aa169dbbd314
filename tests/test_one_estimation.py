"""One estimation engine for identify and diagnose (agrobot.estimation): one parameter type, one
effective sample size, one covariance rule, one rule for two estimates of one quantity. The rules
are checked against truths derived independently (an AR(1) noise's known information content, the
spread of a least-squares estimate over repeated noise draws), and on one log both tools report the
steering offset side by side, agreeing or naming why not."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot import estimation


def ar1(rng, n: int, rho: float) -> np.ndarray:
    e = rng.standard_normal(n)
    out = np.empty(n)
    out[0] = e[0]
    for i in range(1, n):
        out[i] = rho * out[i - 1] + np.sqrt(1 - rho ** 2) * e[i]
    return out


def test_both_tools_use_the_same_rules():
    from agrobot.diagnosis import candidates, effect
    from agrobot.identification import comparisons, driving, kinematic, ordinary_driving

    assert effect.Parameter is estimation.Parameter is ordinary_driving.Parameter is kinematic.Parameter
    assert candidates.effective_size is estimation.effective_size is driving.effective_size
    assert candidates.solution_covariance is estimation.solution_covariance is driving.solution_covariance
    assert candidates.FitResult is estimation.FitResult is driving.FitResult is ordinary_driving.FitResult
    assert comparisons.pair is estimation.compare


def test_effective_size_of_ar1_noise_and_of_a_held_measurement():
    """An AR(1) noise of coefficient rho carries n (1 - rho) / (1 + rho) independent samples; pieces
    pool to the same; a measurement updated once per 4 rows carries at most its updates."""
    rng = np.random.default_rng(0)
    x = ar1(rng, 40000, 0.6)
    truth = 40000 * 0.4 / 1.6
    assert estimation.effective_size(x) == pytest.approx(truth, rel=0.05)
    assert estimation.effective_size(list(x.reshape(40, 1000))) == pytest.approx(truth, rel=0.05)
    assert estimation.effective_size(x, updates=1000) == 1000


def test_covariance_rule_matches_the_spread_of_repeated_fits():
    """y = a + b sin(t / 20) + AR(1) noise: the std the rule gives for a and b (one fit) against the
    standard deviation of a and b over 300 fits of fresh noise."""
    rng = np.random.default_rng(1)
    n = 2000
    t = np.arange(n) * 0.05
    X = np.column_stack([np.ones(n), np.sin(t / 20.0)])
    est, stds = [], []
    for _ in range(300):
        y = 0.3 + 0.5 * X[:, 1] + 0.1 * ar1(rng, n, 0.8)
        coef, *_ = np.linalg.lstsq(X, y, rcond=None)
        r = y - X @ coef
        cov = estimation.covariance(X, float(r @ r), n, estimation.effective_size(r))
        est.append(coef)
        stds.append(np.sqrt(np.diag(cov)))
    ratio = np.mean(stds, axis=0) / np.std(est, axis=0)
    assert np.all((ratio > 0.7) & (ratio < 1.4)), ratio


def test_a_parameter_on_its_bound_has_no_interval():
    J = np.eye(3)[:, :2].repeat(10, axis=0)[:20]
    cov = estimation.covariance(np.column_stack([J, np.linspace(0, 1, 20)]), 1.0, 20, 20.0, held=[False, False, True])
    assert np.isnan(cov[2, 2]) and np.isfinite(cov[0, 0])
    p = estimation.Parameter("x", "1", 1.0, 0.0, 1.0, limit=(0.0, 3.0))
    assert p.at_bound(0.9999) == "upper" and p.widened(0.9999).upper == 3.0 and p.widened(0.5) is None


@pytest.mark.slow
def test_identify_and_diagnose_report_one_offset_side_by_side(tmp_path):
    """The small machine (offset +0.035 rad, gain 0.85, asymmetry 0.15): identify's offset holds the
    truth; the diagnosis's verdict puts its own beside it and, where they differ, names why (the
    diagnosis's steering has no gain per side)."""
    from agrobot.diagnosis.pipeline import diagnosis
    from harness.small_ackermann import make_small_log, write_study

    frame, truth = make_small_log(1, duration=180.0)
    path = tmp_path / "small.csv"
    frame.to_csv(path, index=False)
    result, _ = diagnosis(path, write_study(tmp_path), plots=False)
    ident = result["identified_vehicle"]["identified"]["parameters"]["steer_offset"]
    assert ident["interval"][0] <= truth["offset"] <= ident["interval"][1]
    said = [b for b in result["verdict_bullets"] if b.startswith("steering offset: identify")]
    assert len(said) == 1 and "diagnose" in said[0]
    assert "they agree" in said[0] or "a different model structure" in said[0] or "holds it at" in said[0]


@pytest.mark.slow
def test_identify_and_diagnose_agree_where_their_models_coincide(tmp_path):
    """The same machine with an offset alone (gain 1, no asymmetry): the diagnosis's steering is then
    identify's map, and the two offsets agree within their intervals, both holding the truth's."""
    from agrobot.diagnosis.pipeline import diagnosis
    from harness.small_ackermann import make_small_log, write_study

    frame, truth = make_small_log(1, duration=180.0, truth={"gain": 1.0, "asymmetry": 0.0})
    path = tmp_path / "small.csv"
    frame.to_csv(path, index=False)
    result, _ = diagnosis(path, write_study(tmp_path), plots=False)
    said = [b for b in result["verdict_bullets"] if b.startswith("steering offset: identify")]
    assert len(said) == 1 and "they agree" in said[0], said
    fitted = next(e for e in result["effects"] if e["id"] == "steering_offset")["fitted"]["steer_angle_offset"]
    assert fitted["interval"][0] <= truth["offset"] <= fitted["interval"][1]


def test_one_fit_result_merges_and_has_no_interval_for_what_the_residuals_do_not_see():
    """A fit whose third parameter the residuals do not depend on (a zero Jacobian column): its
    variance is infinite (the pseudo-inverse alone gives zero), and the baseline refit's rule holds
    it; merging keeps each side's own variances."""
    from agrobot.diagnosis.baseline import unpinned

    rng = np.random.default_rng(2)
    n = 400
    X = np.column_stack([np.ones(n), np.linspace(-1, 1, n), np.zeros(n)])
    y = 2.0 + 0.5 * X[:, 1] + 0.1 * rng.standard_normal(n)
    coef, *_ = np.linalg.lstsq(X[:, :2], y, rcond=None)
    r = y - X[:, :2] @ coef
    free = tuple(estimation.Parameter(k, "1", 1.0, -10.0, 10.0) for k in ("a", "b", "c"))
    cov = estimation.covariance(X, float(r @ r), n, estimation.effective_size(r))
    fit = estimation.FitResult({"a": coef[0], "b": coef[1], "c": 0.3}, free, cov, {"y": float(r @ r)}, {"y": n},
                               {"y": float(n)})
    assert fit.std("c") == np.inf and fit.std("a") == pytest.approx(0.1 / np.sqrt(n), rel=0.15)
    assert set(unpinned(fit)) == {"c"} and "do not depend" in unpinned(fit)["c"].detail
    part = estimation.FitResult({**fit.values, "c": 0.7}, free[2:], np.array([[0.01]]), {"z": 1.0}, {"z": 10},
                                {"z": 5.0})
    both = fit.merged(part)
    assert both.values["c"] == 0.7 and both.std("c") == pytest.approx(0.1) and both.std("a") == fit.std("a")
    assert set(both.rss) == {"y", "z"} and both.n_total == n + 10


def test_the_diagnosis_counts_a_yaw_rate_derived_from_a_heading_by_its_updates(tmp_path):
    """The small machine's heading updates at 5 Hz in 20 Hz rows: the yaw stage's fit part holds a
    quarter of its rows' updates, and its effective samples are never more (as identify's)."""
    from agrobot.diagnosis.candidates import fitted
    from agrobot.diagnosis.pipeline import _replay_of
    from harness.small_ackermann import make_small_log, write_study

    frame, truth = make_small_log(3, duration=90.0)
    path = tmp_path / "small.csv"
    frame.to_csv(path, index=False)
    *_, replay, _ = _replay_of(path, write_study(tmp_path), {}, 0.6, False, None, "auto")
    rows = int(replay.masks["yaw"]["fit"].sum())
    assert replay.updates("yaw") == pytest.approx(rows * truth["heading_rate"] / 20.0, rel=0.05)
    assert replay.updates("steering") is None
    fit = fitted(replay, dict(replay.baseline.values), [], ("yaw",), [{}], {"yaw": 1.0})
    assert fit.n["yaw"] == rows and fit.n_eff["yaw"] <= replay.updates("yaw")
