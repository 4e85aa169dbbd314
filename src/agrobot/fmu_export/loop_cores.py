"""The tractor components' C cores (c/components/, the same cores as their FMUs) for the compiled
engine (orchestrator.compiled): the core's shape-fixing #defines, its parameters as run-time
values (a delay length included: one compiled loop serves every delay a sweep draws), its ports.
Registered with the compiled engine by this package's plugin (fmu_export.cli.register)."""
from __future__ import annotations

import functools
from agrobot.orchestrator.build import System
from agrobot.orchestrator.compiled import CCore, NoCCore

from .component_fmus import ComponentExportError, core_parameters, core_spec, exportable
from .sampled_fmu import C_DIR


def loop_core(system: System, name: str) -> CCore:
    """The C core of study component ``name`` (NoCCore says why there is none)."""
    node = system.nodes[name]
    comp, period = node.component, float(node.step)
    if not exportable(comp):
        raise NoCCore(f"type {type(comp).__name__} has no C core")
    try:
        spec = core_spec(system, name)
        parameters = [(n, v) for n, v, _, _ in core_parameters(system, name, spec)]
        if spec.runtime is not None:
            defines, runtime = spec.runtime(comp, period)
        else:
            defines, runtime = spec.compiled(comp, period), {}
    except ComponentExportError as exc:
        raise NoCCore(str(exc).replace(f"{system.study.path}: ", "").replace(f"components.{name}: ", "")) from None
    inputs = [v.name for v in comp.variables if v.causality == "input"]
    outputs = [v.name for v in comp.variables if v.causality == "output"]
    return CCore(f'{defines}#include "{spec.source}"\n', parameters + list(runtime.items()), inputs, outputs,
                 [C_DIR / "components", C_DIR], _sources())


@functools.lru_cache(maxsize=1)
def _sources() -> list:
    """Every C file a core may include (their contents are part of the compiled loop's cache key)."""
    return sorted(p for p in C_DIR.rglob("*") if p.suffix in (".c", ".h"))
