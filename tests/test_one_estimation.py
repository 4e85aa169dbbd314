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
    said = [b for b in result["verdict_bullets"] if b.startswith("the steering offset: identify")]
    assert len(said) == 1 and "diagnose" in said[0]
    assert "they agree" in said[0] or "a different model structure" in said[0]


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
    said = [b for b in result["verdict_bullets"] if b.startswith("the steering offset: identify")]
    assert len(said) == 1 and "they agree" in said[0], said
    fitted = next(e for e in result["effects"] if e["id"] == "steering_offset")["fitted"]["steer_angle_offset"]
    assert fitted["interval"][0] <= truth["offset"] <= fitted["interval"][1]
