"""The skid-steer yaw model on generated recordings with a planted truth: K, tau, T, b recovered
within their intervals, an implausible K named, a turn-rate dependence found only where planted,
a log without a turn-rate input refused with the columns and the remedy, diagnose's refusal."""
from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest
from scipy.signal import lsim

from agrobot.api import diagnose, identify
from agrobot.identification.skid_steer import applies, identify_skid_steer
from agrobot.identification.vehicle import Vehicle
from agrobot.measurements import LogError

FINE = 200.0          # Hz: the truth is integrated on this grid, then sampled at the log's rate


def turn_rates(seconds: float, rng, amplitude: float = 0.6) -> tuple[np.ndarray, np.ndarray]:
    """(t, w) on the fine grid: random turn rates held 1.5-5 s (a quarter of them standing straight),
    smoothed by the drives (0.15 s)."""
    t = np.arange(0.0, seconds, 1.0 / FINE)
    w = np.zeros_like(t)
    start = 0.0
    while start < seconds:
        hold = rng.uniform(1.5, 5.0)
        level = 0.0 if rng.random() < 0.25 else rng.uniform(-amplitude, amplitude)
        w[(t >= start) & (t < start + hold)] = level
        start += hold
    _, smooth, _ = lsim(([1.0], [0.15, 1.0]), w, t)
    return t, smooth


def skid_log(K=0.7, tau=0.2, T=0.3, bias=0.01, slope=0.0, column="turn_rate_cmd", seconds=240.0, rate=20.0,
             noise=0.01, seed=3) -> pd.DataFrame:
    """A skid-steer recording: the gyro r = y + b + noise, T dy/dt + y = K (1 - s|w_d|) w_d, w_d the
    input delayed by tau (an odometry input, tau < 0, is the wheels' turn rate stamped -tau late)."""
    rng = np.random.default_rng(seed)
    t, w = turn_rates(seconds + 4.0, rng)
    if tau >= 0:
        u, w_true = w, np.interp(t - tau, t, w)          # the drives answer tau after the command
    else:
        u, w_true = np.interp(t + tau, t, w), w          # the odometry reports the wheels -tau late
    x = K * (1.0 - slope * np.abs(w_true)) * w_true
    y = lsim(([1.0], [T, 1.0]), x, t)[1] if T > 0 else x          # from rest: the input starts at 0
    keep = (t >= 2.0) & (np.round(t * FINE) % round(FINE / rate) == 0)
    n = int(keep.sum())
    return pd.DataFrame({"t": t[keep] - 2.0, "yaw_rate": y[keep] + bias + rng.normal(0, noise, n),
                         column: u[keep], "v": np.full(n, 1.0)})


def _inside(report: dict, name: str, truth: float) -> bool:
    lo, hi = report["parameters"][name]["interval"]
    return lo <= truth <= hi


@pytest.mark.parametrize("column,K,tau,T", [("turn_rate_cmd", 0.7, 0.2, 0.3), ("odom_yaw_rate", 0.85, -0.3, 0.15)])
def test_recovers_the_planted_truth_within_its_intervals(column, K, tau, T):
    rep = identify_skid_steer(skid_log(K=K, tau=tau, T=T, column=column), "gen.csv")
    assert rep["input"] == column and rep["final_model"] == "skid_steer"
    for name, truth in (("yaw_gain", K), ("delay", tau), ("lag", T), ("gyro_bias", 0.01)):
        assert rep["parameters"][name]["identifiable"], (name, rep["parameters"][name])
        assert _inside(rep, name, truth), (name, truth, rep["parameters"][name])
    assert rep["plausibility"]["plausible"], rep["plausibility"]
    assert not rep["turn_rate_dependence"]["kept"]          # none planted: none found
    assert rep["held_out_fit"]["rmse"] < 0.015               # the noise is 0.01 rad/s


def test_an_implausible_gain_is_fitted_and_named():
    rep = identify_skid_steer(skid_log(K=1.4), "gen.csv")
    assert _inside(rep, "yaw_gain", 1.4)
    assert not rep["plausibility"]["plausible"]
    assert any(f.startswith("yaw_gain") and "effective track" in f for f in rep["plausibility"]["findings"])


def test_a_turn_rate_dependence_is_found_where_planted():
    rep = identify_skid_steer(skid_log(K=0.9, slope=0.6, T=0.2), "gen.csv")
    dep = rep["turn_rate_dependence"]
    assert dep["kept"], dep
    assert _inside(rep, "gain_slope", 0.6) and _inside(rep, "yaw_gain", 0.9)
    assert "s |w_d|" in rep["equation"]


def test_a_log_without_a_turn_rate_input_is_refused_naming_the_columns(tmp_path, cli):
    log = skid_log().drop(columns="turn_rate_cmd")
    with pytest.raises(LogError, match="odom_yaw_rate or turn_rate_cmd.*--signal 'odom_yaw_rate="):
        identify_skid_steer(log, "gen.csv")
    log.to_csv(tmp_path / "none.csv", index=False)
    out = tmp_path / "out"
    run = cli("identify", tmp_path / "none.csv", "--out", out, "--no-plots", timeout=120)
    assert run.returncode == 2 and "Traceback" not in run.stderr
    assert "no delta or delta_cmd" in run.stderr and "odom_yaw_rate or turn_rate_cmd" in run.stderr
    assert "--signal 'odom_yaw_rate=" in run.stderr
    assert not out.exists()


def test_identify_and_diagnose_on_a_skid_steer_log(tmp_path):
    skid_log(column="odom_yaw_rate", tau=-0.2).to_csv(tmp_path / "husky_like.csv", index=False)
    found = identify(tmp_path / "husky_like.csv", method="driving", out=tmp_path / "id", plots=False)
    text = found.summary()
    assert "T dy/dt + y = K w(t - tau)" in text and "input w: odom_yaw_rate" in text
    saved = json.loads((tmp_path / "id" / "identification.json").read_text())
    assert math.isclose(saved["parameters"]["yaw_gain"]["value"], found.report["parameters"]["yaw_gain"]["value"])
    result = diagnose(tmp_path / "husky_like.csv", out=tmp_path / "dg", plots=False).result
    assert result["verdict"] == "cannot decide" and "skid-steered vehicle" in result["reason"]
    assert "Ackermann" in result["reason"]


class _SkidStudy:
    """A study that declares a skid-steered robot (only its [vehicle] table is read)."""

    path = "skid_robot.toml"

    def section(self, name):
        return {"class": "robot", "drive": "skid", "steering": "none"} if name == "vehicle" else None


def test_a_declared_skid_steer_is_fitted_or_refused_by_its_declaration():
    log = skid_log(K=0.6)
    assert applies(log.assign(delta=0.0), Vehicle.from_table({"drive": "skid"}))      # declared: a delta does not count
    assert not applies(log.assign(delta=0.0), Vehicle())                                # an Ackermann log stays one
    rep = identify_skid_steer(log, "gen.csv", _SkidStudy())
    assert "vehicle.drive = 'skid' declared" in rep["notes"][0] and _inside(rep, "yaw_gain", 0.6)
    assert rep["plausibility"]["ranges"]["gyro_bias"][1] == pytest.approx(math.radians(3.0))   # the robot class's
    with pytest.raises(LogError, match="yaw_rate_2 is a second yaw-rate source"):
        identify_skid_steer(log.drop(columns="turn_rate_cmd").assign(yaw_rate_2=0.0), "gen.csv", _SkidStudy())


def test_a_turn_rate_input_updated_at_half_the_rows_rate_is_interpolated_between_its_updates(tmp_path, cli):
    log = skid_log(K=0.7, column="odom_yaw_rate", tau=-0.2)
    log.loc[log.index % 2 == 1, "odom_yaw_rate"] = np.nan          # the odometry at half the gyro's rate
    rep = identify_skid_steer(log, "gen.csv")
    assert _inside(rep, "yaw_gain", 0.7) and rep["parameters"]["yaw_gain"]["identifiable"]
    assert any("odom_yaw_rate: " in n and "blank cells" in n for n in rep["notes"])
    few = skid_log(column="odom_yaw_rate", tau=-0.2)
    few.loc[few.index % 50 != 0, "odom_yaw_rate"] = np.nan          # one update in 2.5 s: too few
    few.to_csv(tmp_path / "few.csv", index=False)
    with pytest.raises(LogError, match="odom_yaw_rate has .* finite cells"):
        identify_skid_steer(few, "gen.csv")
    run = cli("identify", tmp_path / "few.csv", "--out", tmp_path / "out", "--no-plots", timeout=120)
    assert run.returncode == 2 and "Traceback" not in run.stderr and "odom_yaw_rate" in run.stderr


def test_a_turn_rate_input_in_degrees_per_second_is_named_implausible():
    log = skid_log(K=0.7)
    log["turn_rate_cmd"] /= math.radians(1.0)                       # the command written in deg/s
    rep = identify_skid_steer(log, "gen.csv")
    K = rep["parameters"]["yaw_gain"]
    assert K["value"] < 0.3
    assert K["identifiable"] or "% of its range" in K["note"]           # on its bound: the tolerance said
    assert not rep["plausibility"]["plausible"]
    assert any(f.startswith("yaw_gain") and "deg/s?" in f and "turn_rate_cmd=" in f for f in rep["plausibility"]["findings"])
    assert any("looks like deg/s" in n for n in rep["notes"])


def test_a_skid_steer_log_names_the_options_it_passes_over(tmp_path):
    from agrobot.identification.from_log import driving_report
    from agrobot.measurements.options import ImportOptions

    skid_log(column="odom_yaw_rate", tau=-0.2, seconds=60.0).to_csv(tmp_path / "skid.csv", index=False)
    report, _ = driving_report(tmp_path / "skid.csv", recording=ImportOptions(wheelbase=0.5), fit_seconds=30.0,
                               course_speed=1.0)
    passed = [n for n in report["notes"] if n.startswith("passed over: --")]
    assert passed and all(o in passed[0] for o in ("--wheelbase", "--fit-seconds", "--course-speed"))
