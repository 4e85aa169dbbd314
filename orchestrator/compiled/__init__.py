"""The compiled engine: when every component of a study has a C core (its class declares it,
``c_core``: orchestrator.compiled.cores), the study's whole loop (its wiring, rates,
initial values and parameters, the master algorithm's order and sample-and-hold) is generated
as C, compiled once per shape and cached, and run by one call per run.

    from agrobot.orchestrator.compiled import select_engine
    factory, note = select_engine(system, "auto")     # CompiledSimulation, or Simulation and why
    recording = factory(system).run()

The orchestrator's part is generic: it knows no component; orchestrator.compiled.cores says what
a core provides.
"""
from .cores import CCore, CoreDescription, NoCCore
from .simulation import ENGINES, CompiledRefused, CompiledSimulation, cores_of, select_engine
from .toolchain import CompileError, CompilerMissing

__all__ = ["CCore", "CoreDescription", "NoCCore", "ENGINES", "CompiledRefused", "CompiledSimulation",
           "cores_of", "select_engine", "CompileError", "CompilerMissing"]
