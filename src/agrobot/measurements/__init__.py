"""Measured data: the canonical log's columns, reading and checking logs (tables, or raw field
recordings: NMEA, CAN with any maker's DBC, ROS bags, ISO 11783-10 time logs, other tools' tables),
resampling and splitting them."""
from .log import CANONICAL, COLUMNS, LogError, check_log, read_log, resample, split
from .recording import load_log

__all__ = ["CANONICAL", "COLUMNS", "LogError", "check_log", "load_log", "read_log", "resample", "split"]
