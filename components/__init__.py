"""Co-simulation components of the tractor guidance loop, one per module. A study names a
component by its module (``type = "tractor_yaw_plant"``); each module exposes ``COMPONENT``.
The package registers itself with the orchestrator (pyproject.toml, entry point ``components``)."""
from .hardware.record import record_study


def register(registry) -> None:
    """Orchestrator plugin: this package's component types."""
    registry.add_component_package(__name__)
    for former in ("orchestrator", "components", "analysis", "diagnosis", "fields", "fmu_export", "identification",
                   "measurements"):          # study files of the release before the one import root
        registry.add_module_alias(former, f"agrobot.{former}")
    registry.add_run_option("--record", "record the tractor's buses into DIR as a field logger would: gps.nmea "
                            "(host-stamped NMEA) and can.log (candump); a simulated tractor needs no real-time wait",
                            "DIR", record_study)
