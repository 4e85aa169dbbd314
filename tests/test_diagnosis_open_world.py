"""Several causes at once, causes outside the catalogue, honest verdicts.

The logs come from harness/truth_tractor.py (independent of the replay); the hidden effects
and their sizes are drawn there. Tuning used seeds 1-3. Seed 7001 was the first reserved seed: its
first run exposed a flaw (the steering replay smeared a fractional command delay over a sample)
that was fixed in the model, so it was retired; SEED 7002 was first run as this test.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from harness.hidden_effects import diagnose_many, expected_ids as expected, recovered
from harness.truth_tractor import make_log

SEED = 7002
COMBINATIONS = (
    "actuator_delay+gps_latency",                    # the pair: a delay fitted with a latency present
    "steering_offset+yaw_rate_bias",                 # mimics in the yaw stage
    "steering_offset+side_slope",                    # mimics in the yaw stage
    "steering_deadband+steering_rate_limit",         # neither fits alone
    "antenna_lever_arm+gps_latency",                 # mimics in the position stage
    "actuator_delay+steering_offset+antenna_lever_arm",
    "steering_rate_limit+side_slope+yaw_rate_bias",
)
# unlisted fault -> the stages its misfit must be found in
# (none left: the truth's unlisted faults are all named now; steering_sensor_gain is the steering map's gain)
UNLISTED_STAGES: dict[str, set[str]] = {}
# faults of the truth's unlisted group the catalogue has since named (hidden_effects.NAMED)
NAMED_FAULTS = ("gyro_scale_factor", "wheel_slip", "tyre_saturation", "steering_sensor_gain")
MIXED = ("wheel_slip+actuator_delay", "tyre_saturation+gps_latency")


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    folder = str(tmp_path_factory.mktemp("open_world"))
    # saturating tyres are diagnosed as a user's diagnose does: identify on the same log first (one vehicle model)
    cases = [(c, SEED, folder, None, 240.0, None, "tractor", None, "tyre_saturation" in c)
             for c in COMBINATIONS + tuple(UNLISTED_STAGES) + NAMED_FAULTS + MIXED]
    out = {r["effect"]: r for r in diagnose_many(cases)}
    right = sum({e["id"] for e in r["result"]["effects"]} == expected(r["truth"]) for r in out.values())
    print(f"\nexact effect set in {right}/{len(out)} logs")
    return out


@pytest.mark.parametrize("case", COMBINATIONS)
def test_combined_effects_are_found_exactly_and_each_is_fitted_without_bias(runs, case):
    run = runs[case]
    res = run["result"]
    found = {e["id"] for e in res["effects"]}
    assert found == expected(run["truth"]), (found, res["selection_trace"])
    for e in res["effects"]:
        est, true, tol = recovered(e["id"], run["truth"], e["parameters"])
        assert abs(est - true) <= tol, (e["id"], est, true, tol)
        assert e["held_out_gain"] > 0.05
    assert res["verdict"] == min(res["effects"], key=lambda e: e["delta_bic"])["id"]
    assert all(not st["misfit"] for st in res["stages"].values()), res["stages"]


@pytest.mark.parametrize("fault", sorted(UNLISTED_STAGES))
def test_a_fault_outside_the_catalogue_is_unexplained_never_none(runs, fault):
    res = runs[fault]["result"]
    assert [e["id"] for e in res["effects"]] == ["unexplained"], res["selection_trace"]
    assert res["verdict"] == "unexplained"
    u = res["effects"][0]
    assert UNLISTED_STAGES[fault] <= set(u["stages"]), u["stages"]
    assert u["ratio_to_floor"] > 1.5
    for stage in u["stages"]:
        check = u["by_stage"][stage]
        assert check["rms_test"] ** 2 - check["floor"] ** 2 >= check["materiality"] ** 2
        assert abs(check["correlates_with"]["rho"]) > check["correlates_with"].get("bound", 0.1)
    # the data-driven extension fitted on the training part helps on the held-out part, and says what it is
    assert u["extension"]["held_out_gain"] > 0.2 and u["extension"]["rms_after"] < u["extension"]["rms_before"]
    assert u["signature"]["physical"] in u["summary"]


@pytest.mark.parametrize("fault", NAMED_FAULTS)
def test_a_fault_the_catalogue_now_holds_is_named_with_its_value(runs, fault):
    """Wheel slip logs (1 + s) x the ground speed: speed_scale 1 + s; a gyro scale factor s:
    gyro_scale s; saturating tyres: tyre_saturation near their equivalent friction
    (hidden_effects.recovered)."""
    run = runs[fault]
    res = run["result"]
    assert {e["id"] for e in res["effects"]} == expected(run["truth"]), res["selection_trace"]
    e = res["effects"][0]
    est, true, tol = recovered(e["id"], run["truth"], e["parameters"])
    assert abs(est - true) <= tol, (e["id"], est, true)


@pytest.mark.parametrize("case", MIXED)
def test_catalogued_and_unlisted_together(runs, case):
    run = runs[case]
    res = run["result"]
    assert {e["id"] for e in res["effects"]} == expected(run["truth"]), res["selection_trace"]
    for e in res["effects"]:
        if e["id"] != "unexplained":
            est, true, tol = recovered(e["id"], run["truth"], e["parameters"])
            assert abs(est - true) <= tol


def test_noise_floors_match_the_truth_sensors(runs):
    """The floors are estimated from the log alone (here one with three effects, under the model
    the diagnosis selected); the truth's sensor noise is known: gyro 0.005 rad/s, speed 0.02 m/s,
    GPS 0.02 m per axis (harness.truth_tractor)."""
    sensors = runs["actuator_delay+steering_offset+antenna_lever_arm"]["result"]["noise_floor"]["sensors"]
    assert sensors["yaw_rate"] == pytest.approx(0.005, rel=0.15)
    assert sensors["v"] == pytest.approx(0.02, rel=0.15)
    assert sensors["gps"] == pytest.approx(0.02, rel=0.15)


@pytest.mark.slow
def test_two_explanations_that_fit_equally_well_are_reported_inconclusive(monkeypatch, tmp_path):
    """A catalogue holding a twin of steering_offset (same physics, another name): the data cannot
    tell them apart, so the result must name both and the experiment, whichever it keeps."""
    import agrobot.diagnosis.selection as selection
    from agrobot.diagnosis.catalogue import CATALOGUE
    from agrobot.diagnosis.effects.steering_offset import SteeringOffset
    from agrobot.diagnosis.pipeline import diagnose

    class Twin(SteeringOffset):
        id = "steering_offset_twin"

    monkeypatch.setattr(selection, "CATALOGUE", CATALOGUE + (Twin(),))
    frame, _ = make_log(SEED, "steering_offset")
    frame.to_parquet(tmp_path / "log.parquet")
    res = diagnose(tmp_path / "log.parquet", tmp_path / "out", plots=False, identify=False)
    assert len(res["inconclusive"]) == 1
    tie = res["inconclusive"][0]
    assert set(tie["effects"]) == {"steering_offset", "steering_offset_twin"}
    assert "both directions" in tie["experiment"]       # the offset's own experiment: its yaw rate keeps its sign
    assert [e["id"] for e in res["effects"]] == [tie["chosen"]]
    assert res["effects"][0]["inconclusive_with"] == [t for t in tie["effects"] if t != tie["chosen"]]
    assert "**Inconclusive**" in (tmp_path / "out" / "report.md").read_text()


def test_a_log_that_cannot_support_a_verdict_says_so(tmp_path):
    from agrobot.diagnosis.pipeline import diagnose

    frame, _ = make_log(SEED, None, duration=120.0, speeds=(2.0,))
    frame.to_parquet(tmp_path / "log.parquet")
    res = diagnose(tmp_path / "log.parquet", tmp_path / "out", plots=False, identify=False)
    text = " ".join(res["warnings"])
    assert "lasts 120 s" in text and "speed hardly varies" in text
    noise = frame.assign(delta_cmd=frame["delta_cmd"] * 0.05, delta=frame["delta"] * 0.05)
    noise.to_parquet(tmp_path / "quiet.parquet")
    quiet = diagnose(tmp_path / "quiet.parquet", tmp_path / "out2", plots=False, identify=False)
    assert quiet["verdict"] == "cannot decide" or any("noise" in w or "excitation" in w for w in quiet["warnings"])


def test_blocked_recursion_equals_the_plain_loop():
    from agrobot.diagnosis.replay import blocked_recursion

    rng = np.random.default_rng(3)
    N, n = 1001, 4
    A = 0.95 * np.eye(n) + 0.03 * rng.standard_normal((N, n, n))
    b = rng.standard_normal((N, n, 3))
    Z, ref = np.zeros((n, 3)), np.empty((N, 3))
    for k in range(N):
        ref[k] = Z[2]
        Z = A[k] @ Z + b[k]
    for block in (0, 1, 7, 64, 2000):
        assert np.allclose(blocked_recursion(A, b, row=2, block=block), ref, rtol=1e-10, atol=1e-10)


def test_batched_matrix_exponential_equals_scipy():
    from scipy.linalg import expm

    from agrobot.components.models.yaw_dynamics import expm_batched

    rng = np.random.default_rng(4)
    M = rng.standard_normal((30, 6, 6)) * np.logspace(-4, math.log10(40), 30)[:, None, None]
    ref = np.array([expm(m) for m in M])
    scale = np.abs(ref).max(axis=(1, 2), keepdims=True)
    assert np.max(np.abs(expm_batched(M) - ref) / scale) < 1e-10
