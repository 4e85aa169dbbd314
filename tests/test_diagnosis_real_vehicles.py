"""Diagnosis verdicts that make physical sense on real vehicles: a command-only F1TENTH log, the
vehicle's [vehicle] table, look-alike column names, short logs, and the bicycle model's replay
checked against scipy's lsim (a second method)."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.signal import lsim

from agrobot.components.models.yaw_dynamics import TractorParameters, state_space
from agrobot.diagnosis.pipeline import diagnose
from agrobot.diagnosis.replay import YawReplay
from agrobot.identification.vehicle import Vehicle, VehicleError
from harness.truth_tractor import make_log
from tests.vehicle_logs import ROOT_STUDIES, frictionmaps_log

F1TENTH = ROOT_STUDIES / "f1tenth.toml"


def test_bicycle_yaw_replay_matches_lsim():
    p = TractorParameters(m=3.33, I=0.0687, l_f=0.112, l_r=0.208, C_f=106.0, C_r=57.0)
    n, h = 2000, 0.01
    delta = 0.05 * np.sin(np.arange(n) * h * 3.0)
    replay = YawReplay("bicycle", p, h, delta, np.full(n, 2.0), np.zeros(n))
    v = dict(cornering_front_scale=1.3, cornering_rear_scale=0.8, cornering_speed_slope=0.0,
             cornering_reference_speed=2.0, relaxation_scale=1.0, steer_angle_offset=0.0, slope_north=0.0,
             slope_east=0.0, yaw_rate_bias=0.0)
    A, B, C = state_space("bicycle", replace(p, C_f=106.0 * 1.3, C_r=57.0 * 0.8), 2.0)
    _, reference, _ = lsim((A, B[:, None], C[None, :], np.zeros((1, 1))), delta, np.arange(n) * h)
    assert np.max(np.abs(replay.yaw_rate(v) - reference)[5:]) < 0.01 * np.max(np.abs(reference))


@pytest.fixture(scope="module")
def ds1(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ds1")
    log = frictionmaps_log("DS1")
    t = log["t"].to_numpy()
    step = float(np.median(np.diff(t)))
    grid = np.arange(t[0], t[-1], step)
    even = log.__class__({c: np.interp(grid, t, log[c]) for c in log.columns})
    even["t"] = grid - grid[0]
    even.to_parquet(folder / "ds1.parquet")
    return diagnose(folder / "ds1.parquet", folder / "out", F1TENTH, plots=False), even


def test_f1tenth_command_only_log_is_judged_through_the_yaw_rate(ds1):
    res, _ = ds1
    assert res["verdict"] != "cannot decide", res.get("reason")
    assert "yaw" in res["stages_judged"] and "steering" not in res["stages_judged"]
    assert "only the command delta_cmd" in res["not_judged"]["steering"]
    for e in res["effects"] + res["findings"]:
        for name, p in e.get("fitted", {}).items():
            assert p["bounds"][0] < p["bounds"][1]
    # no verdict sits on a bound
    top = next((e for e in res["effects"] if e["id"] == res["verdict"]), None)
    if top is not None:
        assert not any(p["at_bound"] for p in top.get("fitted", {}).values())
    # the scale car's gyro-bias range (3 deg/s), not the tractor's 0.2 rad/s; an end of it the fit
    # reaches is widened toward the physical limit, and the trace says so
    bias = [f for f in res["findings"] if f["id"] == "yaw_rate_bias"]
    lo, hi = bias[0]["fitted"]["yaw_rate_bias"]["bounds"] if bias else (None, None)
    widened = any(line.startswith("widened yaw_rate_bias") for line in res["selection_trace"])
    assert lo == pytest.approx(-math.radians(3.0)) or widened, (lo, hi)
    assert hi == pytest.approx(math.radians(3.0)) or widened, (lo, hi)


def test_yaw_column_under_another_name_is_named(ds1, tmp_path):
    _, even = ds1
    even.rename(columns={"yaw_rate": "YawRate"}).to_parquet(tmp_path / "log.parquet")
    res = diagnose(tmp_path / "log.parquet", tmp_path / "out", F1TENTH, plots=False, identify=False)
    text = res.get("reason", "") + " ".join(res.get("warnings", []))
    assert "YawRate" in text and "rename it to yaw_rate" in text
    assert res["verdict"] != "actuator_delay"


def test_tractor_log_with_yawrate_column_warns_beside_its_steering_verdict(tmp_path):
    frame, _ = make_log(1000, "actuator_delay", duration=90.0)
    frame.rename(columns={"yaw_rate": "YawRate"}).to_parquet(tmp_path / "log.parquet")
    res = diagnose(tmp_path / "log.parquet", tmp_path / "out", plots=False, identify=False)
    assert "yaw" in res["not_judged"] and "YawRate" in res["not_judged"]["yaw"]
    assert any(w.startswith("the log's columns:") and "YawRate" in w for w in res["warnings"])


def test_short_logs_judged_with_a_warning_or_refused_naming_the_minimum(tmp_path):
    frame, _ = make_log(1000, None, duration=59.98)
    frame.to_parquet(tmp_path / "short.parquet")
    res = diagnose(tmp_path / "short.parquet", tmp_path / "a", plots=False, identify=False)
    assert res["verdict"] != "cannot decide" and any("the log lasts 60 s" in w for w in res["warnings"])
    frame[frame["t"] < 25.0].to_parquet(tmp_path / "shorter.parquet")
    res = diagnose(tmp_path / "shorter.parquet", tmp_path / "b", plots=False, identify=False)
    assert res["verdict"] == "cannot decide" and "at least 30 s" in res["reason"] and "held-out" in res["reason"]


def test_vehicle_table_is_checked_and_rules_stages_out():
    with pytest.raises(VehicleError, match="vehicle.class = 'boat'"):
        Vehicle.from_table({"class": "boat"})
    with pytest.raises(VehicleError, match="vehicle.steering"):
        Vehicle.from_table({"steering": "wheel"})
    skid = Vehicle.from_table({"class": "robot", "drive": "skid", "steering": "none", "length": 0.6, "width": 0.4})
    why = skid.not_applicable()
    assert "skid" in why["yaw"] and "no steering angle" in why["steering"]
    assert skid.lever_arm_bounds() == ((-0.15, 0.6), (-0.2, 0.2))
    assert Vehicle.from_table({"class": "scale_car"}).gyro_bias_bound == pytest.approx(math.radians(3.0))
