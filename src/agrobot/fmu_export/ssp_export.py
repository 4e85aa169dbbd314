"""``export-ssp``: a study as an SSP 1.0 archive (System Structure and Parameterization).

``FILE.ssp`` holds ``SystemStructure.ssd`` and ``resources/<component>.fmu``, one FMU per study
component (fmu_export.component_fmus), FMI 2.0 (the version every SSP engine reads). The SSD
keeps the study's component and port names (an input that shares an output's name is
``<name>_in``, FMI names being unique), every connection, each component's parameter values
(inline ParameterBindings, SI with units) and the units with their BaseUnits; DefaultExperiment
gives start and stop time. The orchestrator's study annotation (orchestrator.ssp) carries what SSP 1.0 has
no element for (base step, each component's step, seed), for this project's own import (another
engine is given its step by its own API: libcosim's ``from_ssp_file(path, step_size)``). The SSD is validated against the SSP 1.0 schema before
the archive is made (in memory: agrobot.api.export_ssp writes it).

Imported where used: lxml (the fmu-export extra)."""
from __future__ import annotations

from pathlib import Path
from xml.sax.saxutils import quoteattr

import fmpy

from agrobot.orchestrator.build import System, build_system
from agrobot.orchestrator.errors import InputError
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.ssp import STUDY_ANNOTATION
from agrobot.orchestrator.study import Study
from agrobot.orchestrator.units import base_unit

from .component_fmus import component_model, fmu_input_name, non_exportable
from .packaging import PackagingError, archive
from .sampled_fmu import build_fmu

SSD_NS = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
          "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
          "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues"}


class SSPExportError(InputError):
    """The study cannot be written as an SSP (the message names the study and why)."""


def _unit_xml(unit: str) -> str:
    base = base_unit(unit)
    attrs = " ".join(f'{k}="{v}"' for k, v in (base.fmi_attributes().items() if base else []))
    return f"      <ssc:Unit name={quoteattr(unit)}><ssc:BaseUnit {attrs}/></ssc:Unit>"


def system_structure(system: System, models: dict) -> str:
    """SystemStructure.ssd of the built study whose components are ``models`` (name -> SampledModel)."""
    study = system.study
    s = study.study
    units: set[str] = set()
    elements = []
    for name, model in models.items():
        node = system.nodes[name]
        connectors = []
        # an input no connection drives is left out: it keeps the FMU's start value (fmpy's SSP master
        # would tie an unconnected input connector to the source of the one listed before it)
        driven = {fmu_input_name(node.component, inp) for inp, _, _ in node.sources}
        for port, unit, _ in model.inputs:
            if port not in driven:
                continue
            connectors.append(f'          <ssd:Connector name={quoteattr(port)} kind="input"><ssc:Real unit={quoteattr(unit)}/></ssd:Connector>')
            units.add(unit)
        for port, unit, _ in model.outputs:
            connectors.append(f'          <ssd:Connector name={quoteattr(port)} kind="output"><ssc:Real unit={quoteattr(unit)}/></ssd:Connector>')
            units.add(unit)
        parameters = []
        for pname, value, unit, _ in model.parameters:
            parameters.append(f'                  <ssv:Parameter name={quoteattr(pname)}><ssv:Real value="{float(value)!r}" '
                              f'unit={quoteattr(unit)}/></ssv:Parameter>')
            units.add(unit)
        elements.append(f"""      <ssd:Component name={quoteattr(name)} type="application/x-fmu-sharedlibrary" source="resources/{name}.fmu">
        <ssd:Connectors>
{chr(10).join(connectors)}
        </ssd:Connectors>
        <ssd:ParameterBindings>
          <ssd:ParameterBinding>
            <ssd:ParameterValues>
              <ssv:ParameterSet version="1.0" name={quoteattr(name)}>
                <ssv:Parameters>
{chr(10).join(parameters)}
                </ssv:Parameters>
              </ssv:ParameterSet>
            </ssd:ParameterValues>
          </ssd:ParameterBinding>
        </ssd:ParameterBindings>
        <ssd:Annotations>
          <ssc:Annotation type="{STUDY_ANNOTATION}"><component step="{float(node.step)!r}" type={quoteattr(type(node.component).__name__)} roles={quoteattr(" ".join(node.component.roles))}/></ssc:Annotation>
        </ssd:Annotations>
      </ssd:Component>""")
    connections = []
    for conn in study.connections:
        target = system.nodes[conn.target].component
        connections.append(f'      <ssd:Connection startElement="{conn.source}" startConnector={quoteattr(conn.output)} '
                           f'endElement="{conn.target}" endConnector={quoteattr(fmu_input_name(target, conn.input))}/>')
    unit_rows = "\n".join(_unit_xml(u) for u in sorted(units))
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="{SSD_NS['ssd']}" xmlns:ssc="{SSD_NS['ssc']}" xmlns:ssv="{SSD_NS['ssv']}"
  version="1.0" name={quoteattr(s.name)} description={quoteattr(s.description or s.name)} generationTool="agrobot-guidance export-ssp">
  <ssd:System name={quoteattr(s.name)}>
    <ssd:Elements>
{chr(10).join(elements)}
    </ssd:Elements>
    <ssd:Connections>
{chr(10).join(connections)}
    </ssd:Connections>
  </ssd:System>
  <ssd:Units>
{unit_rows}
  </ssd:Units>
  <ssd:DefaultExperiment startTime="{float(s.start_time)!r}" stopTime="{float(s.stop_time)!r}"/>
  <ssd:Annotations>
    <ssc:Annotation type="{STUDY_ANNOTATION}"><study base_step="{float(s.base_step)!r}" seed="{int(s.seed)}" analysis={quoteattr(s.analysis or "")}/></ssc:Annotation>
  </ssd:Annotations>
</ssd:SystemStructureDescription>
"""


def validate_ssd(text: str) -> list[str]:
    """Errors of the SSD against the SSP 1.0 schema (fmpy ships the standard's XSD files)."""
    from lxml import etree

    schema = etree.XMLSchema(etree.parse(str(Path(fmpy.__file__).parent / "ssp/schema/SystemStructureDescription.xsd")))
    doc = etree.fromstring(text.encode())
    return [] if schema.validate(doc) else [f"line {e.line}: {e.message}" for e in schema.error_log]


def export_ssp(study: Study) -> bytes:
    """The study as an SSP archive's bytes: every component as an FMU, the SSD validated against
    the schema (agrobot.api.export_ssp writes it)."""
    system = build_system(resolve(study))
    missing = non_exportable(system)
    if missing:
        raise SSPExportError(f"{study.path}: cannot export as SSP: no FMU form for "
                             + ", ".join(f"{n} ({type(system.nodes[n].component).__name__})" for n in missing))
    models = {name: component_model(system, name) for name in system.nodes}
    ssd = system_structure(system, models)
    errors = validate_ssd(ssd)
    if errors:
        raise SSPExportError("internal: the SystemStructure.ssd does not validate: " + "; ".join(errors[:5]))
    fmus = {}
    for name, model in models.items():
        try:
            fmus[name] = build_fmu(model, 2)
        except PackagingError as exc:
            raise SSPExportError(str(exc)) from None
    return archive({"SystemStructure.ssd": ssd, **{f"resources/{n}.fmu": data for n, data in fmus.items()}})
