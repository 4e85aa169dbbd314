"""Whether a channel's rows are its own samples interpolated: one rule (measurements.own_samples.
interpolates) for identify's gyro reading and the diagnosis's noise floor alike.

A channel sampled at 9.7 Hz on its own stamps (jittered +-10 ms), interpolated linearly onto 100 Hz
rows (np.interp: the truth). Its stamps rounded to 1 us
(as a POSIX clock keeps them) still pass; rows 1e-3 off the interpolation do not; and a
near-duplicate stamp (1e-9 s after another, another value: a slope of 1e8 per second) widens the
tolerance of the rows beside it alone, so the rows 1e-3 off elsewhere are still told apart.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from agrobot.measurements.own_samples import interpolates, own_stamps


def channel(duplicate: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(rows t, stamps, samples, rows interpolated): 20 s of a 0.3 Hz sine plus noise."""
    rng = np.random.default_rng(3)
    stamps = 0.013 + np.arange(194) / 9.7 + rng.uniform(-0.01, 0.01, 194)
    values = np.sin(2 * np.pi * 0.3 * stamps) + rng.normal(0, 0.05, 194)
    if duplicate:                               # a second sample 1e-9 s after the 100th, 0.1 higher
        stamps = np.insert(stamps, 101, stamps[100] + 1e-9)
        values = np.insert(values, 101, values[100] + 0.1)
    t = np.arange(0.02, 19.9, 0.01)
    return t, stamps, values, np.interp(t, stamps, values)


def test_the_rows_interpolated_from_rounded_stamps_pass_and_rows_off_them_do_not():
    t, stamps, values, rows = channel()
    assert interpolates(t, rows, np.round(stamps, 6), values)
    assert not interpolates(t, rows + 1e-3 * (t > 10), stamps, values)


def test_a_near_duplicate_stamp_does_not_let_every_row_pass():
    t, stamps, values, rows = channel(duplicate=True)
    assert interpolates(t, rows, stamps, values)
    off = rows + 1e-3 * (np.abs(t - stamps[100]) > 1.0)          # off everywhere but beside the duplicate
    assert not interpolates(t, off, stamps, values)
    frame = pd.DataFrame({"t": t, "yaw_rate": off})
    frame.attrs["own_samples"] = {"yaw_rate": (stamps.tolist(), values.tolist())}
    assert own_stamps(frame, "yaw_rate") is None
    frame["yaw_rate"] = rows
    assert np.array_equal(own_stamps(frame, "yaw_rate"), stamps)
