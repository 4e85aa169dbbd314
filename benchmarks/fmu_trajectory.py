"""How far the figure-8 trajectory moves when the exported controller FMU replaces the Python
controllers, with a continuous wheel-angle sensor and with the paper's 1-degree potentiometer,
beside how far it moves when one Python gain changes by 1e-12 (the loop's own sensitivity).

    python benchmarks/fmu_trajectory.py
"""
from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
STUDY = ROOT / "studies/figure8.toml"


def max_position_difference(a, b) -> float:
    return float(np.hypot(a["tractor.x_cg"] - b["tractor.x_cg"], a["tractor.y_cg"] - b["tractor.y_cg"]).max())


def main() -> None:
    from agrobot.api import export_controller
    from agrobot.fmu_export.controller import run_with_exported_controller
    from agrobot.orchestrator.build import build_system
    from agrobot.orchestrator.engine import Simulation
    from agrobot.orchestrator.resolver import resolve
    from agrobot.orchestrator.study import load_study

    with tempfile.TemporaryDirectory() as tmp:
        fmu = export_controller(load_study(STUDY), out=Path(tmp) / "guidance_controller.fmu").path
        smooth = run_with_exported_controller(STUDY, fmu, ["steering.potentiometer_resolution=0"])
        quantised = run_with_exported_controller(STUDY, fmu)
    nudged = Simulation(build_system(resolve(load_study(STUDY, ["tracker.k_s=0.6000000000006"])))).run().to_frame()
    print("max CG position difference over the 160 s figure-8 run [m]")
    print(f"  FMU vs Python, continuous wheel-angle sensor:        {max_position_difference(*smooth[:2]):.2e}")
    print(f"  FMU vs Python, 1-degree potentiometer (as the paper): {max_position_difference(*quantised[:2]):.2e}")
    print(f"  Python vs Python with k_s changed by 1e-12 relative:  {max_position_difference(quantised[0], nudged):.2e}")


if __name__ == "__main__":
    main()
