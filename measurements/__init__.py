"""Measured data: the canonical log's columns, reading and checking logs, resampling and splitting them."""
from .log import CANONICAL, COLUMNS, LogError, read_log, resample, split

__all__ = ["CANONICAL", "COLUMNS", "LogError", "read_log", "resample", "split"]
