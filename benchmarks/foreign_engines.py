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

import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

H = 0.01

from agrobot.fmu_export.foreign_engines import cg_distance, cofmupy_run, fmpy_ssp_run, libcosim_run  # noqa: E402


def difference(ours: pd.DataFrame, other: pd.DataFrame, until: float = 20.0) -> float:
    return cg_distance(ours, other, until)[0]


def cofmupy_or_none(unpacked: Path) -> pd.DataFrame | None:
    import importlib.util

    return cofmupy_run(unpacked, 20.0, H) if importlib.util.find_spec("cofmupy") else None


def main() -> None:
    from agrobot.analysis.figure8 import metrics
    from agrobot.api import export_ssp
    from agrobot.orchestrator.build import build_system
    from agrobot.orchestrator.engine import Simulation
    from agrobot.orchestrator.resolver import resolve
    from agrobot.orchestrator.study import Study

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None, help="keep the SSP here (default: a temporary folder)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        where = args.out or Path(tmp)
        where.mkdir(parents=True, exist_ok=True)
        t0 = time.perf_counter()
        ssp = export_ssp(Study.load(ROOT / "studies/figure8.toml"), out=where / "figure8.ssp", overwrite=True).path
        export_s = time.perf_counter() - t0
        unpacked = where / "unpacked"
        with zipfile.ZipFile(ssp) as zf:
            zf.extractall(unpacked)
        py_study = Study.load(ROOT / "studies/figure8.toml")
        py = Simulation(build_system(resolve(py_study))).run().to_frame()
        study = Study.load(ssp)
        ours = Simulation(build_system(resolve(study))).run().to_frame()
        cosim = libcosim_run(unpacked, study.study.stop_time, H)
        rows = [("Python study", metrics(py, py_study), difference(ours, py)),
                ("this orchestrator, SSP", metrics(ours, study), 0.0),
                ("libcosim, SSP", metrics(cosim, study), difference(ours, cosim)),
                ("fmpy SSP master, 20 s", None, difference(ours, fmpy_ssp_run(ssp, 20.0, H)))]
        cof = cofmupy_or_none(unpacked)
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
