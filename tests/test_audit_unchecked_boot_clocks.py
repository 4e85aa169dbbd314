"""Two loggers' tables, each counting from its own start (not dates): joined on their stamps as if
the loggers started together. Where no pair of channels compares the two clocks (a gyro in one, a
wheel speed in the other), the audit says the offset between them is not known and names the
--align that moves one; where a pair does (a gyro in each), the measured offset is the finding;
dated tables (one time scale, UTC) are not named."""
from __future__ import annotations


import numpy as np
import pandas as pd

from agrobot.measurements.recording import ImportOptions, import_recording

SECONDS = 120.0


def _folder(root, start: float, gyro_in_wheel_file: bool = False, steering: bool = False, seed: int = 1):
    """imu.csv at 50 Hz (its clock in ms from ``start``), wheel.csv at 20 Hz on its own clock in s;
    the machine turns at random (a smooth yaw rate) at 2 m/s; the wheel logger started 7 s after the IMU's."""
    rng = np.random.default_rng(seed)
    root.mkdir()
    ti = np.arange(0.0, SECONDS, 0.02)
    r = np.convolve(rng.normal(0, 1, len(ti)), np.hanning(75), "same")      # smooth, not periodic
    r *= 0.3 / np.std(r)
    pd.DataFrame({"time (ms)": (start + ti) * 1e3, "gz": r + rng.normal(0, 0.01, len(ti))}).to_csv(root / "imu.csv", index=False)
    tw = np.arange(7.0, SECONDS, 0.05)
    wheel = {"time (s)": start + tw - 7.0, "speed": 2.0 + 0.2 * np.sin(2 * np.pi * tw / 30.0)}
    if gyro_in_wheel_file:
        wheel["gz2"] = np.interp(tw, ti, r) + rng.normal(0, 0.01, len(tw))
    if steering:        # the wheel angle that turns the machine so on a 2.5 m wheelbase, logged beside the speed
        wheel["steer"] = np.arctan(np.interp(tw, ti, r) * 2.5 / wheel["speed"])
    pd.DataFrame(wheel).to_csv(root / "wheel.csv", index=False)
    return root


def _clock_findings(folder, *extra, align: str = "none"):
    options = ImportOptions(signals=["yaw_rate=imu.gz[rad/s]", "v=wheel.speed[m/s]", *extra], align=align)
    _, report = import_recording(folder, options)
    return [f for f in report["audit"]["findings"] if f["kind"] in ("clock_offset", "clock_unchecked")]


def test_two_boot_clocks_no_pair_compares_are_said(tmp_path):
    found = _clock_findings(_folder(tmp_path / "ride", start=6.0))
    assert len(found) == 1, found
    f = found[0]
    assert f["kind"] == "clock_unchecked" and f["value"] == 0.0 and f["interval"] is None and f["resolved"]
    assert set(f["channels"]) == {"yaw_rate", "v"}
    assert "not known" in f["meaning"] and "--align " in f["meaning"] and "=SECONDS" in f["meaning"]


def test_a_pair_across_them_measures_the_offset_instead(tmp_path):
    found = _clock_findings(_folder(tmp_path / "ride", start=6.0, gyro_in_wheel_file=True), "yaw_rate_2=wheel.gz2[rad/s]")
    assert found and all(f["kind"] == "clock_offset" for f in found), found
    assert any(abs(abs(f["value"]) - 7.0) < 0.1 for f in found), found


def test_dated_tables_are_one_time_scale(tmp_path):
    assert _clock_findings(_folder(tmp_path / "ride", start=1.7e9)) == []


def test_an_offset_the_user_gives_is_not_said_unknown(tmp_path):
    assert _clock_findings(_folder(tmp_path / "ride", start=6.0), align="wheel=-7") == []


def test_the_steering_against_the_gyro_is_a_comparison(tmp_path):
    """The causality check (steering x speed -> yaw rate, a response never leads its input) compares
    the steering's clock with the gyro's: not said unknown."""
    found = _clock_findings(_folder(tmp_path / "ride", start=6.0, steering=True), "delta=wheel.steer[rad]")
    assert not [f for f in found if f["kind"] == "clock_unchecked"], found
