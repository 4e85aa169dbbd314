"""Identification from ordinary driving on real F1TENTH logs (tests/data copies) and on a simulated
log whose truth is known, checked against a second method (the steady-state regression, and the
closed-form K of the truth's stiffnesses)."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from agrobot.identification.driving import NotEnoughDriving, understeer_gradient
from agrobot.identification.ordinary_driving import identify_driving, summary
from agrobot.measurements import LogError
from agrobot.orchestrator.study import Study
from tests.vehicle_logs import ROOT_STUDIES, autokoopman_log, frictionmaps_log

STUDY = ROOT_STUDIES / "f1tenth.toml"


@pytest.fixture(scope="module")
def study():
    return Study.load(STUDY)


def within(a: dict, b: dict) -> bool:
    """Two estimates agree when their difference is within 1.96 x the combined standard error."""
    return abs(a["value"] - b["value"]) <= 1.96 * math.hypot(a["std"], b["std"])


@pytest.fixture(scope="module")
def ds5(study):
    return identify_driving(frictionmaps_log("DS5"), "DS5", study)


def test_f1tenth_ds5_delay_understeer_saturation_and_held_out_fit(ds5):
    d, K, fit = ds5["delay"], ds5["understeer_gradient"], ds5["held_out_fit"]
    # the README's command-to-yaw delay is about 0.15 s, of which the yaw dynamics take part:
    # the steering's pure delay is a positive fraction of it, well resolved
    assert 0.02 < d["value"] < 0.15 and d["interval"][0] > 0 and d["identifiable"]
    assert K["identifiable"] and K["interval"][0] < K["value"] < K["interval"][1]
    assert 60 < fit["value"] <= 100 and len(fit["per_segment"]) >= 2
    tyre = ds5["tyre_saturation"]
    assert tyre["found"], tyre["why_not"]
    mu = tyre["parameters"]["friction"]
    assert 0.3 < mu["value"] < 1.2                                 # a plastic-tyred car on a floor
    # with the shape C on its bound (C < 1 never reaches the peak: sin(C atan) < sin(C pi/2)) the
    # friction is an extrapolation, never a concluded value; with C free it is concluded
    shape_on_bound = tyre["parameters"]["shape"].get("note", "").startswith("not identifiable")
    assert mu["identifiable"] != shape_on_bound, mu.get("note")
    # the linear range ends where the Magic Formula leaves the linear tyre, below the log's top
    assert ds5["linear_range"]["value"] < 9.81 * mu["value"]
    for name, p in ds5["parameters"].items():                     # every parameter with bounds and interval
        assert len(p["interval"]) == 2 and (p["bounds"] is None or len(p["bounds"]) == 2), name
    text = summary(ds5)                                            # what the engineer reads, saturation found
    assert "tyre saturation found: friction" in text and f"{mu['value']:.3g}" in text


@pytest.mark.slow
def test_f1tenth_slow_run_says_what_it_cannot_identify(study):
    """DS3 is driven at one speed (1.2-1.5 m/s, |a_y| < 2 m/s2): the cornering stiffnesses are not
    identifiable and the steady-state regression refuses (gain and K not told apart); the delay is."""
    rep = identify_driving(frictionmaps_log("DS3"), "DS3", study)
    assert rep["delay"]["identifiable"] and 0.02 < rep["delay"]["value"] < 0.15
    assert "understeer_gradient" not in rep["steady_state_regression"]
    assert "one speed" in rep["steady_state_regression"]["note"]
    assert not rep["tyre_saturation"]["found"]


@pytest.mark.slow
def test_two_encodings_of_one_drive_agree(study):
    """DS1 imported at its fastest stream's rate (39 Hz) and at 20 Hz: delay and K agree within
    their intervals."""
    a = identify_driving(frictionmaps_log("DS1"), "DS1 at 39 Hz", study)
    b = identify_driving(frictionmaps_log("DS1", rate=20.0), "DS1 at 20 Hz", study)
    assert within(a["delay"], b["delay"])
    assert within(a["understeer_gradient"], b["understeer_gradient"])


@pytest.mark.slow
def test_autokoopman_asymmetry_is_a_steering_offset(study):
    """The step runs turn less to the left than to the right (README: an offset of about
    -0.015 rad with a gain of 0.77-0.9): the fit names the offset with an interval excluding zero."""
    rep = identify_driving(autokoopman_log(), "AutoKoopman", study)
    off, gain = rep["parameters"]["steer_offset"], rep["parameters"]["steer_gain"]
    assert off["interval"][1] < 0 and -0.025 < off["value"] < -0.005
    assert 0.7 < gain["value"] < 1.0 and gain["interval"][1] < 1.05
    # independent: the mean steady yaw rate of the +-0.1 rad step runs against the kinematic one
    log = autokoopman_log()
    last = log.groupby("run").tail(40)
    ratio = {}
    for sign in (1, -1):
        sel = last[np.isclose(last["delta_cmd"], sign * 0.1) & (last["v"] > 0.25)]
        ratio[sign] = float((sel["yaw_rate"] * 0.32 / (sel["v"] * sel["delta_cmd"])).mean())
    # with r = g (u + offset/g) v / L: ratio(+) - ratio(-) = 2 offset / 0.1
    offset_from_steps = 0.1 * (ratio[1] - ratio[-1]) / 2
    assert abs(offset_from_steps - off["value"]) < 0.006


def simulated_log(stop: float = 150.0):
    """The F1TENTH study with a stiffer rear axle (c_r = 10: understeer K = (1/5 - 1/10)/g)."""
    from agrobot.orchestrator.runner import simulate

    st = Study.load(STUDY).with_values({"car.C_r": 114.0, "study.stop_time": stop, "plan.duration": stop})
    rec, _ = simulate(st)
    f = rec.to_frame()
    f = f.iloc[::4].reset_index(drop=True)                     # 50 Hz
    return pd.DataFrame({"t": f["t"], "delta_cmd": f["plan.steer_angle_cmd"], "delta": f["steering.steer_angle_measured"],
                         "v": f["car.yaw_rate"] * 0 + f["plan.speed_cmd"], "yaw_rate": f["gyro.yaw_rate_measured"]})


@pytest.mark.slow
def test_simulated_truth_recovered_and_regression_agrees(study):
    log = simulated_log()
    rep = identify_driving(log, "simulated", study)
    K_true = understeer_gradient(5.0, 10.0)                     # the truth's C / F_z: 106/21.2 and 114/11.4
    K = rep["understeer_gradient"]
    assert K["interval"][0] <= K_true <= K["interval"][1] or abs(K["value"] - K_true) < 0.2 * K_true
    ss = rep["steady_state_regression"]
    assert "understeer_gradient" in ss, ss
    # the two agree within their intervals, or within 3 % (the intervals hold the noise only, not
    # the simulation's discretisation; this log is nearly noise-free)
    assert within(K, ss["understeer_gradient"]) or abs(K["value"] - ss["understeer_gradient"]["value"]) < 0.03 * K_true
    assert rep["delay"]["value"] < 0.03                          # a measured wheel angle: no delay left
    assert not rep["tyre_saturation"]["found"]


@pytest.mark.parametrize("case, expect", [
    ("no_yaw", "no yaw_rate"),
    ("YawRate", "the log has YawRate: rename it to yaw_rate"),
    ("short", "record"),
    ("straight", "the steering hardly moves"),
])
def test_bad_logs_are_named(study, case, expect):
    log = frictionmaps_log("DS1")
    if case == "no_yaw":          # no gyro, no heading, no positions for a course
        log = log.drop(columns=[c for c in ("yaw_rate", "heading", "x", "y") if c in log])
    elif case == "YawRate":
        log = log.rename(columns={"yaw_rate": "YawRate"})
    elif case == "short":
        log = log[log["t"] < 12.0]
    else:
        log = log.assign(delta_cmd=0.0)
    with pytest.raises((LogError, NotEnoughDriving)) as err:
        identify_driving(log, "log.csv", study)
    assert expect in str(err.value)


def test_extended_study_plant_saturates_at_the_friction_limit():
    """The yaw plant with tyre_friction (the extended study's option) never turns the car harder
    than friction allows: its lateral acceleration a_y = dv_y/dt + v r (the axle forces over the
    mass) stays within mu g (a closed-form bound), where the linear tyre goes far beyond it."""
    from agrobot.components.tractor_yaw_plant import TractorYawPlant

    def peak_lateral(mu: float) -> float:
        plant = TractorYawPlant("car", {"model": "bicycle", "m": 3.33, "I": 0.0687, "l_f": 0.112, "l_r": 0.208,
                                        "C_f": 106.0, "C_r": 114.0, "tyre_friction": mu, "tyre_shape": 1.3})
        h, peak, vy = 0.005, 0.0, 0.0
        plant.initialize(0.0, h)
        for k in range(800):
            plant.u["steer_angle"], plant.u["speed"] = 0.3, 3.0
            plant.step(k * h, h)
            a_y = (plant.y["lateral_velocity"] - vy) / h + 3.0 * plant.y["yaw_rate"]
            vy = plant.y["lateral_velocity"]
            peak = max(peak, abs(a_y)) if k > 0 else peak
        return peak

    mu = 0.5
    assert peak_lateral(mu) <= mu * 9.81 * 1.02
    assert peak_lateral(0.0) > 1.5 * mu * 9.81


def test_the_minimum_driving_is_guidance_down_to_its_floor():
    """20 s of driving is the nominal minimum: 19 s is identified with a warning naming both
    numbers, under two thirds of it (13.3 s) the log is refused naming the floor."""
    from agrobot.identification.ordinary_driving import MIN_DRIVING
    from harness.truth_tractor import make_log
    from agrobot.studies import shipped

    figure8 = Study.load(shipped("figure8.toml"))
    frame, _ = make_log(5, None, duration=40.0)
    rep = identify_driving(frame[frame.t < 20.0].copy(), "short.csv", figure8)
    seconds = rep["seconds_driven"]
    assert 2 / 3 * MIN_DRIVING <= seconds < MIN_DRIVING
    warned = [n for n in rep["notes"] if n.startswith("warning:")]
    assert len(warned) == 1 and f"{seconds:.3g} s" in warned[0] and "20 s" in warned[0] and "13.3 s" in warned[0]
    with pytest.raises(NotEnoughDriving, match=r"under the floor 13\.3 s"):
        identify_driving(frame[frame.t < 13.0].copy(), "shorter.csv", figure8)
