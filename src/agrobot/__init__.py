"""agrobot: co-simulation of autonomous-tractor guidance after Kayacan et al., "Towards Agrobots".

One import root for everything the project installs: this folder, ``src/agrobot``. The design's
top-level folders (``components/``, ``orchestrator/``, ``studies/``) are linked into it, so every
subpackage is a folder of this name on disk and static tools (mypy, an editor, an import graph) read
the tree as Python imports it:

    agrobot.orchestrator    the co-simulation library (study files, resolver, engine, sweeps)
    agrobot.components      the guidance loop's components, one per module
    agrobot.identification  yaw-dynamics identification (multisine experiments, ordinary driving)
    agrobot.diagnosis       what the simulation gets wrong on a measured log, and why
    agrobot.measurements    recordings of any source to one log format
    agrobot.fields          field geometry and the coverage planner
    agrobot.analysis        metrics, margins and figures of the shipped studies
    agrobot.fmu_export      the controller and subsystems as FMUs and SSPs
    agrobot.studies         the shipped study files (package data)
"""
from importlib import import_module as _import_module
from importlib.metadata import PackageNotFoundError, version as _version

try:
    __version__ = _version("agrobot-guidance")
except PackageNotFoundError:        # pragma: no cover - running from an uninstalled tree
    __version__ = "0+unknown"

# The Python API (agrobot.api) and its results (agrobot.results), imported on first use so that
# ``import agrobot`` stays light: ``from agrobot import run`` loads them. The ``fields`` command's function is
# ``agrobot.api.fields`` (``agrobot.fields`` is the package).
_API = {"run", "sweep", "identify", "diagnose", "convert", "plan", "margins", "tune", "load", "export_controller",
        "export_fmu", "export_ssp", "emulate"}
_RESULTS = {"RunResult", "Metric", "SweepResult", "Identification", "Diagnosis", "Recording", "PlanResult",
            "LoopMargins", "FieldsResult", "ExportedFile", "EmulationResult", "TunedStudy", "load_result"}
__all__ = sorted(_API | _RESULTS)


def __getattr__(name: str):
    if name in _API or name in _RESULTS:
        value = getattr(_import_module(f"{__name__}.{'api' if name in _API else 'results'}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
