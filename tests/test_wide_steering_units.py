"""A wheel angle past 70 deg (a tricycle's or a forklift's steered wheel turns to 90 deg) is read
as radians when the turns say so, a column past pi/2 never (no wheel angle in rad passes 90 deg),
and a unit the user declared to convert still stands when the written log is read back. Generated
recordings: a tricycle of known wheelbase driven through wide turns, r = v tan(delta) / L exactly,
with gyro noise; at the edges, a tractor steered to 60 deg and the tricycle to 85 deg written in
degrees, and the tricycle to 85 deg in rad with its sensor's zero 1 deg off."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from agrobot.api import convert
from agrobot.measurements import LogError, read_log
from agrobot.measurements.log import EVIDENT_ANGLE, READING_ERROR, TAN_ERROR, TAN_WIDEST, WIDEST_LOCK

WHEELBASE = 0.964


def tricycle_log(seed: int = 0, n: int = 3000, h: float = 1 / 30, lock: float = 1.4,
                 wheelbase: float = WHEELBASE) -> pd.DataFrame:
    """Wide turns up to ``lock`` rad both ways, up to 1.8 m/s and slower in tight turns; the truth is
    r = v tan(delta) / L."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * h
    delta = lock * np.sin(2 * np.pi * t / 37.0) * np.abs(np.sin(2 * np.pi * t / 11.0))
    v = (1.05 + 0.75 * np.sin(2 * np.pi * t / 23.0)) / (1 + np.abs(np.tan(delta)))    # slow in tight turns
    yaw_rate = v * np.tan(delta) / wheelbase + rng.normal(0, 0.005, n)
    return pd.DataFrame({"t": t, "delta": delta, "v": v, "yaw_rate": yaw_rate})


@pytest.mark.parametrize("lock, zero, rel", [(1.4, 0.0, 0.02), (math.radians(85), math.radians(1), 0.05)])
def test_wide_steering_is_read_as_radians_on_the_turns_evidence(tmp_path, lock, zero, rel):
    """To 1.4 rad (80 deg), and to a pivot-steer tricycle's 85 deg with its sensor's zero 1 deg off."""
    path = tmp_path / "tricycle.csv"
    log = tricycle_log(lock=lock)
    log["delta"] += zero
    log.to_csv(path, index=False)
    frame = read_log(path, ("t",))
    note = next(n for n in frame.attrs["notes"] if "'delta'" in n)
    assert "read as rad" in note
    found = float(note.split("L = ")[1].split(" m")[0])
    assert found == pytest.approx(WHEELBASE, rel=rel)


@pytest.mark.parametrize("lock, wheelbase", [(60.0, 2.5), (85.0, WHEELBASE)])
def test_a_wide_lock_written_in_degrees_is_refused_as_past_pi_over_2(tmp_path, lock, wheelbase):
    """A tractor steered to 60 deg and the tricycle to 85 deg, their columns in degrees: past pi/2,
    which no wheel angle in rad reaches, whatever the turns."""
    log = tricycle_log(lock=math.radians(lock), wheelbase=wheelbase)
    log["delta"] = np.degrees(log["delta"])
    path = tmp_path / "degrees.csv"
    log.to_csv(path, index=False)
    with pytest.raises(LogError, match=r"'delta' reaches .*past pi/2 = 1.571 rad .* looks like degrees"):
        read_log(path, ("t",))


def test_the_bounds_are_what_their_derivations_say():
    """The widest angle used: a reading error of 0.5 deg moves tan there by TAN_ERROR (10 %, to first order); the
    evident angle: tan exceeds the angle by about three times that; both short of pi/2."""
    assert math.tan(TAN_WIDEST + READING_ERROR) / math.tan(TAN_WIDEST) - 1 == pytest.approx(TAN_ERROR, rel=0.15)   # first order
    assert math.tan(EVIDENT_ANGLE) / EVIDENT_ANGLE - 1 == pytest.approx(3 * TAN_ERROR, rel=0.05)
    assert EVIDENT_ANGLE < TAN_WIDEST < WIDEST_LOCK == math.pi / 2


def test_a_small_angle_in_degrees_is_still_refused(tmp_path):
    """The same turns with a steering in degrees whose true angle never passes 1.4 deg: r follows
    v times the column linearly, not its tangent."""
    truth = tricycle_log()
    small = np.radians(truth["delta"])           # true angles up to 1.4 deg ...
    truth["yaw_rate"] = truth["v"] * np.tan(small) / WHEELBASE
    path = tmp_path / "degrees.csv"
    truth.to_csv(path, index=False)              # ... written in degrees (the column reaches 1.4)
    with pytest.raises(LogError, match="'delta' reaches .* looks like degrees"):
        read_log(path, ("t",))


def test_a_declared_unit_stands_when_the_converted_log_is_read_back(tmp_path):
    """No turns to judge by (the yaw rate does not follow the steering): the declared [rad] is kept
    with a warning by convert, and again by every reader of the log it wrote."""
    raw = tricycle_log()
    raw["yaw_rate"] = np.random.default_rng(1).permutation(raw["yaw_rate"].to_numpy())
    src = tmp_path / "raw.csv"
    raw.to_csv(src, index=False)
    out = tmp_path / "log.csv"
    convert(src, out, signals=["delta=delta[rad]", "v=v[m/s]", "yaw_rate=yaw_rate[rad/s]"])   # as the API takes them
    frame = read_log(out, ("t",))
    assert any("'delta'" in n and "kept as declared [rad]" in n for n in frame.attrs["notes"])
    undeclared = tmp_path / "plain.csv"
    pd.read_csv(out).to_csv(undeclared, index=False)         # the same table without its import report
    with pytest.raises(LogError, match="'delta' reaches .* looks like degrees"):
        read_log(undeclared, ("t",))


def test_the_python_api_refuses_a_malformed_signal_text_by_name(tmp_path):
    src = tmp_path / "raw.csv"
    tricycle_log().to_csv(src, index=False)
    with pytest.raises(LogError, match=r"--signal 'delta\[rad\]': expected COLUMN=EXPR\[unit\]"):
        convert(src, signals=["delta[rad]"])
