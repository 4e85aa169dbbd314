"""A receiver's fixes given as x, y are not called an estimate, whatever their rate and noise;
an estimate (a dead-reckoned path, a localisation on a jittering clock) still is.

Independent truths: generated logs (harness.truth_tractor.make_log: the receiver's fixes with 2 cm
of white noise), the same log's fixes at 1 Hz, and estimates built here from the log's own speed
and gyro (odometry: smooth) and that path with the speed filtered, and read on a clock with 5 ms of jitter (its error along
the track, in proportion to the speed)."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from agrobot.measurements.audit import audit_frame
from agrobot.measurements.position_source import named_estimate
from harness.truth_tractor import make_log


def estimate_kinds(frame: pd.DataFrame) -> list[dict]:
    return [f for f in audit_frame(frame) if f["kind"] == "position_is_estimate"]


def odometry(frame: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """The path dead-reckoned from the speed and the gyro: x' = v cos(psi), y' = v sin(psi), psi' = r."""
    t, v, r = (frame[c].to_numpy(float) for c in ("t", "v", "yaw_rate"))
    h = np.diff(t, prepend=t[0])
    psi = np.cumsum(r * h)
    return np.cumsum(v * np.cos(psi) * h), np.cumsum(v * np.sin(psi) * h)


@pytest.fixture(scope="module")
def small():
    return make_log(2, None, duration=120.0, vehicle="small_ackermann")[0]


@pytest.mark.parametrize("vehicle, rate", [("small_ackermann", 20.0), ("tractor", 20.0), ("tractor", 5.0)])
def test_a_receivers_fixes_as_x_y_are_not_an_estimate(vehicle, rate):
    frame, _ = make_log(3, None, duration=120.0, vehicle=vehicle, rate=rate)
    assert estimate_kinds(frame) == []


def test_a_low_rate_receiver_whose_turns_outweigh_its_noise_is_not_an_estimate():
    frame, _ = make_log(4, None, duration=240.0, vehicle="tractor")
    assert estimate_kinds(frame.iloc[::20].reset_index(drop=True)) == []          # 1 Hz fixes


def test_a_dead_reckoned_path_is_an_estimate(small):
    """Its speed's noise lies along the track; with the speed filtered (1 s mean) it is smooth both ways."""
    frame = small.copy()
    frame["x"], frame["y"] = odometry(frame)
    found = estimate_kinds(frame)
    assert len(found) == 1 and "to the course" in found[0]["meaning"]
    frame["v"] = np.convolve(frame["v"], np.ones(20) / 20, mode="same")
    frame["x"], frame["y"] = odometry(frame)
    found = estimate_kinds(frame)
    assert len(found) == 1 and "smooth both ways" in found[0]["meaning"]


def test_a_localisation_on_a_jittering_clock_is_an_estimate(small):
    frame = small.copy()
    x, y = odometry(frame)
    t = frame["t"].to_numpy(float)
    late = t + 0.005 * np.random.default_rng(7).standard_normal(len(t))
    frame["x"], frame["y"] = np.interp(late, t, x), np.interp(late, t, y)
    found = estimate_kinds(frame)
    assert len(found) == 1 and "to the course" in found[0]["meaning"]


@pytest.mark.parametrize("source, estimate", [("x=pfOdomData.x[m]", True), ("/odometry/filtered pose.pose.position.x", True),
                                              ("/odometry/gps pose.pose.position.x", False), ("x=x[m]", False),
                                              ("east of the run's first fix", False)])
def test_a_source_named_for_an_estimator_is_one_unless_it_names_a_receiver(source, estimate):
    """A particle filter's poses scatter like fixes (isotropic); its topic's name tells."""
    assert (named_estimate(source) is not None) == estimate


def test_a_motion_captures_positions_are_not_an_estimate():
    """Optical motion capture: the path itself with 0.2 mm of white noise the same both ways, at 100 Hz.
    A measurement (white, isotropic), though finer than any receiver's."""
    frame, _ = make_log(5, None, duration=120.0, vehicle="small_ackermann", rate=100.0)
    x, y = odometry(frame)
    noise = 0.2e-3 * np.random.default_rng(11).standard_normal((2, len(x)))
    frame["x"], frame["y"] = np.round(x + noise[0], 6), np.round(y + noise[1], 6)      # Motive writes micrometres
    assert estimate_kinds(frame) == []


def test_a_smooth_path_stored_in_float32_far_from_its_origin_is_still_an_estimate(small):
    """Its rounding (0.06 mm steps 800 m out) is white and the same both ways, but no finer than the
    values' resolution: rounding, not a measurement."""
    frame = small.copy()
    frame["v"] = np.convolve(frame["v"], np.ones(20) / 20, mode="same")
    x, y = odometry(frame)
    frame["x"], frame["y"] = (np.float32(800.0 + x)).astype(float), (np.float32(-600.0 + y)).astype(float)
    found = estimate_kinds(frame)
    assert len(found) == 1 and "smooth both ways" in found[0]["meaning"]
