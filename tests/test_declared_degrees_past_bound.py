"""A yaw rate declared in deg/s (converted to rad/s on reading) that still reaches past a ground
vehicle's 3 rad/s (a gyro shaken by its mount: 230 deg/s) is not "like degrees/s": it was in
degrees. The warning says it was declared in degrees and names other causes; a column declared in
rad/s that reaches as far still reads as degrees/s. Both are kept: the user's word stands."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from agrobot.measurements.log import check_log


def _frame(declared: str, seed: int = 2) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    n = 2000
    frame = pd.DataFrame({"t": np.arange(n) * 0.5, "yaw_rate": rng.normal(0.0, 1.3, n)})   # std 75 deg/s
    frame.attrs["declared"] = {"yaw_rate": declared}
    return frame


def _warning(declared: str) -> str:
    notes = check_log(_frame(declared), "ride.csv", required=("t", "yaw_rate")).attrs.get("notes", [])
    said = [n for n in notes if n.startswith("warning: column 'yaw_rate'")]
    assert len(said) == 1, notes
    return said[0]


@pytest.mark.parametrize("declared", ["deg/s", "degree/s"])
def test_declared_in_degrees_is_not_said_to_look_like_degrees(declared):
    text = _warning(declared)
    assert "looks like degrees" not in text, text
    assert f"declared in degrees [{declared}]" in text and "shaken by its mount" in text and "kept" in text


def test_declared_in_radians_still_looks_like_degrees():
    text = _warning("rad/s")
    assert "looks like degrees/s" in text and "[rad/s]" in text
