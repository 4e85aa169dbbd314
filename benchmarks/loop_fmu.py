"""A study's whole loop as one FMU (export-fmu) against the study: the export's time, the time of
one whole run in the Python engine, the compiled engine, fmpy and libcosim (the FMU stepped at the
study's base step), and the largest difference of every recorded signal over its scale:

- noise off and the potentiometer's quantisation off: the FMU in fmpy and in libcosim against
  the Python engine (a 1e-16 difference of arithmetic order that meets a quantisation threshold
  flips one level, tests/test_compiled_engine.py);
- as shipped (noise and quantisation on): the FMU against the compiled engine, whose C it is
  (the GPS noise of the C cores is their own xoshiro stream, not numpy's).

    python benchmarks/loop_fmu.py [--study figure8.toml] [--stop-time 160] [--fmi-version 2]
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from compiled_engine import NO_QUANTISATION, QUIET, base, timed, worst  # noqa: E402

from agrobot.fmu_export.foreign_engines import libcosim_fmu_run  # noqa: E402
from agrobot.api import export_fmu  # noqa: E402
from agrobot.orchestrator.compiled import CompiledSimulation  # noqa: E402
from agrobot.orchestrator.engine import Simulation  # noqa: E402


def fmpy_run(fmu: Path, columns: list[str], stop: float, step: float):
    """(every output of the FMU in fmpy as a recording's matrix, rows t_0 .. t_n; seconds)."""
    from fmpy import simulate_fmu

    began = time.perf_counter()
    res = simulate_fmu(str(fmu), stop_time=stop, step_size=step, output_interval=step, output=columns)
    elapsed = time.perf_counter() - began
    return SimpleNamespace(data=np.column_stack([res["time"]] + [res[c] for c in columns])), elapsed


def libcosim_run(fmu: Path, columns: list[str], stop: float, step: float):
    """(the FMU in libcosim as a recording's matrix, rows t_1 .. t_n; seconds)."""
    began = time.perf_counter()
    frame = libcosim_fmu_run(fmu, stop, step, name="loop")
    elapsed = time.perf_counter() - began
    return SimpleNamespace(data=frame[["t"] + [f"loop.{c}" for c in columns]].to_numpy()), elapsed


def tail(rec):
    """A recording from t_1 on (libcosim reads the outputs after each step)."""
    return SimpleNamespace(data=rec.data[1:])


def case(study, fmi_version: int, folder: Path, reference: str) -> list[tuple[str, str]]:
    s = study.study
    began = time.perf_counter()
    fmu = export_fmu(study, out=folder / f"{s.name}_{reference}.fmu", fmi_version=fmi_version, overwrite=True).path
    export = time.perf_counter() - began
    factory = Simulation if reference == "python" else CompiledSimulation
    rec, ref_time = timed(factory, study)
    fm, fm_time = fmpy_run(fmu, rec.columns, s.stop_time, s.base_step)
    rows = [("export-fmu (cmake and the C compiler)", f"{export:.1f} s"),
            (f"{reference} engine, one run", f"{ref_time:.2f} s"),
            ("fmpy, one run of the FMU", f"{fm_time:.2f} s"),
            (f"fmpy against {reference}: largest difference / scale", f"{worst(fm, rec):.1e}")]
    if fmi_version == 2:                        # libcosim loads FMI 2.0
        lc, lc_time = libcosim_run(fmu, rec.columns, s.stop_time, s.base_step)
        rows += [("libcosim, one run of the FMU", f"{lc_time:.2f} s"),
                 (f"libcosim against {reference}: largest difference / scale", f"{worst(lc, tail(rec)):.1e}")]
    return rows


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--study", default="figure8.toml")
    parser.add_argument("--stop-time", type=float, default=None, help="default: the study's")
    parser.add_argument("--fmi-version", type=int, default=2, choices=(2, 3))
    args = parser.parse_args()
    stop = [f"study.stop_time={args.stop_time}"] if args.stop_time is not None else []
    table = []
    with tempfile.TemporaryDirectory() as tmp:
        quiet = base(args.study, QUIET + NO_QUANTISATION + stop)
        table += [("noise and quantisation off", *row) for row in case(quiet, args.fmi_version, Path(tmp), "python")]
        shipped = base(args.study, stop)
        table += [("as shipped", *row) for row in case(shipped, args.fmi_version, Path(tmp), "compiled")]
    s = quiet.study
    print(f"{args.study}: {s.stop_time:g} s simulated, base step {s.base_step:g} s, FMI {args.fmi_version}.0")
    print("| case | measurement | value |\n|---|---|---|")
    for row in table:
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
