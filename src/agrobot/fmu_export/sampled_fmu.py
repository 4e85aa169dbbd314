"""A sampled model's FMU, FMI 2.0 or 3.0, from one C core: the model description (ports with
units and BaseUnits, ModelStructure from the model's dependencies), the sources (the generated
model core, ``sampled_instance.c``, the wrapper of the version, the FMI headers) and the build.

The C model core defines ModelState, model_start, model_sample and the MODEL_* constants
(see c/sampled_instance.c); value references: parameters 0.., inputs 1000.., outputs 2000..
"""
from __future__ import annotations

import hashlib
import shutil
import tempfile
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from xml.sax.saxutils import quoteattr

from agrobot.orchestrator.units import base_unit


from .packaging import package_fmu

C_DIR = Path(__file__).with_name("c")
VR_TIME, VR_INPUT0, VR_OUTPUT0 = 999, 1000, 2000       # as c/sampled_instance.c numbers them
WRAPPERS = {2: "fmi2_cs.c", 3: "fmi3_cs.c"}


def c_strings(names) -> str:
    """Names as the body of a C string array initialiser ("" for none: C has no empty arrays)."""
    return ", ".join(f'"{n}"' for n in names) or '""'


def token_of(source: str) -> str:
    """The GUID / instantiation token of a generated source: it changes whenever the source does."""
    return "{" + str(uuid.UUID(hashlib.sha256(source.encode()).hexdigest()[:32])) + "}"


@dataclass
class SampledModel:
    """What an FMU is generated from (ports as (name, unit, description); parameters with a start)."""

    identifier: str
    token: str                                   # GUID / instantiation token, also compiled into the core
    description: str
    period: float                                # s: the sample period
    parameters: list[tuple[str, float, str, str]]
    inputs: list[tuple[str, str, str]]
    outputs: list[tuple[str, str, str]]
    dependencies: dict[str, list[str]]           # output -> inputs read at the same sample instant
    core_source: str                             # the generated model core (C)
    extra_sources: list = field(default_factory=list)   # C files the core includes (paths, or names in c/)
    units: dict[str, str] = field(default_factory=dict)      # further generated translation units (file: C text)
    input_starts: list[float] | None = None      # the inputs' start values (default 0; the core defines MODEL_IN_START)
    stop_time: float | None = None               # s: the default experiment's end, when the model has one
    parameter_variability: str = "tunable"       # or "fixed": set before the initialization ends (MODEL_PAR_FIXED)


def _initial_dependencies(model: SampledModel, output: str) -> list[str]:
    return [p[0] for p in model.parameters] + model.dependencies[output]


def _unit_definitions(units: list[str], indent: str) -> str:
    rows = []
    for unit in units:
        base = base_unit(unit)
        if base is None:
            rows.append(f"{indent}<Unit name={quoteattr(unit)}/>")
            continue
        attrs = " ".join(f'{k}="{v}"' for k, v in base.fmi_attributes().items())
        rows.append(f"{indent}<Unit name={quoteattr(unit)}><BaseUnit {attrs}/></Unit>")
    return "\n".join(rows)


def _units(model: SampledModel) -> list[str]:
    return sorted({u for _, _, u, _ in model.parameters} | {u for _, u, _ in model.inputs + model.outputs} | {"s"})


INPUT_BOUND = 1e9       # |input| at most, in SI: the declared range; sampled_instance.c refuses a value beyond it
INPUT_RANGE = f' min="{-INPUT_BOUND!r}" max="{INPUT_BOUND!r}"'


def _declare(model: SampledModel, variable) -> None:
    """Call ``variable(name, vr, causality, variability, unit, description, start, initial)`` for
    every parameter (tunable or fixed, exact), input and output (discrete, calculated) of the model."""
    for i, (name, start, unit, desc) in enumerate(model.parameters):
        variable(name, i, "parameter", model.parameter_variability, unit, desc, start, "exact")
    for i, (name, unit, desc) in enumerate(model.inputs):
        variable(name, VR_INPUT0 + i, "input", "discrete", unit, desc,
                 model.input_starts[i] if model.input_starts is not None else 0.0)
    for i, (name, unit, desc) in enumerate(model.outputs):
        variable(name, VR_OUTPUT0 + i, "output", "discrete", unit, desc, None, "calculated")


def _shared_elements(model: SampledModel, rows: list[str]) -> str:
    """UnitDefinitions, LogCategories, DefaultExperiment and ModelVariables: alike in FMI 2.0 and 3.0."""
    stop = f' stopTime="{float(model.stop_time)!r}"' if model.stop_time is not None else ""
    return f"""  <UnitDefinitions>
{_unit_definitions(_units(model), "    ")}
  </UnitDefinitions>
  <LogCategories>
    <Category name="logStatusError" description="errors: refused calls and values"/>
    <Category name="logAll" description="everything else"/>
  </LogCategories>
  <DefaultExperiment startTime="0.0"{stop} stepSize="{float(model.period)!r}"/>
  <ModelVariables>
{chr(10).join(rows)}
  </ModelVariables>"""


def _fmi2_description(model: SampledModel) -> str:
    rows, index = [], {}

    def variable(name, vr, causality, variability, unit, description, start=None, initial=None):
        index[name] = len(rows) + 1
        attrs = f'name={quoteattr(name)} valueReference="{vr}" causality="{causality}" variability="{variability}"'
        if initial:
            attrs += f' initial="{initial}"'
        real = f"<Real unit={quoteattr(unit)}" + (f' start="{float(start)!r}"' if start is not None else "") \
            + (INPUT_RANGE if causality == "input" else "") + "/>"
        rows.append(f"    <ScalarVariable {attrs} description={quoteattr(description)}>{real}</ScalarVariable>")

    _declare(model, variable)
    outputs = "\n".join(f'      <Unknown index="{index[n]}" dependencies="{" ".join(str(index[d]) for d in model.dependencies[n])}"/>'
                        for n, _, _ in model.outputs)
    # at initialisation the outputs also follow every parameter (the first sample is computed from them)
    initial = "\n".join(f'      <Unknown index="{index[n]}" dependencies="{" ".join(str(index[d]) for d in _initial_dependencies(model, n))}"/>'
                         for n, _, _ in model.outputs)
    sources = "\n".join(f'      <File name="{name}"/>' for name in _compiled_files(model))
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="{model.identifier}" guid="{model.token}"
  description={quoteattr(model.description)} generationTool="agrobot-guidance fmu_export"
  variableNamingConvention="flat" numberOfEventIndicators="0">
  <CoSimulation modelIdentifier="{model.identifier}" canHandleVariableCommunicationStepSize="true"
    canBeInstantiatedOnlyOncePerProcess="false" canNotUseMemoryManagementFunctions="true">
    <SourceFiles>
{sources}
    </SourceFiles>
  </CoSimulation>
{_shared_elements(model, rows)}
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


def _fmi3_description(model: SampledModel) -> str:
    rows, vr_of = [], {}

    def variable(name, vr, causality, variability, unit, description, start=None, initial=None):
        vr_of[name] = vr
        attrs = f'name={quoteattr(name)} valueReference="{vr}" causality="{causality}" variability="{variability}"'
        if initial:
            attrs += f' initial="{initial}"'
        attrs += f" unit={quoteattr(unit)}" + (f' start="{float(start)!r}"' if start is not None else "") \
            + (INPUT_RANGE if causality == "input" else "")
        rows.append(f"    <Float64 {attrs} description={quoteattr(description)}/>")

    rows.append(f'    <Float64 name="time" valueReference="{VR_TIME}" causality="independent" '
                f'variability="continuous" unit="s" description="simulation time"/>')
    _declare(model, variable)

    def unknown(tag, n):
        deps = " ".join(str(vr_of[d]) for d in (model.dependencies[n] if tag == "Output" else _initial_dependencies(model, n)))
        return f'    <{tag} valueReference="{vr_of[n]}" dependencies="{deps}"/>'

    structure = "\n".join([unknown("Output", n) for n, _, _ in model.outputs]
                          + [unknown("InitialUnknown", n) for n, _, _ in model.outputs])
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="3.0" modelName="{model.identifier}" instantiationToken="{model.token}"
  description={quoteattr(model.description)} generationTool="agrobot-guidance fmu_export"
  variableNamingConvention="flat">
  <CoSimulation modelIdentifier="{model.identifier}" canHandleVariableCommunicationStepSize="true"
    canBeInstantiatedOnlyOncePerProcess="false" providesIntermediateUpdate="false"
    hasEventMode="false" canReturnEarlyAfterIntermediateUpdate="false"/>
{_shared_elements(model, rows)}
  <ModelStructure>
{structure}
  </ModelStructure>
</fmiModelDescription>
"""


def _fmi3_build_description(model: SampledModel) -> str:
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiBuildDescription fmiVersion="3.0">
  <BuildConfiguration modelIdentifier="{model.identifier}">
    <SourceFileSet language="C99">
{chr(10).join(f'      <SourceFile name="{name}"/>' for name in _compiled_files(model))}
    </SourceFileSet>
  </BuildConfiguration>
</fmiBuildDescription>
"""


def _compiled_files(model: SampledModel) -> list[str]:
    """The files the build compiles: the FMU's unit, then the further generated units."""
    return [f"{model.identifier}.c", *model.units]


def model_description(model: SampledModel, fmi_version: int) -> str:
    return _fmi2_description(model) if fmi_version == 2 else _fmi3_description(model)


def write_sources(model: SampledModel, root: Path, fmi_version: int) -> None:
    """``root/sources``: the model core, the shared semantics, the wrapper, and one compilation
    unit ``<identifier>.c`` that includes them (so nothing but the FMI API has external linkage)."""
    sources = root / "sources"
    sources.mkdir(parents=True, exist_ok=True)
    core = f"{model.identifier}_model.c"
    (sources / core).write_text(model.core_source)
    for name, text in model.units.items():
        (sources / name).write_text(text)
    for name in ["sampled_instance.c", WRAPPERS[fmi_version], *model.extra_sources]:
        shutil.copy(C_DIR / name, sources / Path(name).name)      # one flat folder: the includes find each other
    (sources / f"{model.identifier}.c").write_text(
        f"/* {model.identifier}: FMI {fmi_version}.0 co-simulation build of a sampled model (one unit). */\n"
        f'#include "{core}"\n#include "sampled_instance.c"\n#include "{WRAPPERS[fmi_version]}"\n')
    if fmi_version == 3:
        (sources / "buildDescription.xml").write_text(_fmi3_build_description(model))
    (root / "modelDescription.xml").write_text(model_description(model, fmi_version))


def build_fmu(model: SampledModel, fmi_version: int = 2) -> bytes:
    """Generate the sources and build the binary for this platform: the FMU's bytes."""
    if fmi_version not in WRAPPERS:
        raise ValueError(f"FMI version {fmi_version}: expected 2 or 3")
    with tempfile.TemporaryDirectory() as tmp:
        write_sources(model, Path(tmp), fmi_version)
        return package_fmu(Path(tmp), fmi_version, f"{model.identifier}.fmu")
