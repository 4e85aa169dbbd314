"""The one measured-log type: column table, reader checks, resampling, splitting."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from agrobot.measurements import CANONICAL, COLUMNS, LogError, read_log, resample, split


def log(n=400, h=0.05, jitter=0.0, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) * h + jitter * h * rng.uniform(-1, 1, n) * (np.arange(n) > 0)
    return pd.DataFrame({"t": t, "delta_cmd": 0.1 * np.sin(t), "delta": 0.1 * np.sin(t - 0.1), "v": 2.0 + 0 * t,
                         "yaw_rate": 0.2 * np.cos(t), "x": 2.0 * t, "y": 0 * t})


def test_the_column_table_is_the_canonical_order_with_si_units():
    assert CANONICAL == ("t", "delta_cmd", "delta", "v", "yaw_rate", "x", "y")
    assert {COLUMNS[c][0] for c in ("delta_cmd", "delta")} == {"rad"} and COLUMNS["yaw_rate"][0] == "rad/s"


def test_reader_names_the_file_the_column_and_the_fix(tmp_path):
    good = tmp_path / "good.csv"
    log().to_csv(good, index=False)
    assert list(read_log(good).columns) == list(CANONICAL)
    bad = tmp_path / "bad.csv"
    log().drop(columns=["yaw_rate"]).to_csv(bad, index=False)
    with pytest.raises(LogError, match=r"bad.csv: missing columns \['yaw_rate'\].*yaw_rate \[rad/s\]"):
        read_log(bad)
    degrees = log()
    degrees["delta"] = np.degrees(degrees["delta"]) * 10
    degrees.to_csv(bad, index=False)
    with pytest.raises(LogError, match="'delta' reaches .* looks like degrees"):
        read_log(bad)
    log(jitter=0.1).to_csv(bad, index=False)
    with pytest.raises(LogError, match="unevenly sampled"):
        read_log(bad)


def test_resampling_a_jittered_log_recovers_the_signals_on_an_even_grid(tmp_path):
    jittered = log(jitter=0.1)
    even = resample(jittered, 0.05)
    assert np.allclose(np.diff(even["t"]), 0.05)
    # linear interpolation of a 1 rad/s sine sampled at 20 Hz: error below h^2/8 * max|f''| = 3e-5
    assert np.max(np.abs(even["yaw_rate"] - 0.2 * np.cos(even["t"]))) < 0.2 * 0.05 ** 2 / 8 + 1e-9
    path = tmp_path / "even.csv"
    even.to_csv(path, index=False)
    read_log(path)                                   # passes the reader's even-step check now


def test_split_cuts_by_duration():
    fit, held = split(log(n=401), 0.6)
    assert math.isclose(fit["t"].iloc[-1], 0.6 * 20.0 - 0.05) and math.isclose(held["t"].iloc[0], 12.0)
    assert len(fit) + len(held) == 401
