"""Export a study's guidance controller (kinematic tracker + yaw-rate MPC + speed PID cascade) as a
self-contained FMI 2.0 co-simulation FMU: C sources generated from the study's design, a binary
built for this platform with fmpy.build (CMake), the sources shipped inside for other platforms.

Ports are the three components' ports prefixed by their role (``tracker_x_ref``,
``mpc_yaw_rate``, ``speed_controller_speed`` ...); connections between the three stay inside.
Tunable FMU parameters: the tracker gains, the MPC's angle and rate limits, every speed-PID gain.
Fixed by the design (regenerate to change): the MPC model, sample time, horizons and weights.
"""
from __future__ import annotations

import hashlib
import shutil
import tempfile
import uuid
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from components.kinematic_tracker import KinematicTracker
from components.models.condensed_mpc import CondensedTrackingMPC
from components.speed_pid import SpeedPID
from components.yaw_rate_mpc import YawRateMPC
from orchestrator.build import build_system
from orchestrator.errors import InputError
from orchestrator.study import Study

from .packaging import PackagingError, check_fmu_target, package_fmu

MODEL_IDENTIFIER = "guidance_controller"
ANNOTATION_TOOL = "agrobot"          # <Tool name="agrobot"><Sampled/></Tool>: outputs hold on [t, t + dt)
C_DIR = Path(__file__).with_name("c")
# port prefix -> (declared role, the class the C code re-implements)
ROLES = {"tracker": ("tracker", KinematicTracker), "mpc": ("yaw_rate_controller", YawRateMPC),
         "speed_controller": ("speed_controller", SpeedPID)}
TUNABLE = {"tracker": ("k_s", "k_c", "l_r", "lookahead"), "mpc": ("steer_limit", "steer_rate_limit"),
           "speed_controller": ("kp", "ki", "kd", "integral_limit", "feedforward", "inner_kp", "inner_ki",
                                "inner_kd", "neutral_voltage", "voltage_min", "voltage_max")}
VR_IN0, VR_OUT0 = 100, 200


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
    system = build_system(study)
    names: dict[str, str] = {}
    for prefix, (role, cls) in ROLES.items():
        found = study.find(role=role, type=cls)
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
    tracker_in = [i[0] for i in ins if i[0].startswith("tracker_")]
    deps = {}
    for port, _, _ in outs:
        if port.startswith("tracker_"):
            deps[port] = tracker_in
        elif port.startswith("mpc_"):
            deps[port] = tracker_in + ["mpc_yaw_rate"]
        else:
            deps[port] = tracker_in + ["speed_controller_speed"] + (
                ["speed_controller_pedal_position"] if port.endswith("voltage") else [])
    return ControllerDesign(where, names, dt, mpc, mp["model_input"] == "measured", params, ins, outs, deps)


def _c_array(values) -> str:
    return ", ".join(repr(float(v)) for v in np.asarray(values, dtype=float).ravel())


def _guid(source: str) -> str:
    """A GUID that changes whenever the generated source does."""
    return "{" + str(uuid.UUID(hashlib.sha256(source.encode()).hexdigest()[:32])) + "}"


def generate_c(design: ControllerDesign) -> tuple[str, str]:
    """(C source, GUID)."""
    template = (C_DIR / "guidance_controller.c").read_text()
    m = design.mpc
    par_defines = "\n".join(f"#define P_{name} {i}" for i, (name, *_) in enumerate(design.parameters))
    io_defines = "\n".join([f"#define IN_{name} {i}" for i, (name, *_) in enumerate(design.inputs)]
                           + [f"#define OUT_{name} {i}" for i, (name, *_) in enumerate(design.outputs)])
    values = {
        "STUDY": Path(design.study_path).name, "NX": m.A.shape[0], "NC": m.Nc,
        "NPAR": len(design.parameters), "NIN": len(design.inputs), "NOUT": len(design.outputs),
        "VR_IN0": VR_IN0, "VR_OUT0": VR_OUT0, "SAMPLE_TIME": repr(design.sample_time),
        "MEASURED_INPUT": int(design.measured_input), "MPC_H": _c_array(m.H), "MPC_G": _c_array(m.G),
        "MPC_S": _c_array(m.S), "MPC_ADVANCE": _c_array(m._advance), "MPC_B": _c_array(m.B),
        "PAR_START": _c_array([p[1] for p in design.parameters]),
        "PAR_DEFINES": par_defines, "IO_DEFINES": io_defines,
    }
    source = template
    for key, value in values.items():
        source = source.replace(f"@@{key}@@", str(value))
    guid = _guid(source.replace("@@GUID@@", ""))
    source = source.replace("@@GUID@@", guid)
    if "@@" in source:
        raise ExportError("internal: unreplaced placeholder in the C template")
    return source, guid


def model_description(design: ControllerDesign, guid: str) -> str:
    m = design.mpc
    rows, index = [], {}
    units = sorted({u for _, _, u, _ in design.parameters} | {u for _, u, _ in design.inputs + design.outputs})

    def variable(name, vr, causality, variability, unit, description, start=None, initial=None):
        index[name] = len(rows) + 1
        attrs = f'name={quoteattr(name)} valueReference="{vr}" causality="{causality}" variability="{variability}"'
        if initial:
            attrs += f' initial="{initial}"'
        real = f'<Real unit={quoteattr(unit)}' + (f' start="{start!r}"' if start is not None else "") + "/>"
        rows.append(f"    <ScalarVariable {attrs} description={quoteattr(description)}>{real}</ScalarVariable>")

    for i, (name, start, unit, desc) in enumerate(design.parameters):
        variable(name, i, "parameter", "tunable", unit, desc, start, "exact")
    for i, (name, unit, desc) in enumerate(design.inputs):
        variable(name, VR_IN0 + i, "input", "discrete", unit, desc, 0.0)
    for i, (name, unit, desc) in enumerate(design.outputs):
        variable(name, VR_OUT0 + i, "output", "discrete", unit, desc, None, "calculated")
    outputs = "\n".join(f'      <Unknown index="{index[n]}" dependencies="{" ".join(str(index[d]) for d in design.dependencies[n])}"/>'
                        for n, _, _ in design.outputs)
    initial = "\n".join(f'      <Unknown index="{index[n]}" dependencies=""/>' for n, _, _ in design.outputs)
    description = (f"Guidance controller of {Path(design.study_path).name}: kinematic tracker, yaw-rate MPC "
                   f"(model {list(np.round(m.A.ravel(), 12))} discretised at {design.sample_time} s, "
                   f"Np={m.Np}, Nc={m.Nc}, Q={m.Q}, R={m.R}), speed PID cascade")
    unit_defs = "\n".join(f"    <Unit name={quoteattr(u)}/>" for u in units)
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="{MODEL_IDENTIFIER}" guid="{guid}"
  description={quoteattr(description)} generationTool="agrobot-guidance fmu_export"
  variableNamingConvention="flat" numberOfEventIndicators="0">
  <CoSimulation modelIdentifier="{MODEL_IDENTIFIER}" canHandleVariableCommunicationStepSize="false"
    canBeInstantiatedOnlyOncePerProcess="false" canNotUseMemoryManagementFunctions="true">
    <SourceFiles>
      <File name="guidance_controller.c"/>
      <File name="qp_active_set.c"/>
    </SourceFiles>
  </CoSimulation>
  <UnitDefinitions>
{unit_defs}
  </UnitDefinitions>
  <LogCategories>
    <Category name="logStatusError" description="errors"/>
  </LogCategories>
  <DefaultExperiment startTime="0.0" stepSize="{design.sample_time!r}"/>
  <VendorAnnotations>
    <Tool name="{ANNOTATION_TOOL}"><Sampled/></Tool>
  </VendorAnnotations>
  <ModelVariables>
{chr(10).join(rows)}
  </ModelVariables>
  <ModelStructure>
    <Outputs>
{outputs}
    </Outputs>
    <InitialUnknowns>
{initial}
    </InitialUnknowns>
  </ModelStructure>
</fmiModelDescription>
"""


def export_controller(study: Study, out: Path) -> Path:
    """Write ``out`` (.fmu): sources, modelDescription.xml and the binary for this platform."""
    if out.suffix != ".fmu":
        raise ExportError(f"--out {out}: expected a path ending in .fmu")
    try:
        check_fmu_target(out)
    except PackagingError as exc:
        raise ExportError(str(exc)) from None
    design = controller_design(study)
    source, guid = generate_c(design)
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        (root / "sources").mkdir()
        (root / "sources" / "guidance_controller.c").write_text(source)
        for name in ("qp_active_set.c", "qp_active_set.h"):
            shutil.copy(C_DIR / name, root / "sources" / name)
        (root / "modelDescription.xml").write_text(model_description(design, guid))
        try:
            return package_fmu(root, out)
        except PackagingError as exc:
            raise ExportError(str(exc)) from None


def _port_name(design: ControllerDesign):
    """FMU port of a controller component's port: the role prefix and the port name."""
    prefix_of = {n: r for r, n in design.names.items()}
    return lambda comp, port: f"{prefix_of[comp]}_{port}"


def controller_study(study: Study, design: ControllerDesign, fmu_path: str, name: str = "controller") -> Study:
    """The study with the three controller components folded into the FMU (same outside wiring)."""
    return study.collapse(design.names.values(), into=name, type=fmu_path, step=design.sample_time,
                          port_name=_port_name(design))


def controller_feeds(study: Study, design: ControllerDesign) -> dict[str, str]:
    """FMU input -> the study signal ("component.output") that drives it, from the study's wiring."""
    inputs, _, _ = study.boundary(design.names.values(), _port_name(design))
    feeds = {port: f"{v['source'][0]}.{v['source'][1]}" for port, v in inputs.items() if v["source"]}
    return {name: feeds[name] for name, _, _ in design.inputs if name in feeds}


def run_with_exported_controller(study_path: Path, fmu: Path, overrides: list[str] | None = None):
    """Run a study as written and with the FMU in place of its three controllers:
    (python frame, FMU frame, study)."""
    from orchestrator.engine import Simulation

    study = Study.load(study_path, overrides or [])
    with_fmu = controller_study(study, controller_design(study), str(fmu))
    python_frame = Simulation(build_system(study)).run().to_frame()
    return python_frame, Simulation(build_system(with_fmu)).run().to_frame(), study

