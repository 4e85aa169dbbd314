"""The diagnosis-rate benchmark's vehicle-class table (benchmarks/diagnosis_rate.py): the per-class
tally of hand-made rows whose rates are counted here independently, and the class filter and seed count
the command line hands to the table."""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def rate():
    spec = importlib.util.spec_from_file_location("diagnosis_rate", ROOT / "benchmarks" / "diagnosis_rate.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def row(vehicle, effect, found, expected, in_tolerance=True, error=""):
    return {"vehicle": vehicle, "effect": effect, "seed": 1000, "found": found, "expected": expected,
            "in_tolerance": in_tolerance, "error": error, "not_judged": []}


def test_the_class_table_counts_detections_and_false_alarms_per_class(rate, capsys):
    rows = [row("car", "none", [], []),                                               # clean, right
            row("car", "none", ["steering_gain"], []),                                # a false alarm
            row("car", "steering_map_gain", ["steering_gain"], ["steering_gain"]),    # detected
            row("car", "steering_map_gain", ["steering_gain"], ["steering_gain"], in_tolerance=False),  # off
            row("car", "steering_map_curve", ["steering_offset"], ["steering_ratio_curve"]),        # wrong id
            row("car", "steering_map_offset", None, ["steering_offset"], error="CannotDecide: x"),  # failed
            row("tractor", "none", [], []),
            row("tractor", "steering_map_gain", ["steering_gain"], ["steering_gain"])]
    rate._class_rows(rows, ["car", "tractor"], 2, 120.0, 1000, 1.0, "")
    out = capsys.readouterr().out
    assert "| car | 1/4 (25 %) | 1/2 (50 %) | 1 | 0 |" in out
    assert "| tractor | 1/1 (100 %) | 0/1 (0 %) | 0 | 0 |" in out
    assert [r["right"] for r in rows] == [True, False, True, False, False, False, True, True]


@pytest.mark.parametrize("argv, vehicles, seeds", [
    (["--quick"], ["tractor", "car", "small_ackermann"], 1),
    (["--quick", "--classes", "car", "--seeds", "8", "--first-seed", "1008"], ["car"], 8),
    (["--classes", "small_ackermann"], ["small_ackermann"], 3)])
def test_the_command_line_hands_the_classes_and_seeds_to_the_table(rate, monkeypatch, argv, vehicles, seeds):
    called = {}
    monkeypatch.setattr(rate, "class_table", lambda *args: called.setdefault("args", args))
    monkeypatch.setattr(sys, "argv", ["diagnosis_rate.py", *argv])
    rate.main()
    got_vehicles, got_seeds, duration, _, _, first_seed, _ = called["args"]
    assert (got_vehicles, got_seeds) == (vehicles, seeds)
    assert duration == (120.0 if "--quick" in argv else 240.0)
    assert first_seed == (1008 if "1008" in argv else 1000)
