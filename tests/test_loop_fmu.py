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


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """(the FMU, the Python engine's recording) of the quiet figure-8; compiled once, in a cache
    of the module's own."""
    from agrobot.fmu_export.loop_fmu import export_loop

    old = os.environ.get("AGROBOT_CACHE")
    os.environ["AGROBOT_CACHE"] = str(tmp_path_factory.mktemp("compiled-cache"))
    try:
        study = Study.load(shipped("figure8.toml"), QUIET)
        fmu, note = export_loop(study, tmp_path_factory.mktemp("fmu") / "figure8.fmu", 2)
    finally:
        if old is None:
            os.environ.pop("AGROBOT_CACHE", None)
        else:
            os.environ["AGROBOT_CACHE"] = old
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
    assert not [v for v in md.modelVariables if v.causality in ("input", "parameter")]
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
