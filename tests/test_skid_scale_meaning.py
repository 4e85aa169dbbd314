"""A skid-steer's wheel odometry turning 3.6 times its gyro is the skid (K = 0.28 against the track
the odometry divides by), never 'a km/h vs m/s mix-up': that reading needs two speeds."""
from __future__ import annotations

import pytest

from agrobot.measurements.recording import ImportOptions, import_recording
from tests.test_bag_one_clock import _bag

SKID = 3.6         # the odometry's turn rate over the gyro's (truth: K = 1 / 3.6)


def test_a_skid_steers_odometry_scale_is_named_the_skid_not_km_h(tmp_path):
    pytest.importorskip("rosbags")
    _bag(tmp_path / "bag", 0.0, lag=0.0, scale=SKID)
    frame, _ = import_recording(tmp_path / "bag", ImportOptions())
    scale = [f for f in frame.attrs["audit"] if f["kind"] == "scale_disagreement"
             and sorted(f["channels"]) == ["odom_yaw_rate", "yaw_rate"]]
    assert len(scale) == 1 and abs(scale[0]["value"] - SKID) < 0.1, scale
    assert "km/h" not in scale[0]["meaning"] and "skid-steered" in scale[0]["meaning"], scale[0]["meaning"]
