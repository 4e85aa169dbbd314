"""The noise floor of the speed and the positions when the import interpolated them from their own
jittered, slower samples (diagnosis.noise_floor: one rule for every channel).

Truth: a generated tractor log (harness.truth_tractor.make_log, 90 s, rows at 50 Hz; its own white
noise 0.02 m/s and 0.02 m per row) whose speed is read at 8 Hz and its positions at 5 Hz on stamps
jittered by 30 % of an interval, with white noise of SIGMA_V and SIGMA_GPS added to each sample,
then interpolated back onto the rows (harness.own_stamps). A sample between two rows carries the
rows' noise at (1 - f)^2 + f^2 of its variance, 2/3 on average: so the samples' levels are
sqrt(SIGMA^2 + 2/3 0.02^2). Read on the rows, the interpolation damps the top band the levels
are read from (0.6-0.8 of them); read through the same interpolation, within 15 % (the spread
of a level read on 90 s of 8 Hz samples, ~5 %). The speed stage's floor is the RMS of what that noise alone
makes of its residual: the positions' noise across a chord of T s along the track over T, less the
speed noise's mean over the chord -- taken from the very noise the rows carry."""
from __future__ import annotations

import math

import numpy as np
import pytest

from agrobot.diagnosis.candidates import Replay
from agrobot.diagnosis.noise_floor import stage_floors
from agrobot.diagnosis.pipeline import baseline_from_study, load_study
from harness.hidden_effects import BASELINES
from harness.own_stamps import on_own_stamps
from harness.truth_tractor import make_log

SIGMA_V, SIGMA_GPS, ROW_NOISE = 0.1, 0.05, 0.02


@pytest.fixture(scope="module")
def case():
    frame, _ = make_log(11, None, duration=90.0, rate=50.0)
    frame, noise = on_own_stamps(frame, {("v",): (8.0, SIGMA_V), ("x", "y"): (5.0, SIGMA_GPS)}, seed=5)
    replay = Replay(frame, baseline_from_study(load_study(BASELINES["tractor"])))
    return replay, noise, stage_floors(replay, replay.baseline.values)


def test_the_levels_read_are_the_samples_noise(case):
    _, _, floors = case
    for sensor, sigma in (("v", SIGMA_V), ("gps", SIGMA_GPS)):
        truth = math.sqrt(sigma ** 2 + 2 / 3 * ROW_NOISE ** 2)
        assert abs(floors["_sensors"][sensor] - truth) < 0.15 * truth, (sensor, floors["_sensors"], truth)


def test_the_speed_floor_is_what_the_noise_makes_of_the_chord_speed(case):
    replay, noise, floors = case
    k, span = replay.chord_k, replay.chord_span
    chord = replay.gps[2 * k:] - replay.gps[:-2 * k]
    along = chord / np.hypot(chord[:, 0], chord[:, 1])[:, None]
    position = np.column_stack([noise["x"], noise["y"]])
    across = np.sum((position[2 * k:] - position[:-2 * k]) * along, axis=1) / span
    rolling = np.convolve(noise["v"], np.ones(2 * k + 1) / (2 * k + 1), mode="valid")
    error = np.full(len(replay.t), np.nan)
    error[k:-k] = across - rolling
    scored = replay.masks["speed"]["fit"] | replay.masks["speed"]["test"]
    truth = float(np.sqrt(np.mean(error[scored] ** 2)))
    assert abs(floors["speed"] - truth) < 0.15 * truth, (floors["speed"], truth)
