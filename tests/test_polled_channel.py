"""A channel read at irregular times (a value polled in turn with others, an OBD request answered
when the bus allows) and written in faster rows: each row carries a fresh reading (60 % of rows,
at random) or a copy of the last one, so that most updates are one row apart and the others up to
several (measurements.channel_updates). Generated: a wheel speed on a 0.05 km/h grid with noise;
the truth is the rows whose value is fresh and new.
Its rate is that of its updates, not of its rows; noise on a grid that repeats by chance, and a
state that switches now and then, are not held."""
from __future__ import annotations

import numpy as np
import pandas as pd

from agrobot.api import convert
from agrobot.measurements.channel_updates import holding

FS, SECONDS, QUANTUM = 50.0, 60.0, 0.05 / 3.6     # rows per second, s, m/s


def polled_speed(seed: int = 7, fresh: float = 0.6):
    """(t, v, the rows that carry an update): a speed on a grid, read at a random share of rows."""
    rng = np.random.default_rng(seed)
    t = np.arange(0, SECONDS, 1 / FS)
    true = 5.0 + 1.0 * np.sin(2 * np.pi * 0.2 * t) + 0.03 * rng.standard_normal(len(t))
    read = np.round(true / QUANTUM) * QUANTUM
    new = rng.random(len(t)) < fresh
    new[0] = True
    v = read[np.maximum.accumulate(np.where(new, np.arange(len(t)), 0))]
    update = np.r_[True, v[1:] != v[:-1]]
    return t, v, update


def test_a_polled_channel_is_held_at_the_rate_of_its_updates():
    t, v, update = polled_speed()
    truth = (update.sum() - 1) / (t[update][-1] - t[update][0])
    found = holding(t, v)
    assert found is not None
    assert abs(found["updates_hz"] - truth) < 0.1 * truth, (found["updates_hz"], truth)
    assert 24.0 < truth < 32.0
    updates = np.flatnonzero(update)[1:]
    assert np.mean(np.isin(updates, found["keep"])) > 0.99     # the updates are what is kept


def test_values_that_repeat_by_chance_and_a_state_are_not_held():
    rng = np.random.default_rng(11)
    t = np.arange(0, SECONDS, 1 / FS)
    levels = rng.choice([0.0, 3.0, 7.0], size=len(t), p=[0.6, 0.2, 0.2])   # a fresh value every row
    assert np.mean(levels[1:] == levels[:-1]) > 0.4
    assert holding(t, levels) is None
    state = np.repeat(rng.integers(0, 3, 40), rng.integers(40, 120, 40))[: len(t)].astype(float)
    assert holding(t[: len(state)], state) is None


def test_the_audit_reports_the_polled_speed_at_its_updates(tmp_path):
    t, v, update = polled_speed()
    truth = (update.sum() - 1) / (t[update][-1] - t[update][0])
    delta = 0.05 * np.sin(2 * np.pi * 0.1 * t)
    yaw = v * delta / 2.7 + 0.002 * np.random.default_rng(3).standard_normal(len(t))
    pd.DataFrame({"t": t, "delta": delta, "v": v, "yaw_rate": yaw}).to_csv(tmp_path / "log.csv", index=False)
    rec = convert(tmp_path / "log.csv", wheelbase=2.7)
    rows = {r["channel"]: r for r in rec.report["audit"]["channels"]}
    assert abs(rows["v"]["rate_hz"] - truth) < 0.1 * truth, (rows["v"]["rate_hz"], truth)
    held = [f for f in rec.report["audit"]["findings"] if f["kind"] == "held_samples" and f["channels"] == ["v"]]
    assert len(held) == 1 and abs(held[0]["updates_hz"] - truth) < 0.1 * truth
