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
from agrobot.measurements.runs import STANDSTILL_KEPT
from harness.truth_tractor import make_log

STILL = 15.0      # s standing still either side


def standstill_around(frame: pd.DataFrame, bias: float, before: float, after: float) -> pd.DataFrame:
    """The log with ``before`` and ``after`` seconds standing still, the gyro reading ``bias`` and noise."""
    h = float(frame["t"].iloc[1] - frame["t"].iloc[0])
    rng = np.random.default_rng(4)

    def standing(row: pd.Series, seconds: float) -> pd.DataFrame:
        n = int(round(seconds / h))
        out = pd.DataFrame({c: np.full(n, row[c]) for c in frame.columns})
        out["v"] = 0.0
        out["yaw_rate"] = bias + 0.003 * rng.standard_normal(n)
        return out

    raw = pd.concat([standing(frame.iloc[0], before), frame, standing(frame.iloc[-1], after)], ignore_index=True)
    raw["t"] = np.arange(len(raw)) * h
    return raw


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    frame, truth = make_log(3, "yaw_rate_bias", duration=90.0, vehicle="tractor")
    raw = standstill_around(frame, truth["bias"], STILL, STILL)
    h = float(frame["t"].iloc[1] - frame["t"].iloc[0])
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


def test_a_long_idle_is_kept_for_a_minute_next_to_the_run(tmp_path):
    frame, truth = make_log(3, "yaw_rate_bias", duration=30.0, vehicle="tractor")
    path = tmp_path / "idle.csv"
    standstill_around(frame, truth["bias"], 150.0, 5.0).to_csv(path, index=False)
    used = convert(path).report["used"]
    assert used["standstill_kept"][0] == pytest.approx(STANDSTILL_KEPT, abs=0.1)
    assert used["standstill_kept"][1] == pytest.approx(5.0, abs=0.2)


def test_trimming_a_log_with_no_standstill_says_nothing_was_left_out(tmp_path):
    frame, _ = make_log(3, None, duration=30.0, vehicle="tractor")
    path = tmp_path / "moving.csv"
    frame.assign(v=np.maximum(frame["v"], 1.0)).to_csv(path, index=False)     # never standing still
    how = convert(path, trim_standstill=True).report["used"]["how"]
    assert "--trim-standstill: nothing left out: no standstill beside the run" in how
