"""Verdicts a user can trust. No false alarm on a healthy tractor that differs from the
baseline the way real ones do (the paper's servo steering on a 1-deg potentiometer, relaxation
lengths, sensor noise, one speed, field driving), detection kept, a named effect kept against a
free map, and the healthy level the misfit is judged against.

Truths from harness.truth_tractor (healthy variants: HEALTHY). Tuning used seeds 1-7 and the
benchmark's 1000-1003; SEED was first run as this test.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from harness.hidden_effects import diagnose_many, expected_ids, recovered
from agrobot.measurements.log import resolution
from harness.truth_tractor import DEG, HEALTHY, make_log

SEED = 8801
# faults hidden in a healthy-but-different truth: detection must survive the higher healthy level
FAULTS_ON_SERVO = ("steering_offset", "actuator_delay", "steering_deadband", "gyro_scale_factor", "tyre_saturation")


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    folder = str(tmp_path_factory.mktemp("specificity"))
    cases = [(None, SEED, folder, None, 240.0, h) for h in HEALTHY]
    # saturating tyres are diagnosed as a user's diagnose does: identify on the same log first (one vehicle model)
    cases += [(f, SEED, folder, None, 240.0, "servo", "tractor", None, f == "tyre_saturation") for f in FAULTS_ON_SERVO]
    return {(r["effect"], r["healthy"]): r for r in diagnose_many(cases)}


@pytest.mark.parametrize("variant", HEALTHY)
def test_a_healthy_tractor_that_differs_from_the_baseline_is_not_a_fault(runs, variant):
    res = runs[("none", variant)]["result"]
    assert res["verdict"] == "none", (variant, [e["id"] for e in res["effects"]], res["selection_trace"],
                                      {s: (st["rms_test"], st["healthy_level"]) for s, st in res["stages"].items()})
    for stage, st in res["stages"].items():
        assert not st["misfit"], stage
        assert st["healthy_level"] >= st["floor"] * (1 - 1e-12)        # never below the white noise
        assert st["healthy_how"]


def test_the_servo_steering_leaves_more_than_white_noise_and_the_healthy_level_says_how_much(runs):
    """The issue's case: the servo on a 1-deg potentiometer leaves the steering stage well above its
    white-noise floor (the first version's false alarm); the healthy twin explains that excess."""
    res = runs[("none", "servo+rear_relaxation+noisy_sensors")]["result"]
    steer = res["stages"]["steering"]
    assert steer["rms_test"] > 1.2 * steer["floor"]
    assert steer["healthy_level"] > 1.2 * steer["floor"]
    assert abs(steer["rms_test"] - steer["healthy_level"]) < 0.25 * steer["healthy_level"]
    assert steer["materiality"] == pytest.approx(0.5 * DEG, rel=0.02)     # half the 1-deg sensor step
    assert "1 deg potentiometer" in steer["healthy_how"]


@pytest.mark.parametrize("fault", FAULTS_ON_SERVO)
def test_faults_are_still_found_on_a_servo_steered_tractor(runs, fault):
    """The set found is the hidden one; its value is checked where the servo leaves it defined (a
    dead-zone on the servo's error is not the first-order equivalent's dead-band: the PI's integral
    keeps the valve open through it, so the wheels stop closer to the command than D)."""
    run = runs[(fault, "servo")]
    found = {e["id"] for e in run["result"]["effects"]}
    assert found == expected_ids(run["truth"]), (found, run["result"]["selection_trace"])
    for e in run["result"]["effects"]:
        if e["id"] not in ("unexplained", "steering_deadband"):
            est, true, tol = recovered(e["id"], run["truth"], e["parameters"])
            assert abs(est - true) <= tol, (e["id"], est, true)


def test_resolution_finds_a_sensors_step_and_not_a_smooth_signal():
    rng = np.random.default_rng(3)
    smooth = np.cumsum(rng.standard_normal(5000)) * 1e-3
    for q in (math.radians(1.0), math.radians(0.1), 0.001):
        assert resolution(q * np.round(smooth / q)) == pytest.approx(q, rel=1e-6)
        assert resolution(0.3 + q * np.round(smooth / q)) == pytest.approx(q, rel=1e-6)      # an offset grid
    assert resolution(smooth) == 0.0
    assert resolution(np.round(smooth, 9)) == 0.0             # a CSV's printing digits: no repeats, no step
    frame, _ = make_log(SEED, None, duration=30.0, healthy="servo")
    assert resolution(frame["delta"].to_numpy()) == pytest.approx(math.radians(1.0), rel=1e-9)
