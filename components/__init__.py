"""Co-simulation components of the tractor guidance loop, one per module. A study names a
component by its module (``type = "tractor_yaw_plant"``); each module exposes ``COMPONENT``.
The package registers itself with the orchestrator (pyproject.toml, entry point ``components``)."""


def register(registry) -> None:
    """Orchestrator plugin: this package's component types."""
    registry.add_component_package("components")
