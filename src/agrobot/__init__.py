"""agrobot: co-simulation of autonomous-tractor guidance after Kayacan et al., "Towards Agrobots".

One import root for everything the project installs. The subpackages are the repository's top-level
folders, mapped into this package at install time (``setup.py``):

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
from importlib.metadata import PackageNotFoundError, version as _version

try:
    __version__ = _version("agrobot-guidance")
except PackageNotFoundError:        # pragma: no cover - running from an uninstalled tree
    __version__ = "0+unknown"
