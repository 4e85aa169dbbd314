"""Measured data: the canonical log's columns, reading and checking logs, splitting them."""
from .log import CANONICAL, COLUMNS, LogError, read_log, split

__all__ = ["CANONICAL", "COLUMNS", "LogError", "read_log", "split"]
