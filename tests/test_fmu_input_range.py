"""An exported FMU refuses an input beyond its declared range with an FMI error status, and its state is
never poisoned: after the refused 1e308, finite inputs give finite outputs (the figure-8 tractor's
component FMU, driven by a standard master through fmpy)."""
from __future__ import annotations

import math
from pathlib import Path

import pytest

from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study

ROOT = Path(__file__).resolve().parents[1]


def test_an_input_beyond_the_declared_range_is_refused_and_the_state_kept(tmp_path):
    from fmpy import extract, read_model_description
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import FMU2Slave

    from agrobot.fmu_export.component_fmus import export_component

    system = build_system(resolve(Study.load(ROOT / "studies/figure8.toml", ["study.stop_time=5"])))
    fmu = tmp_path / "tractor.fmu"
    fmu.write_bytes(export_component(system, "tractor"))
    md = read_model_description(str(fmu))
    inputs = [v for v in md.modelVariables if v.causality == "input"]
    outputs = [v.valueReference for v in md.modelVariables if v.causality == "output"]
    assert inputs and all(float(v.max) == 1e9 and float(v.min) == -1e9 for v in inputs)
    s = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu)), modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName="x")
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    h, t = float(md.defaultExperiment.stepSize), 0.0
    first = inputs[0].valueReference
    with pytest.raises(FMICallException):
        s.setReal([first], [1e308])
    for _ in range(50):
        s.setReal([v.valueReference for v in inputs], [0.1] * len(inputs))
        s.doStep(t, h)
        t += h
    assert all(math.isfinite(y) for y in s.getReal(outputs))
    s.terminate()
    s.freeInstance()
