"""Co-simulation components of the tractor guidance loop, one per module. A study names a
component by its module (``type = "tractor_yaw_plant"``); each module exposes ``COMPONENT``."""
