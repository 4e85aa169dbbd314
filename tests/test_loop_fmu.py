"""The figure-8's whole loop as one FMU (export-fmu, fmu_export.loop_fmu) against the study run
by the Python engine: fmpy validates it, and fmpy and libcosim, stepping it at the study's base
step, give every recorded signal of the Python run at every instant to 1e-9 of the signal's
scale. Noise off and the potentiometer's quantisation off, as in tests/test_compiled_engine.py:
a 1e-16 difference of arithmetic order that meets a quantisation threshold flips one level.

A study with components that have no C core exits 2 naming them, and writes nothing."""
from __future__ import annotations

import os

import numpy as np
import pytest

from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.engine import Simulation
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study
from agrobot.studies import shipped

STOP, H = 4.0, 0.01
QUIET = ["gps.position_noise_std=0", "gps.velocity_noise_std=0", "steering.potentiometer_resolution=0",
         f"study.stop_time={STOP}"]


@pytest.fixture(scope="module", autouse=True)
def cache(tmp_path_factory):
    """The module's own compiled-engine cache: each shape compiled once, nothing left behind."""
    old = os.environ.get("AGROBOT_CACHE")
    os.environ["AGROBOT_CACHE"] = str(tmp_path_factory.mktemp("compiled-cache"))
    yield
    if old is None:
        os.environ.pop("AGROBOT_CACHE", None)
    else:
        os.environ["AGROBOT_CACHE"] = old


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """(the FMU, the line saying which ports it has, the Python engine's recording) of the quiet
    figure-8, exported once."""
    from agrobot.api import export_fmu

    study = Study.load(shipped("figure8.toml"), QUIET)
    made = export_fmu(study, out=tmp_path_factory.mktemp("fmu") / "figure8.fmu", fmi_version=2)
    fmu, note = made.path, made.note
    assert study.study.base_step == H
    return fmu, note, Simulation(build_system(resolve(study))).run()


def relative_difference(rec, frame, prefix: str = "", first_row: int = 0) -> dict[str, float]:
    """Largest difference of each recorded signal, over the signal's scale (its largest magnitude)."""
    worst = {}
    for j, name in enumerate(rec.columns):
        ours = rec.data[first_row:, j + 1]
        theirs = np.asarray(frame[prefix + name], dtype=float)
        assert theirs.shape == ours.shape, name
        worst[name] = float(np.abs(theirs - ours).max() / max(np.abs(ours).max(), 1e-12))
    return worst


def test_fmpy_and_libcosim_run_the_loop_fmu_as_the_python_engine_runs_the_study(exported):
    from fmpy import read_model_description, simulate_fmu
    from fmpy.validation import validate_fmu

    from agrobot.fmu_export.foreign_engines import libcosim_fmu_run

    fmu, note, rec = exported
    assert validate_fmu(str(fmu)) == []
    md = read_model_description(str(fmu))
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    assert outputs == rec.columns and "every signal the study records" in note    # figure8 declares no [exports]
    assert not [v for v in md.modelVariables if v.causality == "input"]
    assert float(md.defaultExperiment.stepSize) == H
    units = {v.name: v.unit for v in md.modelVariables}
    assert units["tractor.x_cg"] == "m" and units["tractor.yaw_rate"] == "rad/s"

    # fmpy: row k is t_k = k h, the outputs after initialisation first
    res = simulate_fmu(str(fmu), stop_time=STOP, step_size=H, output_interval=H, output=outputs)
    np.testing.assert_allclose(res["time"], rec.data[:, 0], atol=1e-9)
    worst = relative_difference(rec, res)
    assert max(worst.values()) < 1e-9, {k: v for k, v in worst.items() if v >= 1e-9}
    assert np.ptp(rec.data[:, 1 + rec.columns.index("tractor.x_cg")]) > 1.0    # the tractor moved

    # libcosim: outputs read after each step, row k is t_(k+1)
    frame = libcosim_fmu_run(fmu, STOP, H, name="loop")
    np.testing.assert_allclose(frame["t"], rec.data[1:, 0], atol=1e-9)
    worst = relative_difference(rec, frame, "loop.", first_row=1)
    assert max(worst.values()) < 1e-9, {k: v for k, v in worst.items() if v >= 1e-9}



def test_fmpy_runs_the_loop_fmu_with_its_defaults(exported):
    """fmpy's simulate_fmu with its defaults: over a long experiment it doubles the default
    experiment's step until at most 1000 steps (40 s: 0.04 s, 4 sample periods; the 160 s figure-8:
    0.16 s), and each such step is taken as that many samples. The outputs at its output times
    are the Python run's at those instants."""
    from fmpy import simulate_fmu

    fmu, _, rec = exported
    long = simulate_fmu(str(fmu), stop_time=40.0)           # nothing but the stop time
    step = float(np.diff(long["time"])[0])
    assert step == pytest.approx(4 * H) and long["time"][-1] == pytest.approx(40.0)
    res = simulate_fmu(str(fmu), output_interval=step)      # the same step over the study's own 4 s
    rows = np.rint(res["time"] / H).astype(int)
    assert len(rows) == round(STOP / step) + 1
    for j, name in enumerate(rec.columns):
        ours = rec.data[rows, j + 1]
        scale = max(np.abs(rec.data[:, j + 1]).max(), 1e-12)
        assert np.abs(np.asarray(res[name], float) - ours).max() / scale < 1e-9, name
        assert np.asarray(long[name], float)[: len(rows)] == pytest.approx(np.asarray(res[name], float), abs=1e-12)



def test_the_loop_fmus_parameters_set_by_a_master_give_the_study_run_with_them(exported, capsys):
    """Parameters a master sets before the initialization ends (fmpy's start_values) give the
    study run by the Python engine with the same --set; one that shapes what is built (the
    reference's radius: the reference's path, a compiled-in output at t0) is not offered; one set
    during the run is refused by name."""
    from fmpy import read_model_description, simulate_fmu

    fmu, note, base = exported
    md = read_model_description(str(fmu))
    params = {v.name: v for v in md.modelVariables if v.causality == "parameter"}
    assert {"tracker.lookahead", "tractor.C_f", "speed_controller.kp"} <= params.keys()
    assert "reference.radius" not in params and "reference.radius" in note
    assert {v.variability for v in params.values()} == {"fixed"}
    changed = {"tracker.lookahead": 2.4, "tractor.C_f": 6000.0}
    res = simulate_fmu(str(fmu), start_values=changed, output_interval=H)
    rec = Simulation(build_system(resolve(Study.load(shipped("figure8.toml"), QUIET + [
        f"{k}={v}" for k, v in changed.items()])))).run()
    worst = relative_difference(rec, res)
    assert max(worst.values()) < 1e-9, {k: v for k, v in worst.items() if v >= 1e-9}
    assert max(relative_difference(base, res).values()) > 1e-4            # the parameters did change the run
    with pytest.raises(Exception):
        simulate_fmu(str(fmu), stop_time=0.1, input=None, output_interval=H,
                     step_finished=lambda time, recorder: _set_during_run(recorder, params["tracker.lookahead"]))
    assert "tracker.lookahead is a fixed parameter: set it before the initialization ends" in capsys.readouterr().out


def _set_during_run(recorder, variable) -> bool:
    recorder.fmu.setReal([variable.valueReference], [2.0])
    return True

def test_a_step_neither_multiple_nor_divisor_of_the_period_is_refused_with_the_numbers_in_order(exported, capsys):
    from fmpy import simulate_fmu

    fmu, _, _ = exported
    with pytest.raises(Exception, match="DoStep"):
        simulate_fmu(str(fmu), step_size=0.015, output_interval=0.015, stop_time=0.1)
    said = capsys.readouterr().out
    assert "communication step 0.015 s is neither a whole multiple of the sample period 0.01 s nor divides it" in said

def test_a_study_with_components_without_a_c_core_exits_2_naming_them(tmp_path, capsys):
    from agrobot.orchestrator.cli import main

    out = tmp_path / "tractor_side.fmu"
    code = main(["export-fmu", str(shipped("tractor_side.toml")), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2
    line = err.strip().splitlines()[-1]
    assert "tractor_side.toml" in line and "gyro (type GyroSensor" in line and "steering_status" in line
    assert "Traceback" not in err
    assert not out.exists() and not list(tmp_path.iterdir())


def test_a_named_subsystem_in_fmi3_takes_its_inputs_as_the_study_takes_its_constants(tmp_path):
    """The tractor plant with its steering and GPS (export-fmu --components), FMI 3.0: its free
    inputs (wheel-angle command, speed) given by fmpy equal the study's subsystem run in Python
    with those inputs held at the same constants."""
    from fmpy import read_model_description, simulate_fmu
    from fmpy.validation import validate_fmu

    from agrobot.api import export_fmu
    from agrobot.fmu_export.loop_fmu import subsystem

    names = ["tractor", "steering", "gps"]
    study = Study.load(shipped("figure8.toml"), QUIET)
    made = export_fmu(study, out=tmp_path / "tractor.fmu", fmi_version=3, components=names)
    fmu = made.path
    assert validate_fmu(str(fmu)) == []
    md = read_model_description(str(fmu))
    assert md.fmiVersion == "3.0"
    assert sorted(v.name for v in md.modelVariables if v.causality == "input") == ["steering_steer_angle_cmd",
                                                                                  "tractor_speed"]
    given = {"steering_steer_angle_cmd": 0.1, "tractor_speed": 2.0}
    sub = subsystem(study, names).with_values({"steering.inputs.steer_angle_cmd": 0.1, "tractor.inputs.speed": 2.0})
    rec = Simulation(build_system(resolve(sub))).run()
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    assert outputs == [c.replace(".", "_", 1) for c in rec.columns]
    res = simulate_fmu(str(fmu), stop_time=STOP, step_size=H, output_interval=H, output=outputs, start_values=given)
    frame = {c: res[c.replace(".", "_", 1)] for c in rec.columns}
    worst = relative_difference(rec, frame)
    assert max(worst.values()) < 1e-9, {k: v for k, v in worst.items() if v >= 1e-9}
    from agrobot.components.models.yaw_dynamics import TractorParameters

    tractor = TractorParameters.of(build_system(resolve(sub)).nodes["tractor"].component.p)
    wheelbase = tractor.l_f + tractor.l_r
    yaw_rate = rec.data[:, 1 + rec.columns.index("tractor.yaw_rate")]
    # turning as commanded: near the kinematic v tan(delta) / L (a little less: the tyres slip)
    assert yaw_rate[-1] == pytest.approx(2.0 * np.tan(0.1) / wheelbase, rel=0.1)
