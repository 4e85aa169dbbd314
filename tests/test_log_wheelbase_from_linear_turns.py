"""The log's wheelbase is read from its steady turns inside the tyres' linear range, selected on the
steering input as well as the yaw rate.

Independent truth: a 1:10 car of wheelbase 0.32 m driven by hand on a slippery floor, its steering
held in 0.6 s steps (mostly at the 0.34 rad lock) at 0.4-4 m/s, whose tyres give at most 0.2 g and
plough past their peak: a_y = a_kin / (1 + (a_kin / (2 mu g))^2), a_kin = v^2 tan(g delta) / L.
Its turns selected on a small measured |v r| alone are mostly ploughing ones (the yaw rate falls
short of the kinematic one), and read a wheelbase of about 0.5 m."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from agrobot.diagnosis.study_fit import study_check


def ploughing_car(gain: float = 1.0, L: float = 0.32, mu: float = 0.2, seconds: float = 120.0) -> pd.DataFrame:
    rng = np.random.default_rng(5)
    h = 0.02
    t = np.arange(0, seconds, h)
    levels = rng.choice([-0.34, -0.34, -0.34, -0.15, 0.15, 0.34, 0.34, 0.34], size=int(seconds / 0.6) + 1)
    delta = levels[(t // 0.6).astype(int)]
    v = 2.2 + 1.8 * np.sin(2 * np.pi * t / 40)
    kinematic = v * np.tan(gain * np.interp(t - 0.1, t, delta)) / L          # 0.1 s from command to wheels
    r_ss = kinematic / (1 + (v * kinematic / (2 * mu * 9.81)) ** 2)
    r = np.zeros_like(t)
    for k in range(1, len(t)):                                                # 0.08 s yaw lag
        r[k] = r[k - 1] + h / 0.08 * (r_ss[k - 1] - r[k - 1])
    return pd.DataFrame({"t": t, "v": v, "delta_cmd": delta, "yaw_rate": r + 0.005 * rng.standard_normal(len(t))})


def test_a_car_whose_tyres_plough_is_not_taken_for_a_longer_one():
    mine, warning = study_check(ploughing_car(), 0.32, "f1tenth.toml")
    assert warning is None
    assert mine["wheelbase"] == pytest.approx(0.32, rel=0.05)


def test_a_steering_map_turning_the_wheels_half_the_command_is_named_with_its_ratio():
    mine, warning = study_check(ploughing_car(gain=0.5), 0.32, "f1tenth.toml")
    assert mine["wheelbase"] == pytest.approx(0.32 * np.tan(0.34) / np.tan(0.17), rel=0.05)
    assert warning is not None and "0.48 x" in warning


def test_a_log_without_steady_linear_turns_tells_no_wheelbase():
    """Steering reversed every 0.3 s: no turn is steady for 0.5 s."""
    frame = ploughing_car()
    frame["delta_cmd"] = 0.2 * np.sign(np.sin(2 * np.pi * frame["t"] / 0.6))
    mine, warning = study_check(frame, 0.32, "f1tenth.toml")
    assert warning is None and mine["wheelbase"] is None and "too brief or too hard" in mine["why"]


def test_an_understeer_gradient_beyond_the_class_is_read_against_the_logs_steady_turns():
    """K = 0.036 rad/(m/s2) (20 deg/g) fitted on a scale car: with the study's wheelbase in the
    log's linear turns the steering map is cleared and nothing is decided; with turns of twice the
    wheelbase the steering map's gain is named with its ratio; an interval covering the class's
    range is no estimate."""
    from agrobot.diagnosis.plausibility import understeer
    from agrobot.identification.vehicle import Vehicle

    car = Vehicle.from_table({"class": "scale_car", "wheelbase": 0.32})
    same = understeer(0.036, car, 0.5, study_check(ploughing_car(), 0.32, "f1tenth.toml")[0])
    assert "cannot decide" in same and "not the cause" in same
    half = understeer(0.036, car, 0.5, study_check(ploughing_car(gain=0.5), 0.32, "f1tenth.toml")[0])
    assert "steering map's gain reads as tyres" in half and "0.48 x" in half
    wide = understeer({"value": -0.029, "interval": [-0.103, 0.045], "identifiable": True}, car, 0.5)
    assert wide.startswith("not identifiable from this log")


def test_a_fitted_steering_gain_is_checked_against_the_logs_steady_turns():
    """The car's steering map is exact (gain 1): a fitted steering_gain of 1.23 disagrees with its
    steady linear turns, one of 1.02 agrees; with a map of gain 0.5, 0.5 agrees."""
    from agrobot.diagnosis.plausibility import steering_gain_check

    exact = study_check(ploughing_car(), 0.32, "f1tenth.toml")[0]
    fitted = lambda k: [{"id": "steering_gain", "parameters": {"steering_gain": k}}]      # noqa: E731
    assert steering_gain_check(fitted(1.23), exact)[1] is False
    assert steering_gain_check(fitted(1.02), exact)[1] is True
    half = study_check(ploughing_car(gain=0.5), 0.32, "f1tenth.toml")[0]
    assert steering_gain_check(fitted(0.5), half)[1] is True


def test_a_steering_input_never_held_yields_no_steady_turn_even_at_the_log_start():
    """A steering ramp of 0.2 rad/s (0.1 rad over the 0.5 s a turn must be held): no sample is a steady
    turn, the log's first ones (with fewer than 0.5 s behind them) included."""
    from agrobot.diagnosis.study_fit import steady_turns

    t = np.arange(0.0, 2.0, 0.02)
    delta = 0.1 + 0.2 * t
    log = pd.DataFrame({"t": t, "v": np.full_like(t, 1.0), "delta": delta, "yaw_rate": np.tan(delta) / 2.5})
    assert len(steady_turns(log, 2.5)["v"]) == 0


def test_an_understeer_outside_its_class_without_steady_turns_says_so():
    """A car's K of 0.05 rad/(m/s2) (28 deg/g, beyond any car's) on a log without steady linear turns:
    the reason names them, not a bare dash."""
    from agrobot.diagnosis.plausibility import understeer
    from agrobot.identification.vehicle import Vehicle

    text = understeer(0.05, Vehicle.from_table({"class": "car"}), None, {})
    assert not text.rstrip().endswith("-") and "no steady turns to read a wheelbase from" in text
