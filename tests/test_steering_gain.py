"""The command's gain (diagnosis.effects.steering_gain): on a log without a measured wheel angle the
yaw stage is driven by the command replayed, and wheels that turn k x the command are named with k.
The truth (harness.truth_tractor): a wheel-angle sensor reading g x the angle with the steering
loop closed on it turns the wheels delta_cmd / g; the log without its delta column is that command's
gain, k = 1 / g, drawn by the truth, never by the diagnosis."""
from __future__ import annotations

import pytest

from agrobot.diagnosis.baseline import baseline_from_study
from agrobot.diagnosis.candidates import Replay
from harness.hidden_effects import BASELINES, recovered
from agrobot.diagnosis.selection import Selector
from harness.truth_tractor import make_log
from agrobot.orchestrator.study import Study


def test_the_gain_is_a_candidate_for_every_steering_type():
    """A measured wheel angle carries a potentiometer's gain as a command carries a servo's."""
    baseline = baseline_from_study(Study.load(BASELINES["tractor"]))
    frame, _ = make_log(1000, None, duration=90.0)
    measured = Selector(Replay(frame, baseline))
    commanded = Selector(Replay(frame.drop(columns=["delta"]), baseline))
    assert {"steering_gain", "steering_asymmetry"} <= {e.id for e in measured.catalogue}
    assert {"steering_gain", "steering_asymmetry"} <= {e.id for e in commanded.catalogue}


@pytest.mark.slow
@pytest.mark.parametrize("fault", ["steering_sensor_gain", None])
def test_wheels_turning_k_x_the_command_are_named_with_k(tmp_path, fault):
    from agrobot.diagnosis.pipeline import diagnose

    frame, truth = make_log(1000, fault)
    log = tmp_path / "command_only.parquet"
    frame.drop(columns=["delta"]).to_parquet(log)
    result = diagnose(log, None, BASELINES["tractor"], identify=False)
    found = {e["id"]: e for e in result["effects"]}
    if fault is None:
        assert result["verdict"] == "none", result["selection_trace"][:5]
        return
    assert set(found) == {"steering_gain"} and result["verdict_status"] == "conclusive", result["selection_trace"][:5]
    est, true, tol = recovered("steering_gain", truth, found["steering_gain"]["parameters"])
    assert abs(est - true) <= tol and abs(true - 1.0) > 0.1, (est, true)
