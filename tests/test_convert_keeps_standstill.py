"""convert keeps the standstill before and after the run it uses: identify measures a gyro's bias
there (the mean reading standing still) and concludes it; ``--trim-standstill`` leaves it out, said.

Truth: harness.truth_tractor's paper tractor with a planted gyro bias (its drawn value), driven 90 s,
with 15 s standing still before and after (v = 0, the gyro reading the bias and its noise)."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from agrobot.api import convert
from agrobot.identification.ordinary_driving import identify_driving
from agrobot.measurements import read_log
from harness.truth_tractor import make_log

STILL = 15.0      # s standing still either side


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    frame, truth = make_log(3, "yaw_rate_bias", duration=90.0, vehicle="tractor")
    h = float(frame["t"].iloc[1] - frame["t"].iloc[0])
    n = int(round(STILL / h))
    rng = np.random.default_rng(4)

    def standing(row: pd.Series) -> pd.DataFrame:
        out = pd.DataFrame({c: np.full(n, row[c]) for c in frame.columns})
        out["v"] = 0.0
        out["yaw_rate"] = truth["bias"] + 0.003 * rng.standard_normal(n)
        return out

    raw = pd.concat([standing(frame.iloc[0]), frame, standing(frame.iloc[-1])], ignore_index=True)
    raw["t"] = np.arange(len(raw)) * h
    path = tmp_path_factory.mktemp("standstill") / "raw.csv"
    raw.to_csv(path, index=False)
    return path, truth["bias"], len(raw) * h


def test_the_converted_log_keeps_the_standstill_and_identify_concludes_the_bias(recording, tmp_path):
    path, bias, seconds = recording
    rec = convert(path, tmp_path / "log.csv")
    assert len(rec.log) * (rec.log["t"].iloc[1] - rec.log["t"].iloc[0]) > seconds - 1.0
    assert "with the standstill either side" in rec.report["used"]["how"]
    rep = identify_driving(read_log(tmp_path / "log.csv", ("t",)), "log.csv")
    found = rep["parameters"]["gyro_bias"]
    assert "standing still" in found.get("how", "") and found.get("concluded", True), found
    lo, hi = found["interval"]
    assert lo <= bias <= hi, (bias, found)
    assert abs(bias) > 3 * (hi - lo)                    # a bias worth naming, not one inside its own interval


def test_trimming_the_standstill_is_an_option_and_said(recording):
    path, _, seconds = recording
    rec = convert(path, trim_standstill=True)
    assert len(rec.log) * (rec.log["t"].iloc[1] - rec.log["t"].iloc[0]) < seconds - 2 * STILL + 1.0
    assert "left out (--trim-standstill)" in rec.report["used"]["how"]
