"""A table's IMU mounted on its side (gravity on y): a yaw rate mapped from the gyro's z column is
named a roll or pitch rate, with the mapping that reads the vertical axis; following it gives the
planted yaw rate. A level IMU (gravity on z) and an accelerometer in g declared so are judged alike."""
from __future__ import annotations

import numpy as np
import pytest

from agrobot.api import convert
from agrobot.measurements.imu_axes import GRAVITY
from agrobot.measurements.signal_expressions import parse_signal

START = 1.7e9


def _imu_csv(folder, up: str, accel_unit: str = "") -> tuple[np.ndarray, np.ndarray]:
    """A 50 Hz IMU table whose ``up`` axis carries gravity and the yaw rate r(t) = 0.3 sin(0.5 t)
    (the truth); the other gyro axes carry small roll and pitch rates."""
    folder.mkdir()
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 40.0, 0.02)
    r = 0.3 * np.sin(0.5 * t)
    gyro = {a: 0.02 * rng.standard_normal(len(t)) for a in "xyz"}
    acc = {a: 0.5 * rng.standard_normal(len(t)) for a in "xyz"}
    gyro[up], acc[up] = r, GRAVITY + 0.3 * rng.standard_normal(len(t))
    scale = 1 / GRAVITY if accel_unit == "g" else 1.0
    unit = f" [{accel_unit}]" if accel_unit else ""
    lines = ["t,gyro_x,gyro_y,gyro_z," + ",".join(f"acc_{a}{unit}" for a in "xyz")]
    lines += [f"{START + t[i]:.3f}," + ",".join(f"{gyro[a][i]:.5f}" for a in "xyz") + ","
              + ",".join(f"{acc[a][i] * scale:.5f}" for a in "xyz") for i in range(len(t))]
    (folder / "imu.csv").write_text("\n".join(lines) + "\n")
    return t, r


def _axis_findings(rec) -> list[dict]:
    return [f for f in rec.report["audit"]["findings"] if f["kind"] == "mislabelled_channel"]


@pytest.mark.parametrize("accel_unit", ["", "g"])
def test_a_gyro_column_that_is_not_the_vertical_axis_is_named_with_the_one_that_is(tmp_path, accel_unit):
    t, r = _imu_csv(tmp_path / "rec", "y", accel_unit)
    rec = convert(tmp_path / "rec", signals=[parse_signal("yaw_rate=imu.gyro_z[rad/s]")])
    found = _axis_findings(rec)
    assert len(found) == 1 and found[0]["channels"] == ["yaw_rate"] and not found[0]["resolved"]
    assert "vertical axis is y" in found[0]["meaning"] and "--signal yaw_rate=imu.gyro_y" in found[0]["meaning"]
    fixed = convert(tmp_path / "rec", signals=[parse_signal("yaw_rate=imu.gyro_y[rad/s]")])
    assert not _axis_findings(fixed)
    log = fixed.log
    truth = np.interp(log["t"].to_numpy(float), t - t[0], r)
    assert np.max(np.abs(log["yaw_rate"].to_numpy(float) - truth)) < 0.01


def test_a_level_imu_keeps_its_z_gyro_without_a_finding(tmp_path):
    _imu_csv(tmp_path / "rec", "z")
    rec = convert(tmp_path / "rec", signals=[parse_signal("yaw_rate=imu.gyro_z[rad/s]")])
    assert not _axis_findings(rec)
