"""A channel's rate is the rate at which its values carry new information (measurements.
channel_updates), on generated recordings whose truth is known:

- a steering sampled at 18.5 Hz, its sample times jittered by a fifth of its period, written in
  25 Hz rows (each row the last sample): its updates one, then two rows apart, a hold of no whole
  number of rows; its rate is its samples', not its rows';
- four wheel speeds, each held at its own rate (12.5, 10, 8.3 and 6.25 Hz) in 25 Hz rows, and their
  mean mapped as the speed: the mean changes whenever any wheel does, but it samples no faster
  than its fastest wheel;
- a speed on a cruise, on a 0.01 m/s grid: it repeats most rows, genuinely (it moves less than a
  step a row); it is not held, its rate is its rows', and the report says why its repeats are
  not copies."""
from __future__ import annotations

import numpy as np
import pandas as pd

from agrobot.api import convert
from agrobot.measurements.channel_updates import holding
from agrobot.measurements.signal_expressions import parse_signal

FS, SECONDS, L = 25.0, 120.0, 2.7          # rows per second, s, wheelbase m


def held_in_rows(t: np.ndarray, rate: float, signal, jitter: float, rng, phase: float = 0.0):
    """(values in the rows ``t``, the rows where a new sample appears): a sensor sampled at
    ``rate`` with its sample times jittered by ``jitter`` of a period, each row its last sample."""
    step = 1.0 / rate
    ts = phase + np.arange(-1, int(SECONDS * rate) + 2) * step + jitter * step * rng.uniform(-0.5, 0.5, int(SECONDS * rate) + 3)
    ts = np.sort(ts)
    samples = signal(ts, rng)
    last = np.searchsorted(ts, t, side="right") - 1
    new = np.r_[True, last[1:] != last[:-1]]
    return samples[last], new


def steering(ts, rng):
    return 0.08 * np.sin(2 * np.pi * 0.12 * ts) + 0.02 * np.sin(2 * np.pi * 0.5 * ts) + 3e-4 * rng.standard_normal(len(ts))


def log_csv(folder, t, columns: dict):
    path = folder / "log.csv"
    pd.DataFrame({"t": t, **columns}).to_csv(path, index=False)
    return path


def audit_row(rec, name: str) -> dict:
    """The audit's channel row of ``name`` (channels on one clock share a row)."""
    return next(r for r in rec.report["audit"]["channels"] if name in r["channel"].split(", "))


def truth_rate(t: np.ndarray, new: np.ndarray) -> float:
    at = np.flatnonzero(new)[1:]
    return (len(at) - 1) / float(t[at[-1]] - t[at[0]])


def test_a_steering_held_at_a_jittered_non_integer_ratio_is_held_at_its_samples_rate(tmp_path):
    rng = np.random.default_rng(21)
    t = np.arange(0, SECONDS, 1 / FS)
    delta, new = held_in_rows(t, 18.5, steering, 0.2, rng)
    truth = truth_rate(t, new)
    assert 18.0 < truth < 19.0 and 0.2 < 1 - new.mean() < 0.3     # a quarter of the rows repeat: no whole ratio
    found = holding(t, delta)
    assert found is not None
    assert abs(found["updates_hz"] - truth) < 0.02 * truth, (found["updates_hz"], truth)
    assert np.mean(np.isin(np.flatnonzero(new)[1:], found["keep"])) > 0.99    # the samples are what is kept
    v = 8.0 + 0.5 * np.sin(2 * np.pi * 0.05 * t) + 0.01 * rng.standard_normal(len(t))
    yaw = v * np.tan(steering(t, rng)) / L + 0.002 * rng.standard_normal(len(t))
    rec = convert(log_csv(tmp_path, t, {"delta": delta, "v": v, "yaw_rate": yaw}), wheelbase=L)
    assert abs(audit_row(rec, "delta")["rate_hz"] - truth) < 0.03 * truth, audit_row(rec, "delta")
    assert abs(audit_row(rec, "v")["rate_hz"] - FS) < 0.01 * FS                 # a speed that changes every row is not held
    held = [f for f in rec.report["audit"]["findings"] if f["kind"] == "held_samples"]
    assert [f["channels"] for f in held] == [["delta"]]


def wheel(offset: float):
    def speed(ts, rng):
        return 6.0 + offset + 1.5 * np.sin(2 * np.pi * 0.03 * ts) + 0.02 * rng.standard_normal(len(ts))
    return speed


def test_a_mean_of_four_wheels_held_at_their_own_rates_samples_as_its_fastest_wheel(tmp_path):
    rng = np.random.default_rng(5)
    t = np.arange(0, SECONDS, 1 / FS)
    wheels, rates = {}, {}
    for name, rate, offset, phase in (("fl", 12.5, -0.05, 0.013), ("fr", 10.0, 0.05, 0.029),
                                      ("rl", 25.0 / 3.0, -0.04, 0.007), ("rr", 6.25, 0.04, 0.031)):
        wheels[name], new = held_in_rows(t, rate, wheel(offset), 0.0, rng, phase)
        rates[name] = truth_rate(t, new)
    mean = sum(wheels.values()) / 4
    assert np.mean(mean[1:] != mean[:-1]) > 0.7          # the mean changes at most rows: its rows' rate counts them
    delta = 0.05 * np.sin(2 * np.pi * 0.1 * t)
    yaw = mean * delta / L + 0.002 * rng.standard_normal(len(t))
    path = log_csv(tmp_path, t, {**wheels, "delta": delta, "yaw_rate": yaw})
    signals = [parse_signal(s) for s in ("v=0.25*(log.fl + log.fr + log.rl + log.rr)[m/s]", "delta=log.delta[rad]",
                                         "yaw_rate=log.yaw_rate[rad/s]")]
    rec = convert(path, wheelbase=L, signals=signals, time="t[s]")
    v = audit_row(rec, "v")
    truth = max(rates.values())                          # the fastest wheel: 12.5 Hz
    assert abs(v["rate_hz"] - truth) < 0.03 * truth, (v, rates)
    assert any(q.startswith("v: ") and "a sum of signals" in q for q in rec.report["quirks"]), rec.report["quirks"]
    assert np.allclose(np.sort(rec.log["v"].dropna().to_numpy())[[0, -1]], np.sort(mean)[[0, -1]], atol=0.05)


def test_a_quantised_speed_on_a_cruise_repeats_genuinely_and_is_not_held(tmp_path):
    rng = np.random.default_rng(9)
    t = np.arange(0, SECONDS, 1 / FS)
    true = np.minimum(3.0 + 0.1 * t, 5.0) + 0.003 * rng.standard_normal(len(t))   # up to 5 m/s, then a cruise
    v = np.round(true / 0.01) * 0.01
    assert np.mean(v[1:] == v[:-1]) > 0.6               # most rows repeat: the grid, not a hold
    assert holding(t, v) is None
    delta = 0.05 * np.sin(2 * np.pi * 0.1 * t)
    yaw = true * delta / L + 0.002 * rng.standard_normal(len(t))
    rec = convert(log_csv(tmp_path, t, {"delta": delta, "v": v, "yaw_rate": yaw}), wheelbase=L)
    v_row = audit_row(rec, "v")
    assert abs(v_row["rate_hz"] - FS) < 0.01 * FS and "held" not in v_row
    said = [q for q in rec.report["quirks"] if q.startswith("v: ")]
    assert len(said) == 1 and "single steps of its 0.01 grid" in said[0] and "not held" in said[0], said
