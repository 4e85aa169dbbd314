"""The figure-8 as an SSP in this orchestrator and in foreign engines: tracking metrics over the
whole run (this orchestrator, libcosim) and the largest distance from this orchestrator's CG
trajectory over the first 20 s (libcosim, fmpy's SSP master, cofmupy). Prints a table.

    python benchmarks/foreign_engines.py [--out DIR]

cofmupy is optional (skipped when not installed); the test suite holds the bounds
(tests/test_foreign_engines.py)."""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

H = 0.01


def difference(ours: pd.DataFrame, other: pd.DataFrame, until: float = 20.0) -> float:
    a, b = ours[ours["t"] <= until + 1e-9], other[other["t"] <= until + 1e-9]
    a, b = a.set_index(a["t"].round(6)), b.set_index(b["t"].round(6))
    common = a.index.intersection(b.index)
    return float(np.hypot(a.loc[common, "tractor.x_cg"] - b.loc[common, "tractor.x_cg"],
                          a.loc[common, "tractor.y_cg"] - b.loc[common, "tractor.y_cg"]).max())


def libcosim_frame(unpacked: Path, stop: float) -> pd.DataFrame:
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.WARNING)
    execution = CosimExecution.from_ssp_file(str(unpacked), step_size=int(round(H * 1e9)))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    watched = []
    for info in execution.slave_infos():
        variables = [v for v in execution.slave_variables(info.index) if v.causality == 2]
        watched.append((info.name.decode(), info.index, [v.name.decode() for v in variables], [v.reference for v in variables]))
    rows = []
    for k in range(int(round(stop / H))):
        execution.step()
        row = [(k + 1) * H]
        for _, index, _, refs in watched:
            row += observer.last_real_values(index, refs)
        rows.append(row)
    return pd.DataFrame(rows, columns=["t"] + [f"{n}.{v}" for n, _, names, _ in watched for v in names])


def fmpy_frame(ssp: Path) -> pd.DataFrame:
    from fmpy.ssp.simulation import simulate_ssp

    res = simulate_ssp(str(ssp), stop_time=20.0, step_size=H)
    return pd.DataFrame({"t": res["time"] + H, "tractor.x_cg": res["tractor.x_cg"], "tractor.y_cg": res["tractor.y_cg"]})


def cofmupy_frame(unpacked: Path) -> pd.DataFrame | None:
    try:
        import cofmupy.wrappers
        from cofmupy import Coordinator
    except ImportError:
        return None
    import xml.etree.ElementTree as ET

    read = cofmupy.wrappers.read_model_description

    def numeric(*args, **kwargs):          # cofmupy expects fmpy 0.3.20's numbers (tests/test_foreign_engines.py)
        md = read(*args, **kwargs)
        for field in ("startTime", "stopTime", "stepSize", "tolerance"):
            value = getattr(md.defaultExperiment, field, None) if md.defaultExperiment is not None else None
            if isinstance(value, str):
                setattr(md.defaultExperiment, field, float(value))
        return md

    cofmupy.wrappers.read_model_description = numeric
    ns = "{http://ssp-standard.org/SSP1/SystemStructureDescription}"
    root = ET.parse(unpacked / "SystemStructure.ssd").getroot()
    config = {"fmus": [{"id": c.get("name"), "path": str(unpacked / c.get("source"))} for c in root.iter(f"{ns}Component")],
              "connections": [{"source": {"id": c.get("startElement"), "variable": c.get("startConnector"), "type": "fmu"},
                               "target": [{"id": c.get("endElement"), "variable": c.get("endConnector"), "type": "fmu"}]}
                              for c in root.iter(f"{ns}Connection")],
              "edge_sep": " -> ", "cosim_method": "jacobi", "iterative": False, "root": ""}
    coordinator = Coordinator()
    coordinator.start(config)
    coordinator.run_simulation(step_size=H, end_time=20.0)
    res = coordinator.get_results()
    return pd.DataFrame({"t": np.asarray(res["time"]) + H, "tractor.x_cg": np.asarray(res[("tractor", "x_cg")]),
                         "tractor.y_cg": np.asarray(res[("tractor", "y_cg")])})


def main() -> None:
    from analysis.figure8 import metrics
    from fmu_export.ssp_export import export_ssp
    from orchestrator.build import build_system
    from orchestrator.engine import Simulation
    from orchestrator.study import Study

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None, help="keep the SSP here (default: a temporary folder)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        where = args.out or Path(tmp)
        where.mkdir(parents=True, exist_ok=True)
        t0 = time.perf_counter()
        ssp = export_ssp(Study.load(ROOT / "studies/figure8.toml"), where / "figure8.ssp")
        export_s = time.perf_counter() - t0
        unpacked = where / "unpacked"
        with zipfile.ZipFile(ssp) as zf:
            zf.extractall(unpacked)
        py_study = Study.load(ROOT / "studies/figure8.toml")
        py = Simulation(build_system(py_study)).run().to_frame()
        study = Study.load(ssp)
        ours = Simulation(build_system(study)).run().to_frame()
        cosim = libcosim_frame(unpacked, study.study.stop_time)
        rows = [("Python study", metrics(py, py_study), difference(ours, py)),
                ("this orchestrator, SSP", metrics(ours, study), 0.0),
                ("libcosim, SSP", metrics(cosim, study), difference(ours, cosim)),
                ("fmpy SSP master, 20 s", None, difference(ours, fmpy_frame(ssp)))]
        cof = cofmupy_frame(unpacked)
        if cof is not None:
            rows.append(("cofmupy (Jacobi), 20 s", None, difference(ours, cof)))
    print(f"export-ssp of studies/figure8.toml: {export_s:.1f} s")
    print(f"{'run':28s} {'max straight':>13s} {'max curved':>11s} {'mean straight':>14s} {'vs our SSP run (0-20 s)':>24s}")
    for name, m, d in rows:
        cells = [f"{m[k]:.3f} m" for k in ("euclid_max_straight", "euclid_max_curved", "euclid_mean_straight")] \
            if m else ["-", "-", "-"]
        print(f"{name:28s} {cells[0]:>13s} {cells[1]:>11s} {cells[2]:>14s} {d:>22.3f} m")
    print("paper: max straight < 0.40 m, max curved < 0.60 m")


if __name__ == "__main__":
    main()
