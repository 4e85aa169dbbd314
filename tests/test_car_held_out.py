"""The passenger car's clean log of seed 1006 (a seed no one tuned on), diagnosed against its baseline
study (studies/passenger_car.toml) as benchmarks/diagnosis_rate.py --classes car does.

The truth plants nothing at that seed: no lever arm (its antenna sits at the rear axle, as the
study's), stiffnesses within the others' spread. The gyro's white noise (0.002 rad/s at 20 Hz),
integrated into the dead-reckoned track's heading, drifts the track at 30 m/s by a GPS noise's worth
within a 10 s window. Read with equal weight at every frequency, that drift biases the block fit of
the cornering stiffnesses on the yaw rate and the track (candidates.fit_baseline) towards a stiffer
rear axle, and a lever arm fitted with the stiffnesses freed can undo that error on the held-out
part. The position stage's residual is whitened by the dead reckoning's own noise
(replay.TrackWhitening: the drift's covariance from the log's gyro and speed white levels), so the
fit stays at the truth's C_r and nothing is named. The first test checks the cause itself: with the
gyro's noise alone taken out the log is healthy.
"""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.diagnosis.pipeline import diagnose
from harness.hidden_effects import BASELINES
from harness.truth_tractor import make_log

SEED = 1006


def _diagnosed(frame, folder) -> list[str]:
    log = folder / "car.parquet"
    frame.to_parquet(log)
    result = diagnose(log, folder / "out", plots=False, study_path=BASELINES["car"], identify=False)
    return sorted(e["id"] for e in result["effects"])


def test_car_seed_1006_is_healthy_without_its_gyro_noise(tmp_path):
    """The gyro's noise-free yaw rate from two logs of one draw, its noise x 1 and x q (healthy
    quiet_sensors: every sensor's noise x q, the same standard normals): r = (g_q - q g_1) / (1 - q).
    With only that channel's noise taken out, nothing is named: neither the truth's parameters nor
    the other sensors' noise bring the lever arm."""
    frame, truth = make_log(SEED, None, duration=120.0, vehicle="car")
    quiet, quiet_truth = make_log(SEED, None, duration=120.0, vehicle="car", healthy="quiet_sensors")
    q = quiet_truth["healthy_noise"]
    assert truth["effects"] == [] and np.allclose(frame["x"], quiet["x"], atol=0.05)    # one draw of the plan
    frame["yaw_rate"] = (quiet["yaw_rate"].to_numpy() - q * frame["yaw_rate"].to_numpy()) / (1.0 - q)
    assert _diagnosed(frame, tmp_path) == []


def test_car_seed_1006_clean_log_names_nothing(tmp_path):
    """The log as the benchmark generates it: a healthy car, so no effect may be named."""
    frame, _ = make_log(SEED, None, duration=120.0, vehicle="car")
    assert _diagnosed(frame, tmp_path) == []


@pytest.mark.slow
def test_car_seed_1006_clean_log_of_240_s_names_nothing(tmp_path):
    """The same draw driven for 240 s (the benchmark's default length): 144 s to fit pin the rear
    stiffness against the gyro's drift, and nothing is named."""
    frame, _ = make_log(SEED, None, duration=240.0, vehicle="car")
    assert _diagnosed(frame, tmp_path) == []
