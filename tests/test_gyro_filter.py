"""A gyro read through a low-pass filter is named 'gyro_filter' with its time constant. Truth: the
small Ackermann machine of harness.truth_tractor (its baseline study harness.vehicle_classes.study),
its yaw-rate column filtered at first order with a known time constant (hidden_effects.filtered_gyro,
an exact integration on a 1 ms grid, not the replay's recursion); the same log unfiltered names
nothing."""
from __future__ import annotations

import pytest

from agrobot.diagnosis.pipeline import diagnose
from harness.hidden_effects import filtered_gyro, recovered
from harness.truth_tractor import make_log
from harness.vehicle_classes import study

TAU = 0.15          # s: a MEMS gyro's output filter or a logger's smoothing


@pytest.fixture(scope="module")
def clean():
    return make_log(3, None, duration=120.0, vehicle="small_ackermann")[0]


def run(frame, folder):
    frame.to_parquet(folder / "log.parquet")
    return diagnose(folder / "log.parquet", None, study(folder), plots=False, identify=False)


def test_a_filtered_gyro_is_named_with_its_time_constant(clean, tmp_path):
    result = run(filtered_gyro(clean, TAU), tmp_path)
    assert [e["id"] for e in result["effects"]] == ["gyro_filter"], result["verdict"]
    fit = result["effects"][0]["fitted"]["gyro_time_constant"]
    estimate, truth, tol = recovered("gyro_filter", {"gyro_time_constant": TAU}, {"gyro_time_constant": fit["value"]})
    assert abs(estimate - truth) <= tol and fit["interval"][0] - tol <= TAU <= fit["interval"][1] + tol, fit


def test_the_unfiltered_log_names_nothing(clean, tmp_path):
    result = run(clean, tmp_path)
    assert result["effects"] == [] and result["verdict_status"] == "conclusive", result["verdict"]
