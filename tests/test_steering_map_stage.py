"""The steering map read on the steering stage, and the map effects' ranges on every machine, against
independent truths: an actuator simulated in wheel angles and read through harness.steering_maps'
own inverse of the map (Newton's method, not the diagnosis's table), and the yaw rate an offset
makes, v o / L."""
from __future__ import annotations

import math

import numpy as np
import pytest

from agrobot.components.models import steering_equivalent
from agrobot.estimation import FitResult
from agrobot.diagnosis.catalogue import CATALOGUE
from agrobot.diagnosis.effects.steering_offset import SPEED_KEY, WHEELBASE_KEY
from agrobot.diagnosis.effects.steering_ratio_curve import DELTA_KEY
from agrobot.diagnosis.selection import _judge
from agrobot.diagnosis.steering_map import mapped_steering
from harness.steering_maps import reading

H, TAU, DEAD, RATE = 0.05, 0.05, 0.002, 0.6
VALUES = {"steering_time_constant": TAU, "steering_deadband": DEAD, "steering_rate_limit": RATE, "command_delay": 0.0}
EFFECTS = {e.id: e for e in CATALOGUE}


def _command(seed: int = 3) -> np.ndarray:
    """Steps of up to +-0.4 rad held 3 s: the large ones ride on the rate limit."""
    rng = np.random.default_rng(seed)
    return np.repeat(rng.uniform(-0.4, 0.4, 40), int(3.0 / H))


@pytest.mark.parametrize("planted", [{"gain": 1.25}, {"gain": 0.8}, {"asymmetry": 0.2}, {"curvature": 2.0}])
def test_the_steering_stage_read_through_the_map_is_the_actuator_moving_the_wheels(planted):
    """An actuator whose rate limit is a wheel rate, its command and angle logged through a map that
    is off: replayed through the same map the log is met to rounding; the plain replay (the rate
    in the reading's units) misses it by a material amount."""
    wheels_cmd = _command()
    wheels = steering_equivalent.simulate(wheels_cmd, H, TAU, DEAD, RATE, 0.0, 0.0)
    cmd, logged = reading(wheels_cmd, **planted), reading(wheels, **planted)
    names = {"gain": "steering_gain", "asymmetry": "steering_asymmetry", "curvature": "steering_ratio_curvature"}
    v = {**VALUES, **{names[k]: x for k, x in planted.items()}}
    mapped = mapped_steering(cmd, H, v, float(logged[0]))
    plain = mapped_steering(cmd, H, VALUES, float(logged[0]))
    assert np.max(np.abs(mapped - logged)) < 1e-4
    assert np.sqrt(np.mean((plain - logged) ** 2)) > math.radians(0.25)


def test_without_a_map_the_steering_stage_is_the_plain_replay():
    cmd = _command(5)
    np.testing.assert_array_equal(mapped_steering(cmd, H, VALUES, 0.0),
                                  steering_equivalent.simulate(cmd, H, TAU, DEAD, RATE, 0.0, 0.0))


def test_the_map_effects_are_fitted_on_the_turns_and_tested_on_the_steering():
    for eid in ("steering_gain", "steering_asymmetry", "steering_ratio_curve"):
        assert EFFECTS[eid].stages[0] == "yaw" and EFFECTS[eid].tested_on == ("steering",)
    assert EFFECTS["steering_offset"].tested_on == ()         # an offset cancels in the loop's difference


@pytest.mark.parametrize("offset_deg, speed, wheelbase, material", [
    (0.1, 20.0, 2.7, True),      # a car: v o / L = 0.013 rad/s
    (0.1, 0.8, 1.27, False),     # a small robot at walking speed: 0.001 rad/s, under 0.3 deg
    (0.35, 0.8, 1.27, True),     # a zero a mechanic resets, whatever the speed
    (0.02, 20.0, 2.7, False),    # 0.0026 rad/s
])
def test_an_offset_is_material_by_its_angle_or_by_the_yaw_rate_it_makes(offset_deg, speed, wheelbase, material):
    base = {"steer_angle_offset": 0.0, SPEED_KEY: speed, WHEELBASE_KEY: wheelbase}
    yaw = speed * math.radians(offset_deg) / wheelbase
    assert (yaw >= 0.005 or offset_deg >= 0.3) is material
    assert EFFECTS["steering_offset"].material({"steer_angle_offset": math.radians(offset_deg)}, base) is material


def test_a_ratio_curve_is_searched_for_the_same_ratio_changes_at_a_cars_small_angles():
    """At 1 deg of steering the curvature's range is scaled by (0.3 rad / 1 deg)^2: the ratio changes
    c delta^2 it can reach at the log's angles are the tractor's at 0.3 rad."""
    curve = EFFECTS["steering_ratio_curve"]
    (p,) = curve.parameters
    d = math.radians(1.0)
    (q,) = curve.for_log({DELTA_KEY: d}).parameters
    assert q.upper * d * d == pytest.approx(p.upper * 0.3 ** 2)
    assert q.limit[0] * d * d == pytest.approx(p.limit[0] * 0.3 ** 2)
    assert curve.for_log({DELTA_KEY: 0.4}) is curve
    assert curve.parameters[0] is p                               # the catalogue's own is left as it was


def _fit_of(rmse: dict, rss: dict) -> FitResult:
    return FitResult({"steering_gain": 1.25}, (), np.zeros((0, 0)), dict(rss), {s: 1000 for s in rss}, {s: 300.0 for s in rss},
                     dict(rmse))


@pytest.mark.parametrize("track_after, supported", [(0.0236, True), (0.05, False)])
def test_a_track_left_within_its_noise_does_not_count_against_a_gain_that_fixes_the_turns(track_after, supported):
    """The yaw rate's held-out RMS falls by 22 %; the track's rises by 5.3 % to 0.0236 m on a 0.0227 m
    floor (1.04 x: noise, as a car's map gain left it) or to 0.05 m (2.2 x its floor, 0.044 m above
    it: misfit, then it counts)."""
    gain = EFFECTS["steering_gain"]
    floors = {"yaw": 0.0019, "position": 0.0227, "_healthy": {"yaw": 0.0024, "position": 0.0227}}
    without = _fit_of({"yaw": 0.0040, "position": 0.0224}, {"yaw": 1.6e-5 * 1000, "position": 0.0224 ** 2 * 1000})
    with_ = _fit_of({"yaw": 0.0031, "position": track_after}, {"yaw": 0.96e-5 * 1000, "position": 0.0224 ** 2 * 1000})
    judged = _judge(gain, with_, without, ("yaw", "position"), {"steering_gain": 1.0}, 0.05, floors)
    assert judged.supported is supported, judged.reasons
    assert _judge(gain, with_, without, ("yaw", "position"), {"steering_gain": 1.0}, 0.05).supported is False
