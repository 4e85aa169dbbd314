"""Every quantity identify and diagnose both estimate on one log, side by side
(diagnosis.shared_quantities): on generated logs with a planted truth the two agree within their
95 % intervals, both holding the truth, or the line names why with both numbers."""
from __future__ import annotations

import json
import math

import pytest

from agrobot.diagnosis.shared_quantities import SHARED, shared_quantities


def _small(tmp_path, drop=(), seed: int = 1, duration: float = 90.0):
    """The small Ackermann machine (gain 0.85, asymmetry 0.15, offset 0.035 rad, servo lag 0.15 s)
    diagnosed against its baseline study; identify runs on the same log."""
    from agrobot.diagnosis.pipeline import diagnosis
    from harness.small_ackermann import make_small_log, write_study

    frame, truth = make_small_log(seed, duration=duration)
    path = tmp_path / "small.csv"
    frame.drop(columns=list(drop)).to_csv(path, index=False)
    result, write = diagnosis(path, write_study(tmp_path), plots=False, workers=1)
    return result, write, truth


def _pair(result: dict, quantity: str) -> dict:
    (q,) = [q for q in result["shared_quantities"] if q["quantity"] == quantity]
    return q


def _holds(est: dict, value: float) -> bool:
    return est["interval"][0] <= value <= est["interval"][1]


@pytest.mark.slow
def test_identify_and_diagnose_agree_on_the_planted_steering_gain_and_asymmetry(tmp_path):
    """identify's g_left, g_right become the diagnosis's k = (g_left + g_right) / 2 and
    a = (g_left - g_right) / (g_left + g_right): both estimates hold the planted 0.85 and 0.15 and
    agree; the lines are verdict bullets and diagnosis.json's ``shared_quantities``."""
    result, write, truth = _small(tmp_path)
    gain, asym = _pair(result, "steering gain"), _pair(result, "steering asymmetry")
    for q, planted in ((gain, truth["gain"]), (asym, truth["asymmetry"])):
        assert q["agree"], q["line"]
        assert all(_holds(e, planted) for e in q["estimates"].values()), q["line"]
        assert q["line"] in result["verdict_bullets"] and q["line"].endswith("they agree")
    assert gain["identify_how"] == "(g_left + g_right) / 2" and gain["diagnose_how"] == "steering_gain"
    write(tmp_path / "out")
    written = json.loads((tmp_path / "out" / "diagnosis.json").read_text())["shared_quantities"]
    assert {q["quantity"] for q in written} >= {"steering gain", "steering asymmetry", "steering offset"}


@pytest.mark.slow
def test_a_delay_against_a_delay_and_a_lag_is_named_with_both_numbers(tmp_path):
    """The same machine without its angle reading: identify's input is the command, its pure delay
    takes up the servo's 0.15 s lag; the diagnosis's steering has that lag beside a delay held at
    the study's 0: they differ, and the line says both reasons with the numbers."""
    result, _, truth = _small(tmp_path, drop=("delta",))
    q = _pair(result, "steering delay")
    mine, theirs = q["estimates"]["identify"], q["estimates"]["diagnose"]
    assert not q["agree"] and 0.1 <= mine["value"] <= 0.22, q["line"]         # the 0.15 s servo lag as a delay
    assert theirs["value"] == 0.0 and q["diagnose_fixed"]
    structure = next(r for r in q["reasons"] if r.startswith("a different model structure"))
    assert "first-order lag" in structure and "pure delay" in structure
    assert any(r.startswith("the diagnosis holds it at the study's 0 s (actuator_delay not kept") for r in q["reasons"])
    assert f"identify {mine['value']:.3g} s [" in q["line"] and "they differ" in q["line"]


@pytest.mark.slow
def test_both_hold_the_planted_gyro_bias(tmp_path):
    """A tractor with a gyro bias: identify's gyro_bias and the diagnosis's yaw_rate_bias agree and
    both intervals hold the planted bias."""
    from agrobot.diagnosis.pipeline import diagnosis
    from harness.hidden_effects import BASELINES
    from harness.truth_tractor import make_log

    frame, truth = make_log(1, "yaw_rate_bias", duration=150.0)
    path = tmp_path / "tractor.parquet"
    frame.to_parquet(path)
    result, _ = diagnosis(path, BASELINES["tractor"], plots=False, workers=1)
    q = _pair(result, "gyro bias")
    assert q["agree"], q["line"]
    assert all(_holds(e, truth["bias"]) for e in q["estimates"].values()), q["line"]


def _sides(gain: float, fixed: bool, wheelbase: float = 1.27, split: str = "tail"):
    ident = {"quantities": {"steer_gain": {"value": 0.85, "std": 0.01, "how": "(g_left + g_right) / 2"}},
             "input": "delta", "final_model": "kinematic", "wheelbase": 1.27, "lag": None, "span": [0.0, 90.0]}
    diag = {"parameters": {"steering_gain": {"value": gain, "std": math.nan if fixed else 0.01, "fixed": fixed,
                                             "how": "the study's value" if fixed else "steering_gain",
                                             "held": "steering_gain not kept: dBIC 2.5 is not below -10"}},
            "time_constant": 0.1, "command_only": False, "wheelbase": wheelbase, "span": [3.0, 54.0], "split": split}
    return ident, diag


def test_the_gain_is_compared_on_the_studys_wheelbase_and_a_held_gain_is_named():
    """A turn gives g / L: on a study whose wheelbase is 1.2 x identify's, the diagnosis's gain is
    1.2 x identify's for the same turns (0.85 x 1.2 = 1.02), and they agree; a gain the diagnosis
    holds at the study's 1 is named so, with its spans."""
    (q,) = shared_quantities(*_sides(1.02, False, wheelbase=1.27 * 1.2))
    assert q["agree"] and q["estimates"]["identify"]["value"] == pytest.approx(1.02), q["line"]
    (q,) = shared_quantities(*_sides(0.85, False, wheelbase=1.27 * 1.2))
    assert not q["agree"]                            # the same gain on a longer wheelbase: another turn
    (q,) = shared_quantities(*_sides(1.0, True))
    assert not q["agree"] and q["reasons"][0] == ("the diagnosis holds it at the study's 1 (steering_gain not kept: "
                                                  "dBIC 2.5 is not below -10)")
    assert q["reasons"][-1].startswith("different stretches: identify fits segments spread over t 0-90 s")
    assert "the diagnosis its fit part t 3-54 s" in q["reasons"][-1]
    assert q["line"].startswith("steering gain: identify 0.85 [0.83, 0.87] ((g_left + g_right) / 2); diagnose 1 ")
    assert [s.parameter for s in SHARED] == ["steering_gain", "steering_asymmetry", "steer_angle_offset",
                                             "command_delay", "yaw_rate_bias", "understeer_gradient"]


@pytest.mark.slow
def test_both_understeer_gradients_hold_the_tractors_planted_stiffnesses(tmp_path):
    """A healthy tractor with drawn stiffnesses: identify's K (its fitted cornering coefficients) and
    the diagnosis's (the study's stiffnesses x its refitted scales) agree and lie within 5 % of
    K = m / L (l_r / C_f - l_f / C_r) of the truth's."""
    from agrobot.diagnosis.pipeline import diagnosis
    from harness.hidden_effects import BASELINES
    from harness.truth_tractor import TABLE, make_log

    frame, truth = make_log(2, None, duration=150.0)
    path = tmp_path / "tractor.parquet"
    frame.to_parquet(path)
    result, _ = diagnosis(path, BASELINES["tractor"], plots=False, workers=1)
    L = TABLE["l_f"] + TABLE["l_r"]
    K = TABLE["m"] / L * (TABLE["l_r"] / truth["C_f"] - TABLE["l_f"] / truth["C_r"])
    q = _pair(result, "understeer gradient")
    assert q["agree"] and " deg/g" in q["line"], q["line"]
    assert all(e["value"] == pytest.approx(K, rel=0.05) for e in q["estimates"].values()), q["line"]
