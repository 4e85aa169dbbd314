"""The shipped study files (TOML) and their fields, installed as package data."""
from importlib.resources import files
from pathlib import Path


def shipped(name: str = "") -> Path:
    """The path of a shipped study file or folder (``shipped("figure8.toml")``), wherever the package is
    installed (editable or not)."""
    return Path(str(files(__name__))) / name if name else Path(str(files(__name__)))
