"""An exported SSP (or one FMU) run by other co-simulation engines (libcosim, fmpy's SSP master, cofmupy), each
returning a table with a time column ``t`` and ``component.output`` columns, and the distance
between two runs' CG tracks. Used by tests/test_foreign_engines.py and
benchmarks/foreign_engines.py.

Imported where used: libcosimpy (the test extra), cofmupy (optional: the README's test command installs it
apart, without its pinned dependencies).
"""
from __future__ import annotations

import contextlib
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pandas as pd
from fmpy.ssp.simulation import simulate_ssp

SSD = "{http://ssp-standard.org/SSP1/SystemStructureDescription}"


def cg_distance(ours: pd.DataFrame, other: pd.DataFrame, until: float) -> tuple[float, int]:
    """(largest distance between the two runs' tractor.x_cg/y_cg at common instants up to
    ``until``, number of common instants)."""
    a, b = ours[ours["t"] <= until + 1e-9], other[other["t"] <= until + 1e-9]
    a, b = a.set_index(a["t"].round(6)), b.set_index(b["t"].round(6))
    common = a.index.intersection(b.index)
    return float(np.hypot(a.loc[common, "tractor.x_cg"] - b.loc[common, "tractor.x_cg"],
                          a.loc[common, "tractor.y_cg"] - b.loc[common, "tractor.y_cg"]).max()), len(common)


def ssd_graph(unpacked: Path) -> tuple[dict[str, str], list[tuple[str, str, str, str]]]:
    """(component -> FMU path, connections (from, output, to, input)) of an unpacked SSP."""
    root = ET.parse(Path(unpacked) / "SystemStructure.ssd").getroot()
    components = {c.get("name"): str(Path(unpacked) / c.get("source")) for c in root.iter(f"{SSD}Component")}
    connections = [(c.get("startElement"), c.get("startConnector"), c.get("endElement"), c.get("endConnector"))
                   for c in root.iter(f"{SSD}Connection")]
    return components, connections


def libcosim_run(unpacked: Path, stop: float, step: float) -> pd.DataFrame:
    """libcosim on the unpacked SSP (its step from the API), every real output recorded after
    each step (row k: t = (k + 1) step)."""
    from libcosimpy.CosimExecution import CosimExecution

    _quiet_libcosim()
    return _libcosim_record(CosimExecution.from_ssp_file(str(unpacked), step_size=int(round(step * 1e9))), stop, step)


def libcosim_fmu_run(fmu: Path, stop: float, step: float, name: str = "loop") -> pd.DataFrame:
    """libcosim on one FMU (instance ``name``), recorded as ``libcosim_run`` records an SSP."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimSlave import CosimLocalSlave

    _quiet_libcosim()
    execution = CosimExecution.from_step_size(step_size=int(round(step * 1e9)))
    execution.add_local_slave(CosimLocalSlave(fmu_path=str(fmu), instance_name=name))
    return _libcosim_record(execution, stop, step)


def _quiet_libcosim() -> None:
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level

    log_output_level(CosimLogLevel.WARNING)


def _libcosim_record(execution, stop: float, step: float) -> pd.DataFrame:
    """Step ``execution`` to ``stop``, every real output of every instance read after each step
    (row k: t = (k + 1) step; columns ``instance.variable``)."""
    from libcosimpy.CosimObserver import CosimObserver

    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    watched = []
    for info in execution.slave_infos():
        variables = [v for v in execution.slave_variables(info.index) if v.causality == 2]     # outputs
        watched.append((info.name.decode(), info.index, [v.name.decode() for v in variables],
                        [v.reference for v in variables]))
    steps = int(round(stop / step))
    rows = np.empty((steps, 1 + sum(len(w[2]) for w in watched)))
    for k in range(steps):
        execution.step()
        row = [(k + 1) * step]
        for _, index, _, refs in watched:
            row += observer.last_real_values(index, refs)
        rows[k] = row
    return pd.DataFrame(rows, columns=["t"] + [f"{n}.{v}" for n, _, names, _ in watched for v in names])


def fmpy_ssp_run(ssp: Path, stop: float, step: float) -> pd.DataFrame:
    """fmpy's SSP master; it reads each output after doStep, so row k holds the state at t_k + h."""
    res = simulate_ssp(str(ssp), stop_time=stop, step_size=step)
    return pd.DataFrame({"t": res["time"] + step, "tractor.x_cg": res["tractor.x_cg"], "tractor.y_cg": res["tractor.y_cg"]})


@contextlib.contextmanager
def _cofmupy_numeric_default_experiment():
    """cofmupy 1.0 pins fmpy 0.3.20, whose model description gives the default experiment as
    numbers; fmpy 0.3.32 keeps the attributes' text. Convert them where cofmupy reads them, for
    the duration of a run (a compatibility shim, not a change of its master)."""
    import cofmupy.wrappers

    read = cofmupy.wrappers.read_model_description

    def numeric(*args, **kwargs):
        md = read(*args, **kwargs)
        if md.defaultExperiment is not None:
            for field in ("startTime", "stopTime", "stepSize", "tolerance"):
                value = getattr(md.defaultExperiment, field, None)
                if isinstance(value, str):
                    setattr(md.defaultExperiment, field, float(value))
        return md

    cofmupy.wrappers.read_model_description = numeric
    try:
        yield
    finally:
        cofmupy.wrappers.read_model_description = read


def cofmupy_run(unpacked: Path, stop: float, step: float) -> pd.DataFrame:
    """cofmupy's Jacobi master on the unpacked SSP's FMUs and connections; like fmpy's, its
    results pair the time of a step's start with the outputs after it."""
    from cofmupy import Coordinator

    components, connections = ssd_graph(unpacked)
    config = {"fmus": [{"id": n, "path": p} for n, p in components.items()],
              "connections": [{"source": {"id": a, "variable": o, "type": "fmu"},
                               "target": [{"id": b, "variable": i, "type": "fmu"}]} for a, o, b, i in connections],
              "edge_sep": " -> ", "cosim_method": "jacobi", "iterative": False, "root": ""}
    with _cofmupy_numeric_default_experiment():
        coordinator = Coordinator()
        coordinator.start(config)
        coordinator.run_simulation(step_size=step, end_time=stop)
        res = coordinator.get_results()
    return pd.DataFrame({"t": np.asarray(res["time"]) + step, "tractor.x_cg": np.asarray(res[("tractor", "x_cg")]),
                         "tractor.y_cg": np.asarray(res[("tractor", "y_cg")])})
