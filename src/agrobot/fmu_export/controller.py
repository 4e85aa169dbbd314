"""Export a study's guidance controller (kinematic tracker + yaw-rate MPC + speed PID cascade) as a
self-contained FMI 2.0 or 3.0 co-simulation FMU: C sources generated from the study's design, a
binary built for this platform with fmpy.build (CMake), the sources shipped inside for other platforms.

One C core for both versions: the generated model (``guidance_core.c``: y_k = g(x_k, u_k),
x_k+1 = f(x_k, u_k) at the MPC's sample instants), the shared co-simulation semantics
(``sampled_instance.c``: get after set recomputes, the period handled inside for any communication
step dividing it, call sequence and finite inputs checked) and a thin wrapper per FMI version.

Ports are the three components' ports prefixed by their role (``tracker_x_ref``,
``mpc_yaw_rate``, ``speed_controller_speed`` ...); connections between the three stay inside.
Tunable FMU parameters: the tracker gains, the MPC's angle and rate limits, every speed-PID gain.
Fixed by the design (regenerate to change): the MPC model, sample time, horizons and weights.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from agrobot.components.kinematic_tracker import KinematicTracker
from agrobot.components.models.c_sources import GUIDANCE_LAWS, QP_SOLVER
from agrobot.components.models.condensed_mpc import CondensedTrackingMPC
from agrobot.components.speed_pid import SpeedPID
from agrobot.components.yaw_rate_mpc import YawRateMPC
from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.compiled.cores import c_array
from agrobot.orchestrator.engine import Simulation
from agrobot.orchestrator.errors import InputError
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study

from .packaging import PackagingError
from .sampled_fmu import SampledModel, build_fmu, c_strings, token_of

MODEL_IDENTIFIER = "guidance_controller"
C_DIR = Path(__file__).with_name("c")
FMI_VERSIONS = (2, 3)
# port prefix -> (declared role, the class the C code re-implements)
ROLES = {"tracker": ("tracker", KinematicTracker), "mpc": ("yaw_rate_controller", YawRateMPC),
         "speed_controller": ("speed_controller", SpeedPID)}
TUNABLE = {"tracker": ("k_s", "k_c", "l_r", "lookahead"), "mpc": ("steer_limit", "steer_rate_limit"),
           "speed_controller": ("kp", "ki", "kd", "integral_limit", "feedforward", "inner_kp", "inner_ki",
                                "inner_kd", "neutral_voltage", "voltage_min", "voltage_max")}
VR_IN0, VR_OUT0 = 1000, 2000        # as sampled_instance.c numbers inputs and outputs


class ExportError(InputError):
    """The study's controller cannot be exported (message names the study and the reason)."""


@dataclass
class ControllerDesign:
    """Everything the C code and the model description are generated from."""

    study_path: str
    names: dict[str, str]                       # role -> component name in the study
    sample_time: float
    mpc: CondensedTrackingMPC
    measured_input: bool
    parameters: list[tuple[str, float, str, str]]   # (port, start, unit, description)
    inputs: list[tuple[str, str, str]]              # (port, unit, description)
    outputs: list[tuple[str, str, str]]
    dependencies: dict[str, list[str]]              # output port -> input ports it depends on


def controller_design(study: Study) -> ControllerDesign:
    where = str(study.path)
    model = resolve(study)
    system = build_system(model)
    names: dict[str, str] = {}
    for prefix, (role, cls) in ROLES.items():
        found = model.find(role=role, type=cls)
        if len(found) != 1:
            raise ExportError(f"{where}: the controller export needs exactly one {cls.__name__} "
                              f"component, found {len(found)}" + (f" ({', '.join(found)})" if found else ""))
        names[prefix] = found[0]
    steps = {system.nodes[n].step for n in names.values()}
    if len(steps) != 1:
        raise ExportError(f"{where}: tracker, MPC and speed controller must share one step, got "
                          + ", ".join(f"{n}: {system.nodes[n].step} s" for n in names.values()))
    dt = steps.pop()
    comps = {role: system.nodes[n].component for role, n in names.items()}
    mp = comps["mpc"].p
    mpc = CondensedTrackingMPC(mp["num"], mp["den"], dt, int(mp["prediction_horizon"]),
                               int(mp["control_horizon"]), float(mp["Q"]), float(mp["R"]),
                               float(mp["steer_limit"]), float(mp["steer_rate_limit"]) * dt)
    if mpc.Nc > 10 or mpc.A.shape[0] > 8:
        raise ExportError(f"{where}: the exported QP solver handles a control horizon up to 10 "
                          f"(got {mpc.Nc}) and a model order up to 8")
    params, ins, outs = [], [], []
    for role, comp in comps.items():
        declared = {v.name: v for v in comp.variables}
        for key in TUNABLE[role]:
            v = declared[key]
            params.append((f"{role}_{key}", float(comp.p[key]), v.unit, v.description))
        ins += [(f"{role}_{v.name}", v.unit, v.description) for v in comp.variables if v.causality == "input"]
        outs += [(f"{role}_{v.name}", v.unit, v.description) for v in comp.variables if v.causality == "output"]
    internal = ("mpc_yaw_rate_ref", "speed_controller_speed_desired")     # driven by the tracker
    ins = [i for i in ins if i[0] not in internal]
    deps = controller_dependencies(mp["model_input"] == "measured")
    return ControllerDesign(where, names, dt, mpc, mp["model_input"] == "measured", params, ins, outs, deps)


def controller_dependencies(measured_input: bool) -> dict[str, list[str]]:
    """Output port -> the input ports its value at a sample instant is computed from, as the C
    core's equations read them (guidance_core.c: model_sample)."""
    pose = ["tracker_x_ref", "tracker_y_ref", "tracker_x", "tracker_y", "tracker_xdot_ref", "tracker_ydot_ref",
            "tracker_heading"]
    speed_desired = pose
    yaw_rate_desired = pose + ["tracker_yaw_rate_ref", "tracker_lateral_velocity"]
    steer = yaw_rate_desired + ["mpc_yaw_rate"] + (["mpc_steer_angle"] if measured_input else [])
    pedal = speed_desired + ["speed_controller_speed"]
    return {"tracker_speed_desired": speed_desired, "tracker_yaw_rate_desired": yaw_rate_desired,
            "tracker_error_x": ["tracker_x_ref", "tracker_x"], "tracker_error_y": ["tracker_y_ref", "tracker_y"],
            "mpc_steer_angle_cmd": steer, "mpc_qp_status": steer,
            "speed_controller_pedal_position_cmd": pedal,
            "speed_controller_pedal_valve_voltage": pedal + ["speed_controller_pedal_position"]}


def generate_c(design: ControllerDesign) -> tuple[str, str]:
    """(the model core's C source, GUID / instantiation token)."""
    template = (C_DIR / "guidance_core.c").read_text()
    m = design.mpc
    par_defines = "\n".join(f"#define P_{name} {i}" for i, (name, *_) in enumerate(design.parameters))
    io_defines = "\n".join([f"#define IN_{name} {i}" for i, (name, *_) in enumerate(design.inputs)]
                           + [f"#define OUT_{name} {i}" for i, (name, *_) in enumerate(design.outputs)])
    values = {
        "STUDY": Path(design.study_path).name, "NX": m.A.shape[0], "NC": m.Nc,
        "NPAR": len(design.parameters), "NIN": len(design.inputs), "NOUT": len(design.outputs),
        "SAMPLE_TIME": repr(float(design.sample_time)),
        "PAR_NAMES": c_strings(p[0] for p in design.parameters), "IN_NAMES": c_strings(i[0] for i in design.inputs),
        "OUT_NAMES": c_strings(o[0] for o in design.outputs),
        "MEASURED_INPUT": int(design.measured_input), "MPC_H": c_array(m.H), "MPC_G": c_array(m.G),
        "MPC_S": c_array(m.S), "MPC_ADVANCE": c_array(m._advance), "MPC_B": c_array(m.B),
        "PAR_START": c_array([p[1] for p in design.parameters]),
        "PAR_DEFINES": par_defines, "IO_DEFINES": io_defines,
    }
    source = template
    for key, value in values.items():
        source = source.replace(f"@@{key}@@", str(value))
    guid = token_of(source.replace("@@GUID@@", ""))
    source = source.replace("@@GUID@@", guid)
    if "@@" in source:
        raise ExportError("internal: unreplaced placeholder in the C template")
    return source, guid


def sampled_model(design: ControllerDesign) -> SampledModel:
    """The controller as a sampled model (the generated C core and its ports)."""
    m = design.mpc
    source, guid = generate_c(design)
    description = (f"Guidance controller of {Path(design.study_path).name}: kinematic tracker, yaw-rate MPC "
                   f"(model A = {[float(a) for a in np.round(m.A.ravel(), 12)]} discretised at "
                   f"{float(design.sample_time)} s, Np={int(m.Np)}, Nc={int(m.Nc)}, Q={float(m.Q)}, R={float(m.R)}), "
                   f"speed PID cascade; sampled every {float(design.sample_time)} s, outputs follow the inputs "
                   f"of each sample instant")
    return SampledModel(MODEL_IDENTIFIER, guid, description, design.sample_time, design.parameters, design.inputs,
                        design.outputs, design.dependencies, source, [*GUIDANCE_LAWS, *QP_SOLVER])


def export_controller(study: Study, fmi_version: int = 2) -> bytes:
    """The controller's FMU (FMI ``fmi_version``.0): sources, modelDescription.xml, the binary for
    this platform, as the archive's bytes (agrobot.api.export_controller writes it)."""
    if fmi_version not in FMI_VERSIONS:
        raise ExportError(f"--fmi-version {fmi_version}: expected one of {', '.join(map(str, FMI_VERSIONS))}")
    model = sampled_model(controller_design(study))
    try:
        return build_fmu(model, fmi_version)
    except PackagingError as exc:
        raise ExportError(str(exc)) from None


def _port_name(design: ControllerDesign):
    """FMU port of a controller component's port: the role prefix and the port name."""
    prefix_of = {n: r for r, n in design.names.items()}
    return lambda comp, port: f"{prefix_of[comp]}_{port}"


def controller_study(study: Study, design: ControllerDesign, fmu_path: str, name: str = "controller") -> Study:
    """The study with the three controller components folded into the FMU (same outside wiring)."""
    return resolve(study).collapse(design.names.values(), into=name, type=fmu_path, step=design.sample_time,
                                   port_name=_port_name(design))


def controller_feeds(study: Study, design: ControllerDesign) -> dict[str, str]:
    """FMU input -> the study signal ("component.output") that drives it, from the study's wiring."""
    inputs, _, _ = resolve(study).boundary(design.names.values(), _port_name(design))
    feeds = {port: f"{v['source'][0]}.{v['source'][1]}" for port, v in inputs.items() if v["source"]}
    return {name: feeds[name] for name, _, _ in design.inputs if name in feeds}


def run_with_exported_controller(study_path: Path, fmu: Path, overrides: list[str] | None = None):
    """Run a study as written and with the FMU in place of its three controllers:
    (python frame, FMU frame, study)."""
    study = Study.load(study_path, overrides or [])
    with_fmu = controller_study(study, controller_design(study), str(fmu))
    python_frame = Simulation(build_system(resolve(study))).run().to_frame()
    return python_frame, Simulation(build_system(resolve(with_fmu))).run().to_frame(), study

