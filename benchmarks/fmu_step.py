"""One guidance-controller step (tracker + yaw-rate MPC + speed PID) on the inputs recorded in a
figure-8 run: the Python components, the exported FMU called through fmpy, and the FMU's C step
alone (a C harness calling fmi2SetReal/fmi2DoStep/fmi2GetReal). Median and p99.

    python benchmarks/fmu_step.py [--seconds 60]
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
def recorded_inputs(seconds: float):
    """(study, the 20 Hz samples of a figure-8 run, FMU input -> recorded column)."""
    from agrobot.fmu_export.controller import controller_design, controller_feeds
    from agrobot.orchestrator.build import build_system
    from agrobot.orchestrator.engine import Simulation
    from agrobot.orchestrator.resolver import resolve
    from agrobot.orchestrator.study import Study

    st = Study.load(ROOT / "studies/figure8.toml", [f"study.stop_time={seconds}"])
    frame = Simulation(build_system(resolve(st))).run().to_frame().iloc[::5]
    return st, frame, controller_feeds(st, controller_design(st))


def time_python(st, frame, feeds) -> np.ndarray:
    from agrobot.orchestrator.build import build_system
    from agrobot.orchestrator.resolver import resolve

    nodes = build_system(resolve(st)).nodes
    comps = [nodes[n].component for n in ("tracker", "mpc", "speed_controller")]
    for c in comps:
        c.initialize(0.0, 0.05)
    cols = {port: frame[col].to_numpy() for port, col in feeds.items()}
    times = np.empty(len(frame))
    tracker, mpc, speed = comps
    for k in range(len(frame)):
        t0 = time.perf_counter_ns()
        for port in ("x_ref", "y_ref", "xdot_ref", "ydot_ref", "x", "y", "heading"):
            tracker.u[port] = cols["tracker_" + port][k]
        tracker.step(k * 0.05, 0.05)
        mpc.u["yaw_rate_ref"], mpc.u["yaw_rate"] = tracker.y["yaw_rate_desired"], cols["mpc_yaw_rate"][k]
        mpc.u["steer_angle"] = cols["mpc_steer_angle"][k]
        mpc.step(k * 0.05, 0.05)
        speed.u["speed_desired"], speed.u["speed"] = tracker.y["speed_desired"], cols["speed_controller_speed"][k]
        speed.u["pedal_position"] = cols["speed_controller_pedal_position"][k]
        speed.step(k * 0.05, 0.05)
        times[k] = time.perf_counter_ns() - t0
    return times * 1e-9


def time_fmpy(fmu: Path, frame, feeds) -> np.ndarray:
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu))
    refs = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu)),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bench")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    vin = [refs[p] for p in feeds]
    vout = [v.valueReference for v in md.modelVariables if v.causality == "output"]
    data = frame[list(feeds.values())].to_numpy()
    times = np.empty(len(frame))
    for k in range(len(frame)):
        t0 = time.perf_counter_ns()
        slave.setReal(vin, list(data[k]))
        slave.doStep(k * 0.05, 0.05)
        slave.getReal(vout)
        times[k] = time.perf_counter_ns() - t0
    slave.terminate()
    slave.freeInstance()
    return times * 1e-9


def time_c(fmu: Path, frame, feeds, tmp: Path) -> np.ndarray:
    from fmpy import read_model_description

    md = read_model_description(str(fmu))
    ins = [v for v in md.modelVariables if v.causality == "input"]
    outs = [v for v in md.modelVariables if v.causality == "output"]
    if [v.name for v in ins] != list(feeds):
        raise RuntimeError("the FMU's inputs are not in the expected order")
    with zipfile.ZipFile(fmu) as zf:
        zf.extractall(tmp / "fmu")
    lib = tmp / "fmu/binaries/linux64/guidance_controller.so"
    harness = tmp / "harness"
    subprocess.run(["gcc", "-O2", "-o", str(harness), str(ROOT / "benchmarks/c/fmu_step_harness.c"), "-ldl"], check=True)
    data = np.ascontiguousarray(frame[list(feeds.values())].to_numpy(), dtype=float)
    (tmp / "inputs.bin").write_bytes(data.tobytes())
    res = subprocess.run([str(harness), str(lib), md.guid, str(tmp / "inputs.bin"), str(len(ins)),
                          str(ins[0].valueReference), str(len(outs)), str(outs[0].valueReference), "0.05"],
                         check=True, capture_output=True, text=True)
    return np.array([float(x) for x in res.stdout.split()]) * 1e-9


def measure(seconds: float = 60.0) -> dict:
    from agrobot.api import export_controller

    st, frame, feeds = recorded_inputs(seconds)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        fmu = export_controller(st, out=tmp / "guidance_controller.fmu").path
        rows = {"Python components (tracker + MPC + PID)": time_python(st, frame, feeds),
                "FMU through fmpy (set, doStep, get)": time_fmpy(fmu, frame, feeds),
                "FMU C step alone (C harness)": time_c(fmu, frame, feeds, tmp)}
    return {"steps": len(frame), "rows": rows}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seconds", type=float, default=60.0, help="simulated seconds of recorded inputs")
    args = parser.parse_args()
    r = measure(args.seconds)
    base = np.median(r["rows"]["FMU C step alone (C harness)"])
    print(f"one controller step, {r['steps']} recorded input samples")
    print(f"{'':<42}{'median [us]':>12}{'p99 [us]':>10}{'x C step':>10}")
    for name, t in r["rows"].items():
        print(f"{name:<42}{np.median(t) * 1e6:>12.2f}{np.percentile(t, 99) * 1e6:>10.2f}{np.median(t) / base:>10.1f}")


if __name__ == "__main__":
    sys.exit(main())
