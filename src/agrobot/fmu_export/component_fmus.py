"""One FMU per study component, from the same equations as the Python components: a C model core
per component type (c/components/<core>.c, the core its class names in ``C_CORE``; core_of) behind the
shared sampled-model semantics (c/sampled_instance.c), FMI 2.0 or 3.0.

The FMU keeps the component's name and port names; its numeric parameters are tunable FMU
parameters with the study's values as starts; parameters that fix the code's shape (the yaw
model, a delay length, the MPC design) are compiled in. The sample period is the component's
step in the study: continuous components (plant, actuators) are exact or substepped over it as
their Python counterparts are, so a plant FMU stepped at its period reproduces the Python run.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from agrobot.orchestrator.build import System
from agrobot.orchestrator.component import Component
from agrobot.orchestrator.errors import InputError

from .sampled_fmu import C_DIR, SampledModel, build_fmu, c_array, c_strings, token_of


class ComponentExportError(InputError):
    """A study component that has no FMU form (the message names it and why)."""


@dataclass(frozen=True)
class CoreSpec:
    """How a component type becomes a model core."""

    source: str                                                  # c/components/<source>
    compiled: Callable[[Component, float], str] = lambda comp, period: ""   # C #defines of fixed values
    compiled_parameters: tuple[str, ...] = ()                    # parameters consumed by ``compiled``
    values: Callable[[Component], dict[str, float]] | None = None  # parameter values overriding comp.p
    extra_parameters: tuple[tuple[str, float, str, str], ...] = ()  # FMU-only parameters
    dependencies: Callable[[Component], dict[str, list[str]]] | None = None   # default: the declared feedthrough
    extra_sources: tuple[str, ...] = ()
    extra_values: Callable[[Component, str], dict[str, float]] | None = None
    # the compiled loop (fmu_export.loop_cores): C #defines that replace ``compiled``'s, reading the
    # values that vary from run to run (a delay length) as run-time parameters, and those values
    runtime: Callable[[Component, float], tuple[str, dict[str, float]]] | None = None


def _numeric(value) -> bool:
    return isinstance(value, (bool, int, float, np.number))


def _substeps(comp: Component, period: float) -> str:
    return f"#define SUBSTEPS {max(1, int(round(period / float(comp.p['internal_step']))))}\n"


def _plant_compiled(comp: Component, period: float) -> str:
    from agrobot.components.models.yaw_dynamics import PHYSICAL_MODELS, controllable_canonical

    model = comp.p["model"]
    if comp.p["terrain_file"]:
        raise ComponentExportError(f"components.{comp.name}: terrain_file = {comp.p['terrain_file']!r} has no FMU "
                                   f"form (the exported plant's ground is the plane of slope_angle)")
    if float(comp.p["tyre_friction"]) > 0:
        raise ComponentExportError(f"components.{comp.name}: tyre_friction = {comp.p['tyre_friction']!r} has no FMU "
                                   f"form (the exported plant's tyres are linear)")
    if model == "transfer_function":          # yaw rate from num/den in controllable canonical form
        A, B, C = controllable_canonical(comp.p["tf_num"], comp.p["tf_den"])
        n = A.shape[0]
        return (f"#define YAW_MODEL 3\n#define TF_ORDER {n}\nstatic const double TF_A[{n * n}] = {{{c_array(A)}}};\n"
                f"static const double TF_B[{n}] = {{{c_array(B)}}};\nstatic const double TF_C[{n}] = {{{c_array(C)}}};\n")
    if model not in PHYSICAL_MODELS:
        raise ComponentExportError(f"components.{comp.name}: model = {model!r} has no FMU form "
                                   f"(the exported plant covers {', '.join(PHYSICAL_MODELS)} and transfer_function)")
    return f"#define YAW_MODEL {PHYSICAL_MODELS.index(model)}\n"


def _plant_values(comp: Component) -> dict[str, float]:
    from agrobot.components.models.yaw_dynamics import TractorParameters

    params = TractorParameters.of(comp.p)           # the named set resolved, cornering scales applied
    return {k: getattr(params, k) for k in ("m", "I", "l_f", "l_r", "C_f", "C_r", "sigma_f", "sigma_r")}


def _steering_compiled(comp: Component, period: float) -> str:
    return _substeps(comp, period) + f"#define DELAY_STEPS {int(round(float(comp.p['command_delay']) / period))}\n"


def capacity(n: int) -> int:
    """Room of a buffer whose length is a run-time value: 32, or the next power of two (a few
    shapes cover every length a sweep draws)."""
    return 32 if n <= 32 else 1 << (n - 1).bit_length()


def _steering_runtime(comp: Component, period: float) -> tuple[str, dict[str, float]]:
    steps = int(round(float(comp.p["command_delay"]) / period))
    return (_substeps(comp, period) + f"#define DELAY_CAPACITY {capacity(steps)}\n#define DELAY_STEPS ((int)p[P__delay_steps])\n",
            {"_delay_steps": float(steps)})


GPS_QUALITY_PARAMETERS = ("outages", "quality_log", "quality_log_start", "rtk_float_error_std", "dgps_error_std",
                          "single_error_std", "degraded_error_time_constant")


def _gps_compiled(comp: Component, period: float) -> str:
    for key in ("outages", "quality_log"):
        if comp.p[key]:
            raise ComponentExportError(f"components.{comp.name}: {key} = {comp.p[key]!r} has no FMU form (the "
                                       f"exported receiver has an RTK fix or random dropouts)")
    return f"#define LAG {int(round(float(comp.p['latency']) / period))}\n#define LATENCY {float(comp.p['latency'])!r}\n"


def _gps_runtime(comp: Component, period: float) -> tuple[str, dict[str, float]]:
    _gps_compiled(comp, period)                      # refuses what has no C form
    lag = int(round(float(comp.p["latency"]) / period))
    return (f"#define LAG_CAPACITY {capacity(lag)}\n#define LAG ((int)p[P__lag])\n#define LATENCY (p[P__latency])\n",
            {"_lag": float(lag), "_latency": float(comp.p["latency"])})


def _delay_runtime(comp: Component, period: float) -> tuple[str, dict[str, float]]:
    samples = int(comp.p["samples"])
    return (f"#define DELAY_CAPACITY {capacity(samples)}\n#define DELAY_SAMPLES ((int)p[P__samples])\n",
            {"_samples": float(samples)})


def _mpc_compiled(comp: Component, period: float) -> str:
    p = comp.p
    try:
        return _mpc_design(tuple(map(float, p["num"])), tuple(map(float, p["den"])), float(period),
                           int(p["prediction_horizon"]), int(p["control_horizon"]), float(p["Q"]), float(p["R"]),
                           float(p["steer_limit"]), float(p["steer_rate_limit"]), p["model_input"] == "measured")
    except ComponentExportError as exc:
        raise ComponentExportError(f"components.{comp.name}: {exc}") from None


@functools.lru_cache(maxsize=32)
def _mpc_design(num, den, period, horizon, control_horizon, Q, R, steer_limit, steer_rate_limit, measured) -> str:
    """The MPC's compiled design (a sweep's draws share it: designed once per process)."""
    from agrobot.components.models.condensed_mpc import CondensedTrackingMPC

    m = CondensedTrackingMPC(list(num), list(den), period, horizon, control_horizon, Q, R, steer_limit,
                             steer_rate_limit * period)
    if m.Nc > 10 or m.A.shape[0] > 8:
        raise ComponentExportError(f"the exported QP solver handles a control horizon up to 10 (got {m.Nc}) and a "
                                   f"model order up to 8")
    return (f"#define NX {m.A.shape[0]}\n#define NC {m.Nc}\n#define MEASURED_INPUT {int(measured)}\n"
            f"static const double MPC_H[NC * NC] = {{{c_array(m.H)}}};\n"
            f"static const double MPC_G[NC * (NX + 2)] = {{{c_array(m.G)}}};\n"
            f"static const double MPC_S[NC * NC] = {{{c_array(m.S)}}};\n"
            f"static const double MPC_ADVANCE[2 * NX * (NX + 2)] = {{{c_array(m._advance)}}};\n"
            f"static const double MPC_B[NX] = {{{c_array(m.B)}}};\n")


def _mpc_dependencies(comp: Component) -> dict[str, list[str]]:
    reads = ["yaw_rate_ref", "yaw_rate"] + (["steer_angle"] if comp.p["model_input"] == "measured" else [])
    return {"steer_angle_cmd": reads, "qp_status": reads}


def _gps_seed(comp: Component, name: str) -> dict[str, float]:
    return {"seed": float(int(comp.rng.integers(0, 2**52)))}


# C core name (a component class's ``C_CORE``) -> how it becomes a model core
CORES: dict[str, CoreSpec] = {
    "figure8_reference": CoreSpec("figure8_reference.c"),
    "tractor_yaw_plant": CoreSpec("tractor_yaw_plant.c", _plant_compiled,
                                ("model", "parameter_set", "tf_num", "tf_den", "cornering_scale_front",
                                 "cornering_scale_rear", "terrain_file"), _plant_values),
    "steering_hydraulics": CoreSpec("steering_hydraulics.c", _steering_compiled, ("internal_step", "command_delay"),
                                    runtime=_steering_runtime),
    "speed_drivetrain": CoreSpec("speed_drivetrain.c", _substeps, ("internal_step",)),
    "gps_sensor": CoreSpec("gps_sensor.c", _gps_compiled, ("latency",) + GPS_QUALITY_PARAMETERS,
                           extra_parameters=(("seed", 0.0, "1", "seed of the noise generator (xoshiro256**)"),),
                           extra_values=_gps_seed, runtime=_gps_runtime),
    "speed_kf": CoreSpec("speed_kf.c"),
    "pose_ekf": CoreSpec("pose_ekf.c"),
    "computation_delay": CoreSpec("computation_delay.c",
                                  lambda comp, period: f"#define DELAY_SAMPLES {int(comp.p['samples'])}\n", ("samples",),
                                  runtime=_delay_runtime),
    "kinematic_tracker": CoreSpec("kinematic_tracker.c", extra_sources=("guidance_laws.c",)),
    "speed_pid": CoreSpec("speed_pid.c", extra_sources=("guidance_laws.c",)),
    "yaw_rate_mpc": CoreSpec("yaw_rate_mpc.c", _mpc_compiled,
                           ("num", "den", "prediction_horizon", "control_horizon", "Q", "R", "model_input",
                            "qp_solver", "qp_tolerance"),
                           dependencies=_mpc_dependencies,
                           extra_sources=("guidance_laws.c", "qp_active_set.c", "qp_active_set.h")),
}


def fmu_input_name(comp: Component, name: str) -> str:
    """The FMU variable of input ``name``: the same name, or ``<name>_in`` where an output has that
    name too (FMI names are unique; the speed filter reads and writes ``vel_east``)."""
    return f"{name}_in" if name in comp.declared("output") else name


def core_of(comp: Component) -> tuple[str, CoreSpec] | None:
    """(C core name, its spec) of a component: the ``C_CORE`` its own class declares (a subclass
    with other equations declares its own), None when it has no C form."""
    name = vars(type(comp)).get("C_CORE")
    return (name, CORES[name]) if name in CORES else None


def exportable(comp: Component) -> bool:
    return core_of(comp) is not None


def core_spec(system: System, name: str) -> CoreSpec:
    """The C model core of the study component ``name`` (the ``C_CORE`` its class declares, core_of); a
    ComponentExportError names the component when it has none."""
    comp = system.nodes[name].component
    core = core_of(comp)
    if core is None:
        raise ComponentExportError(f"{system.study.path}: components.{name}: type {type(comp).__name__} has no FMU "
                                   f"form (its class declares no C_CORE of {', '.join(sorted(CORES))})")
    return core[1]


def core_parameters(system: System, name: str, spec: CoreSpec) -> list[tuple[str, float, str, str]]:
    """(name, value, unit, description) of the core's parameters: the component's numeric
    parameters not compiled in, then the core's own (a seed)."""
    comp = system.nodes[name].component
    values = {**comp.p, **(spec.values(comp) if spec.values else {})}
    parameters = []
    for v in comp.variables:
        if v.causality != "parameter" or v.name in spec.compiled_parameters:
            continue
        value = values[v.name]
        if not _numeric(value):
            raise ComponentExportError(f"{system.study.path}: components.{name}.parameters.{v.name} = {value!r}: "
                                       f"not a number; the FMU form takes numeric parameters only")
        parameters.append((v.name, float(value), v.unit or "1", v.description))
    extra = dict(spec.extra_values(comp, name)) if spec.extra_values else {}
    return parameters + [(n, extra.get(n, start), unit, desc) for n, start, unit, desc in spec.extra_parameters]


def component_model(system: System, name: str) -> SampledModel:
    """The sampled model of the study component ``name`` (its parameters as resolved in the study)."""
    node = system.nodes[name]
    comp, period = node.component, float(node.step)
    spec = core_spec(system, name)
    parameters = core_parameters(system, name, spec)
    outputs = [(v.name, v.unit or "1", v.description) for v in comp.variables if v.causality == "output"]
    inputs = [(fmu_input_name(comp, v.name), v.unit or "1", v.description)
              for v in comp.variables if v.causality == "input"]
    if spec.dependencies is not None:
        deps = spec.dependencies(comp)
    elif comp.sampled:
        deps = {o: list(comp.feedthrough.get(o, ())) for o, _, _ in outputs}
    else:
        deps = {}
    deps = {o: [fmu_input_name(comp, i) for i in deps.get(o, [])] for o, _, _ in outputs}
    try:
        compiled = spec.compiled(comp, period)
    except ComponentExportError as exc:
        raise ComponentExportError(f"{system.study.path}: {exc}") from None
    prologue = "\n".join([
        f"/* {name}: {type(comp).__name__} of {Path(str(system.study.path)).name}, sampled every {period!r} s "
        f"(generated by fmu_export.component_fmus) */",
        "#include <math.h>", "#include <stdlib.h>", "#include <string.h>",
        f"#define MODEL_NPAR {len(parameters)}", f"#define MODEL_NIN {len(inputs)}", f"#define MODEL_NOUT {len(outputs)}",
        f"#define MODEL_PERIOD {period!r}",
        f"static const double MODEL_PAR_START[MODEL_NPAR + 1] = {{{c_array([p[1] for p in parameters]) or '0.0'}}};",
        f"static const char *const MODEL_PAR_NAMES[MODEL_NPAR + 1] = {{{c_strings(p[0] for p in parameters)}}};",
        f"static const char *const MODEL_IN_NAMES[MODEL_NIN + 1] = {{{c_strings(i[0] for i in inputs)}}};",
        f"static const char *const MODEL_OUT_NAMES[MODEL_NOUT + 1] = {{{c_strings(o[0] for o in outputs)}}};",
        *[f"#define P_{p[0]} {i}" for i, p in enumerate(parameters)],
        *[f"#define IN_{v.name} {i}" for i, v in enumerate(x for x in comp.variables if x.causality == "input")],
        *[f"#define OUT_{x[0]} {i}" for i, x in enumerate(outputs)],
        compiled,
        f'#include "{spec.source}"', ""])
    token = token_of(prologue + (C_DIR / "components" / spec.source).read_text())
    source = prologue.replace("#define MODEL_PERIOD", f'#define MODEL_TOKEN "{token}"\n#define MODEL_PERIOD')
    description = (f"{name} ({type(comp).__name__}) of {Path(str(system.study.path)).name}: {type(comp).__doc__ or ''}"
                   .strip().split("\n")[0] + f"; sampled every {period!r} s")
    return SampledModel(name, token, description, period, parameters, inputs, outputs, deps, source,
                        [f"components/{spec.source}", *spec.extra_sources])



def export_component(system: System, name: str, out: Path, fmi_version: int = 2) -> Path:
    return build_fmu(component_model(system, name), out, fmi_version)


def non_exportable(system: System) -> list[str]:
    return [n for n, node in system.nodes.items() if not exportable(node.component)]
