"""The yaw plant's steering geometry: under "tan" the dynamics are driven by tan(delta), so the turn
without slip is the Ackermann one r = v tan(delta) / L at any lock, the linearisation about the
straight line is the linear plant's, and the C core steps the same plant as the Python one. The
diagnosis replays its baseline under the geometry chosen (the option, the study's or identify's):
an Ackermann machine steered to 0.6 rad with a perfect map is not read as a steering ratio curve
(the cubic term of tan, 1/3, under "w"), and a planted curve is still named with its value.

The truths: the kinematic limit v tan(delta) / L worked by hand; harness.small_ackermann's machine,
integrated from r = v tan(w) / (L + K v^2) (its own equations, not the plant's), with the map of
harness.steering_maps planted by read_through."""
from __future__ import annotations

import math

import numpy as np
import pytest

from agrobot.components.tractor_yaw_plant import MAX_TAN_ANGLE, TractorYawPlant, steer_input
from agrobot.diagnosis.pipeline import diagnose
from agrobot.diagnosis.baseline import fixed_geometry
from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.engine import Simulation
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study
from agrobot.studies import shipped
from harness.small_ackermann import make_small_log
from harness.steering_maps import read_through
from harness.vehicle_classes import study

L = 1.4          # the plant's default l_f + l_r


def _steady_yaw_rate(geometry: str, speed: float, delta: float, **params) -> float:
    plant = TractorYawPlant("t", {"model": "rlf", "steering_geometry": geometry, **params})
    plant.initialize(0.0, 0.01)
    plant.u.update(speed=speed, steer_angle=delta)
    for k in range(4000):
        plant.step(k * 0.01, 0.01)
    return plant.y["yaw_rate"]


@pytest.mark.parametrize("delta", [0.5, 0.9])
def test_at_walking_pace_tan_turns_on_the_ackermann_radius_and_w_on_the_small_angle_one(delta):
    v = 0.2                                   # K v^2 / L ~ 1e-4: the kinematic limit
    assert _steady_yaw_rate("tan", v, delta) == pytest.approx(v * math.tan(delta) / L, rel=2e-3)
    assert _steady_yaw_rate("w", v, delta) == pytest.approx(v * delta / L, rel=2e-3)


def test_small_angles_and_the_linearisation_are_the_linear_plants():
    v, delta = 2.0, 0.01                      # tan 0.01 = 0.01 (1 + 3.3e-5)
    assert _steady_yaw_rate("tan", v, delta) == pytest.approx(_steady_yaw_rate("w", v, delta), rel=1e-4)
    blocks = []
    for geometry in ("w", "tan"):
        plant = TractorYawPlant("t", {"model": "rlf", "steering_geometry": geometry})
        plant.initialize(0.0, 0.01)
        blocks.append(plant.linear_model(0.01, 2.0))
    np.testing.assert_array_equal(blocks[0].B, blocks[1].B)


def test_the_offset_is_added_before_the_tangent_and_the_angle_clipped():
    v, delta, offset = 0.2, 0.6, 0.05
    assert _steady_yaw_rate("tan", v, delta, steer_angle_offset=offset) == pytest.approx(
        v * math.tan(delta + offset) / L, rel=2e-3)
    assert steer_input(1.45, "tan") == pytest.approx(math.tan(MAX_TAN_ANGLE))
    assert steer_input(0.7, "w") == 0.7


def test_an_unknown_geometry_is_refused_by_name():
    plant = TractorYawPlant("t", {"steering_geometry": "atan"})
    with pytest.raises(Exception, match="steering_geometry='atan'"):
        plant.initialize(0.0, 0.01)
    with pytest.raises(ValueError, match="--steering-geometry 'atan'"):
        fixed_geometry("atan", None)


@pytest.mark.slow
def test_the_c_core_steps_the_tan_plant_as_the_python_one(tmp_path, monkeypatch):
    from agrobot.orchestrator.compiled import CompiledSimulation

    monkeypatch.setenv("AGROBOT_CACHE", str(tmp_path))
    quiet = ["gps.position_noise_std=0", "gps.velocity_noise_std=0", "steering.potentiometer_resolution=0",
             "study.stop_time=30"]
    runs = {}
    for geometry in ("w", "tan"):
        study_ = Study.load(shipped("figure8.toml"), quiet + [f"tractor.steering_geometry={geometry}"])
        compiled = CompiledSimulation(build_system(resolve(study_))).run()
        python = Simulation(build_system(resolve(study_))).run()
        k = compiled.columns.index("tractor.yaw_rate") + 1
        np.testing.assert_allclose(compiled.data[:, k], python.data[:, k], rtol=0, atol=1e-9)
        runs[geometry] = compiled.data[:, k]
    assert np.abs(runs["tan"] - runs["w"]).max() > 1e-6      # the core does step the tangent


def _diagnosed(tmp_path, geometry: str, curvature: float = 0.0, identify: bool = False) -> dict:
    """The machine with a perfect map (gain 1, no asymmetry, no offset) steered up to 0.6 rad at
    0.3-1.5 m/s for 240 s, its wheel-angle reading through a planted ratio curve; no command column
    (the yaw and track stages judged), diagnosed against its baseline study."""
    frame, _ = make_small_log(5507, duration=240.0, truth=dict(gain=1.0, asymmetry=0.0, offset=0.0))
    frame = frame.drop(columns=["delta_cmd"])
    assert np.percentile(np.abs(frame["delta"]), 99) >= 0.5          # large angles: tan w exceeds w by 10 %
    if curvature:
        frame = read_through(frame, curvature=curvature)
    log = tmp_path / "log.parquet"
    frame.to_parquet(log)
    return diagnose(log, None, study(tmp_path, speeds=(0.3, 0.8, 1.5)), plots=False, identify=identify,
                    steering_geometry=geometry)


@pytest.mark.slow
def test_a_perfect_ackermann_map_read_under_w_is_the_cubic_of_tan(tmp_path):
    """The failure the geometry removes: under "w" the tangent's cubic term is named as a ratio curve."""
    res = _diagnosed(tmp_path, "w")
    found = {e["id"]: e for e in res["effects"]}
    assert res["verdict"] == "steering_ratio_curve", res["verdict_statement"]
    assert found["steering_ratio_curve"]["parameters"]["steering_ratio_curvature"] == pytest.approx(1 / 3, abs=0.1)


@pytest.mark.slow
def test_a_perfect_ackermann_map_under_tan_names_nothing(tmp_path):
    res = _diagnosed(tmp_path, "tan")
    assert res["verdict"] == "none", (res["verdict_statement"], res["selection_trace"])
    assert res["steering_geometry"]["value"] == "tan"
    assert "--steering-geometry tan" in res["steering_geometry"]["says"]


@pytest.mark.slow
def test_identify_chooses_tan_for_the_diagnosis_in_the_kinematic_regime(tmp_path):
    res = _diagnosed(tmp_path, "auto", identify=True)
    assert res["steering_geometry"]["value"] == "tan", res["steering_geometry"]
    assert "identify" in res["steering_geometry"]["says"] and "passed over: delta" in res["steering_geometry"]["says"]
    assert res["verdict"] == "none", res["verdict_statement"]


@pytest.mark.slow
def test_a_planted_ratio_curve_is_named_relative_to_tan(tmp_path):
    res = _diagnosed(tmp_path, "tan", curvature=0.8)
    found = {e["id"]: e for e in res["effects"]}
    assert res["verdict"] == "steering_ratio_curve", res["verdict_statement"]
    assert found["steering_ratio_curve"]["parameters"]["steering_ratio_curvature"] == pytest.approx(0.8, abs=0.15)


def test_a_study_declaring_its_geometry_is_taken_without_identify(tmp_path):
    from agrobot.diagnosis.baseline import baseline_from_study

    path = study(tmp_path, speeds=(0.3, 0.8, 1.5))
    base = baseline_from_study(Study.load(path, ["car.steering_geometry=tan"]))
    assert (base.steering_geometry, base.geometry_declared) == ("tan", True)
    assert fixed_geometry("auto", base) == ("tan", "the study's yaw plant steering_geometry = 'tan'")
    assert fixed_geometry("w", base)[0] == "w"
    assert not baseline_from_study(Study.load(path)).geometry_declared
