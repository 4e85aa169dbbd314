"""The yaw plant's friction per axle, tyre_friction_ratio rho: the front axle's Magic Formula peak is
mu F_zf, the rear's rho mu F_zr (components.models.tyre). Independent references: the identification's
compiled single-track kernel (identification/single_track_kernel.c, which takes the rear's peak as
mu F_zr with F_zr given as rho F_zr) stepping the same car with the wheel angle held over each step
(a zero-order hold, the plant's), and the plant's own step before the ratio existed (models.tyre.ros2_step
with one mu on both axles), which rho = 1 repeats to the bit."""
from __future__ import annotations

import math

import numpy as np
import pytest

from agrobot.components.models.tyre import axle_loads, ros2_step
from agrobot.components.tractor_yaw_plant import TractorYawPlant
from agrobot.identification import single_track_kernel
from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study, StudyError
from agrobot.studies import shipped

# a 982 kg mid-engined car (l_f 1.33 m, l_r 1.07 m), Magic Formula tyres of front friction 0.9
CAR = {"m": 982.0, "I": 982.0 * 1.33 * 1.07, "l_f": 1.33, "l_r": 1.07, "C_f": 7.0e4, "C_r": 1.2e5,
       "sigma_f": 0.5, "sigma_r": 0.8, "tyre_friction": 0.9, "tyre_shape": 1.3}
H, SPEED = 0.01, 20.0


def steering(n: int = 400) -> np.ndarray:
    """From straight ahead into a ramp to 0.06 rad and back through the other side: both axles bend."""
    t = np.arange(n) * H
    return 0.06 * np.sin(2 * np.pi * t / 3.0) * np.minimum(t / 1.0, 1.0)


def plant_run(delta: np.ndarray, **parameters) -> tuple[np.ndarray, np.ndarray]:
    """(yaw rate, lateral velocity) after each step of the plant at SPEED from rest."""
    plant = TractorYawPlant("car", {"model": "rlf", **CAR, **parameters})
    plant.initialize(0.0, H)
    yaw, vy = np.empty(len(delta)), np.empty(len(delta))
    for k, d in enumerate(delta):
        plant.u["steer_angle"], plant.u["speed"] = float(d), SPEED
        plant.step(k * H, H)
        yaw[k], vy[k] = plant.y["yaw_rate"], plant.y["lateral_velocity"]
    return yaw, vy


@pytest.mark.parametrize("model", ["bicycle", "rlf"])
def test_the_plant_steps_a_friction_per_axle_as_the_compiled_kernel(model):
    delta = steering()
    n = len(delta)
    fzf, fzr = axle_loads(CAR["m"], CAR["l_f"], CAR["l_r"])
    runs = {}
    for ratio in (1.0, 0.6, 1.6):
        plant = TractorYawPlant("car", {"model": model, **CAR, "tyre_friction_ratio": ratio})
        plant.initialize(0.0, H)
        yaw = np.empty(n)
        for k, d in enumerate(delta):
            yaw[k] = plant.y["yaw_rate"]
            plant.u["steer_angle"], plant.u["speed"] = float(d), SPEED
            plant.step(k * H, H)
        row = {"lag_decay": 0.0, "hold_gain": 1.0, "lag": 0.0, "delay": 0.0, "C_f": CAR["C_f"], "C_r": CAR["C_r"],
               "mu": CAR["tyre_friction"], "shape": CAR["tyre_shape"], "cornering_speed_slope": 0.0,
               "cornering_reference_speed": 2.0, "sigma_f": CAR["sigma_f"], "sigma_r": CAR["sigma_r"], "m": CAR["m"],
               "I": CAR["I"], "l_f": CAR["l_f"], "l_r": CAR["l_r"], "F_zf": fzf, "F_zr": ratio * fzr}
        par = np.array([[row[k] for k in single_track_kernel.PARAMETERS]])
        # the plant's sub-steps (at most 2 ms): five per 10 ms step, the wheel angle held over it
        kernel, _ = single_track_kernel.simulate(model, math.ceil(H / 0.002), H, delta[None], np.full((1, n), SPEED),
                                                 par, np.ones((1, n)))
        assert np.max(np.abs(yaw - kernel[0])) <= 1e-9 * np.max(np.abs(kernel[0])), ratio
        runs[ratio] = yaw
    assert np.max(np.abs(runs[1.0])) * SPEED > 0.8 * CAR["tyre_friction"] * 9.81       # driven into the bend
    # the rear letting go first turns the car harder, the front first less
    assert np.max(np.abs(runs[0.6])) > 1.05 * np.max(np.abs(runs[1.0])) > 1.05 * np.max(np.abs(runs[1.6]))


def test_a_ratio_of_one_is_the_plant_of_one_friction_to_the_bit():
    """rho = 1 (the default) steps the state as the plant did with one mu on both axles: ros2_step
    with ``mu`` alone, five 2 ms sub-steps per 10 ms step."""
    delta = steering(150)
    yaw, vy = plant_run(delta)
    plant = TractorYawPlant("car", {"model": "rlf", **CAR})
    plant.initialize(0.0, H)
    params = plant.params
    z = np.zeros(3)
    for k, d in enumerate(delta):
        for _ in range(5):
            z = ros2_step("rlf", params, z, H / 5, SPEED, SPEED, float(d), float(d), mu=CAR["tyre_friction"],
                          shape=CAR["tyre_shape"], C_f=params.C_f, C_r=params.C_r)
        assert (yaw[k], vy[k]) == (z[1], z[0]), k
    again = plant_run(delta, tyre_friction_ratio=1.0)
    assert np.array_equal(yaw, again[0]) and np.array_equal(vy, again[1])


@pytest.mark.parametrize("value", ["3.0", "0.2", "-1.0"])
def test_a_ratio_out_of_its_range_is_refused_naming_the_file_the_field_and_the_range(value):
    study = Study.load(shipped("figure8.toml"), ["tractor.tyre_friction=0.8", f"tractor.tyre_friction_ratio={value}"])
    with pytest.raises(StudyError) as err:
        build_system(resolve(study))
    said = str(err.value)
    assert "figure8.toml: components.tractor" in said and f"tyre_friction_ratio={float(value)!r}" in said
    assert "expected a number in [0.5, 2]" in said and "mu_r / mu_f" in said
