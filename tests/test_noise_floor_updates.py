"""A noise floor read on the sensor's own updates (diagnosis.noise_floor): a gyro of known white
noise sigma updated every 4th row of a log, held or interpolated between its updates, on a slow
yaw motion. Read on the rows its white level comes out far below sigma (the hold and the
interpolation are low-pass); read on its updates it is sigma."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from agrobot.diagnosis.noise_floor import level_on_updates, update_step, white_level

SIGMA, FACTOR, FS = 0.01, 4, 50.0


def held_gyro(interpolated: bool, seed: int = 3) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    t = np.arange(0, 120, 1 / FS)
    slow = 0.2 * np.sin(2 * np.pi * 0.1 * t)
    tu = t[::FACTOR]
    updates = slow[::FACTOR] + SIGMA * rng.standard_normal(len(tu))      # what the sensor says, at its updates
    if interpolated:
        return t, np.interp(t, tu, updates)
    return t, np.repeat(updates, FACTOR)[: len(t)]


@pytest.mark.parametrize("interpolated", [False, True])
def test_the_floor_on_updates_is_the_sensors_sigma(interpolated):
    t, r = held_gyro(interpolated)
    on_rows = white_level(r, FS)
    on_updates = level_on_updates(r, FS, FACTOR)
    assert on_rows < 0.6 * SIGMA
    assert abs(on_updates - SIGMA) < 0.15 * SIGMA, on_updates


def test_the_update_step_from_the_import_finding_or_the_repeats():
    t, r = held_gyro(False)
    frame = pd.DataFrame({"t": t, "yaw_rate": r})
    assert update_step(frame, "yaw_rate", 1 / FS) == FACTOR
    t, r = held_gyro(True)
    frame = pd.DataFrame({"t": t, "yaw_rate": r})
    assert update_step(frame, "yaw_rate", 1 / FS) == 1         # nothing says it: every row
    frame.attrs["audit"] = [{"kind": "held_samples", "channels": ["yaw_rate"], "updates_hz": FS / FACTOR}]
    assert update_step(frame, "yaw_rate", 1 / FS) == FACTOR
