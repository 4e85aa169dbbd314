"""A fit of the track stages (position, speed) replays each value set's dead-reckoned antenna track
once: the speed stage, scored on the same sets right after the position stage, reads the tracks
that stage replayed (a racecar's side-slip block fits yaw, position and speed together at every
step of every fit, and the track is most of a step's cost). Truth: the tracks computed directly with
replay.antenna_track, and the count of its calls."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from agrobot.diagnosis import candidates
from agrobot.diagnosis.baseline import baseline_from_study
from agrobot.diagnosis.candidates import Replay
from agrobot.diagnosis.replay import antenna_track
from agrobot.orchestrator.study import load_study
from harness.truth_tractor import make_log

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def replay():
    frame, _ = make_log(11, "antenna_lever_arm", duration=60.0)
    return Replay(frame, baseline_from_study(load_study(ROOT / "studies" / "figure8.toml")))


def test_position_then_speed_replay_each_track_once(replay, monkeypatch):
    assert {"position", "speed"} <= set(replay.stages)
    calls = []

    def counted(*args):
        calls.append(args[3])
        return antenna_track(*args)

    monkeypatch.setattr(candidates, "antenna_track", counted)
    base = dict(replay.baseline.values)
    sets = [{**base, "antenna_forward": a} for a in (0.0, 0.3, 0.6)]
    position = replay.residuals_many("position", sets, "fit")
    speed = replay.residuals_many("speed", sets, "fit")
    assert len(calls) == len(sets)                     # not one per stage and set
    for v, r_pos, r_speed in zip(sets, position, speed):
        track = antenna_track(replay.t, replay.gyro, replay.speed, v, replay.lateral(v))
        fresh = replay.track_residuals(track, replay.windows["fit"])       # aligned, whitened
        assert np.array_equal(r_pos, fresh)
        k = replay.chord_k
        d = track[2 * k:] - track[:-2 * k]
        chord = np.full(len(replay.t), np.nan)
        chord[k:-k] = np.hypot(d[:, 0], d[:, 1]) / replay.chord_span
        assert np.array_equal(r_speed, (replay.track_speed - chord)[replay.masks["speed"]["fit"]])
    replay.residuals_many("position", sets[:1] + [{**base, "antenna_forward": 0.9}], "fit")
    assert len(calls) == len(sets) + 1                 # a new set replayed, the kept one read
