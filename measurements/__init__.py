"""Measured data: the canonical log's columns, reading and checking logs (tables, or raw field
recordings of NMEA and CAN), resampling and splitting them."""
from .log import CANONICAL, COLUMNS, LogError, check_log, load_log, read_log, resample, split

__all__ = ["CANONICAL", "COLUMNS", "LogError", "check_log", "load_log", "read_log", "resample", "split"]
