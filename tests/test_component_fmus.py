"""Every figure-8 component as a self-contained C FMU (fmu_export.component_fmus), equivalence-
tested against its Python component: a Python closed-loop run of the figure-8 records every
component's inputs and outputs; each FMU, driven by a standard master (set the recorded inputs of
t_k, read the outputs, doStep) with its own step, must give the recorded outputs. The GPS runs
without noise here (its generator differs from numpy's); its noise is checked statistically."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.engine import Simulation
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study

ROOT = Path(__file__).resolve().parents[1]
OVERRIDES = ["study.stop_time=30", "gps.position_noise_std=0", "gps.velocity_noise_std=0"]


@pytest.fixture(scope="module")
def recorded():
    study = Study.load(ROOT / "studies/figure8.toml", OVERRIDES)
    system = build_system(resolve(study))
    return system, Simulation(system).run().to_frame()


def drive(fmu: Path, inputs: dict[str, np.ndarray], h: float, n: int, parameters: dict[str, float] | None = None):
    """Standard master: set inputs of t_k, get outputs, doStep(t_k, h); rows are the outputs at t_k."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    s = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu)), modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName="x")
    s.instantiate()
    if parameters:
        s.setReal([vr[k] for k in parameters], list(parameters.values()))
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    rows = []
    names = list(inputs)
    for k in range(n):
        if names:
            s.setReal([vr[m] for m in names], [float(inputs[m][k]) for m in names])
        rows.append(s.getReal([vr[o] for o in outputs]))
        s.doStep(k * h, h)
    s.terminate()
    s.freeInstance()
    return dict(zip(outputs, np.asarray(rows).T))


@pytest.fixture(scope="module")
def component_fmus(recorded, tmp_path_factory):
    from agrobot.fmu_export.component_fmus import export_component

    system, _ = recorded
    where = tmp_path_factory.mktemp("components")
    fmus = {name: where / f"{name}.fmu" for name in system.nodes}
    for name, path in fmus.items():
        path.write_bytes(export_component(system, name))
    return fmus


TOLERANCE = {"tractor": 1e-8, "ekf": 1e-8}          # m, rad: exact discretisation, expm by another method


@pytest.mark.parametrize("name", ["reference", "tractor", "steering", "drivetrain", "gps", "speed_filter", "ekf",
                                  "tracker", "mpc", "speed_controller", "command_link"])
def test_component_fmu_reproduces_its_python_component(recorded, component_fmus, name):
    from agrobot.fmu_export.component_fmus import fmu_input_name

    system, frame = recorded
    node = system.nodes[name]
    rows = frame.iloc[::node.ratio].reset_index(drop=True)
    comp = node.component
    inputs = {fmu_input_name(comp, inp): rows[f"{src.name}.{out}"].to_numpy() for inp, src, out in node.sources}
    got = drive(component_fmus[name], inputs, node.step, len(rows))
    for out in comp.declared("output"):
        expected = rows[f"{name}.{out}"].to_numpy()
        np.testing.assert_allclose(got[out], expected, rtol=1e-9, atol=TOLERANCE.get(name, 1e-9), err_msg=f"{name}.{out}")


def test_gps_fmu_noise_has_the_configured_spread_and_the_seed_repeats_it(recorded, component_fmus):
    system, _ = recorded
    n = 4000
    truth = {"x_true": np.linspace(0, 10, n), "y_true": np.zeros(n), "vel_east_true": np.ones(n),
             "vel_north_true": np.zeros(n)}
    noisy = {"position_noise_std": 0.02, "velocity_noise_std": 0.05, "seed": 7.0}
    a = drive(component_fmus["gps"], truth, 0.05, n, noisy)
    b = drive(component_fmus["gps"], truth, 0.05, n, noisy)
    other = drive(component_fmus["gps"], truth, 0.05, n, {**noisy, "seed": 8.0})
    e = a["x"] - truth["x_true"]
    assert np.std(e) == pytest.approx(0.02, rel=0.05) and abs(np.mean(e)) < 0.002
    assert np.std(a["vel_east"] - 1.0) == pytest.approx(0.05, rel=0.05)
    assert abs(np.corrcoef(e[1:], e[:-1])[0, 1]) < 0.05                # white
    np.testing.assert_array_equal(a["x"], b["x"])
    assert not np.array_equal(a["x"], other["x"])


def test_a_component_without_an_fmu_form_is_named(tmp_path):
    from agrobot.fmu_export.component_fmus import ComponentExportError, component_model

    system = build_system(resolve(Study.load(ROOT / "studies/figure8.toml", ["tractor.tyre_friction=0.8"])))
    with pytest.raises(ComponentExportError, match="figure8.toml: components.tractor: tyre_friction = 0.8 has no C form"):
        component_model(system, "tractor")
