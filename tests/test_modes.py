"""The stretches judged: a mode channel selects them (--where), and without one the stretches
the steering command does not explain (driven by hand while the follower's command runs on) are
found and left out. Generated logs with known stretches: the follower drives 0-60 s and
115-180 s, a person 60-100 s (the wheel angle follows a hand signal, the command keeps going),
the machine stands 100-115 s."""
from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from agrobot.measurements import LogError
from agrobot.measurements.modes import judged, parse_where, unexplained_mask
from agrobot.measurements.options import ImportOptions
from agrobot.measurements.recording import load_log
from agrobot.orchestrator.cli import main

RATE, WHEELBASE = 20.0, 1.2
HAND, PAUSE = (60.0, 100.0), (100.0, 115.0)


def mower_log(path, seed: int = 3, with_mode: bool = True):
    """A small Ackermann machine's log with its mode channel (auto / manual / paused)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 180.0, 1.0 / RATE)
    cmd = 0.25 * np.sin(0.35 * t) + 0.1 * np.sin(1.1 * t + 1.0)
    follow = np.zeros_like(t)                           # the actuator: a first-order lag of 0.15 s
    for k in range(1, len(t)):
        follow[k] = follow[k - 1] + (cmd[k - 1] - follow[k - 1]) / (0.15 * RATE)
    hand = 0.3 * np.sin(0.9 * t + 2.0) * np.sin(0.13 * t)
    manual = (t >= HAND[0]) & (t < HAND[1])
    paused = (t >= PAUSE[0]) & (t < PAUSE[1])
    delta = np.where(manual, hand, follow) + rng.normal(0, 0.002, len(t))
    v = np.where(paused, 0.0, 1.5)
    yaw = v * np.tan(delta) / WHEELBASE + rng.normal(0, 0.003, len(t))
    heading = np.cumsum(yaw) / RATE
    frame = pd.DataFrame({"t": t, "delta_cmd": cmd, "delta": delta, "v": v, "yaw_rate": yaw,
                          "x": np.cumsum(v * np.cos(heading)) / RATE, "y": np.cumsum(v * np.sin(heading)) / RATE})
    if with_mode:
        frame["mode"] = np.where(manual, "manual", np.where(paused, "paused", "auto"))
    frame.to_csv(path, index=False)
    return frame


def test_where_selects_the_declared_mode_and_prints_its_stretches(tmp_path, capsys):
    truth = mower_log(tmp_path / "mower.csv")
    frame, _ = load_log(tmp_path / "mower.csv", recording=ImportOptions(where="mode == auto"))
    auto = truth["mode"] == "auto"
    assert np.array_equal(frame["t"].to_numpy(), truth["t"][auto].to_numpy())
    printed = capsys.readouterr().err
    assert "2 stretch(es)" in printed and "0.00-59.95 s" in printed and "115.00-179.95 s" in printed
    assert f"({100 * auto.mean():.0f} % of the log)" in printed
    both, _ = load_log(tmp_path / "mower.csv", recording=ImportOptions(where="mode == auto or mode = 'paused'"))
    assert len(both) == int((truth["mode"] != "manual").sum())
    fast, _ = load_log(tmp_path / "mower.csv", recording=ImportOptions(where="mode == auto and t >= 120"))
    assert fast["t"].min() == 120.0


def test_a_mode_that_selects_nothing_exits_2_naming_the_file_channel_and_values(tmp_path, capsys):
    mower_log(tmp_path / "mower.csv")
    with pytest.raises(LogError, match=r"mower.csv: --where 'mode == remote' selects nothing: column 'mode' holds "
                                       r"'auto' \(2500 rows\), 'manual' \(800 rows\), 'paused' \(300 rows\)"):
        load_log(tmp_path / "mower.csv", recording=ImportOptions(where="mode == remote"))
    for bad in ("mode", "mode ~ auto", "== auto"):
        with pytest.raises(LogError, match="expected COLUMN OP VALUE"):
            parse_where(bad)
    for command in ("identify", "diagnose"):
        assert main([command, str(tmp_path / "mower.csv"), "--where", "mode == remote", "--out",
                     str(tmp_path / command)]) == 2
        err = capsys.readouterr().err
        assert "mower.csv" in err and "'mode'" in err and "'manual'" in err and "Traceback" not in err
    assert not (tmp_path / "identify").exists()        # the diagnosis writes its verdict 'cannot decide' and why
    assert "selects nothing" in json.loads((tmp_path / "diagnose" / "diagnosis.json").read_text())["reason"]


def test_without_a_mode_the_hand_driven_stretch_is_found_named_and_left_out(tmp_path, capsys):
    truth = mower_log(tmp_path / "mower.csv", with_mode=False)
    found, fit = unexplained_mask(truth)
    t = truth["t"].to_numpy()
    named = t[found]
    assert abs(named.min() - HAND[0]) < 1.5 and abs(named.max() - HAND[1]) < 1.5     # the truth's stretch
    assert not found[(t < HAND[0] - 1.5) | (t > HAND[1] + 1.5)].any()              # nothing else
    assert abs(fit["delay_s"] - 0.15) <= 0.1
    frame, _ = load_log(tmp_path / "mower.csv", recording=ImportOptions())
    assert len(frame) == len(truth) - int(found.sum())
    assert not ((frame["t"] > HAND[0] + 1.5) & (frame["t"] < HAND[1] - 1.5)).any()
    printed = capsys.readouterr().err
    assert "the command does not explain the steering" in printed and "left out (--keep-unexplained" in printed
    kept, _ = load_log(tmp_path / "mower.csv", recording=ImportOptions(keep_unexplained=True))
    assert len(kept) == len(truth) and "kept (--keep-unexplained)" in capsys.readouterr().err
    follower = judged(truth[truth["t"] < HAND[0]].reset_index(drop=True), "log", ImportOptions())
    assert len(follower) == int((truth["t"] < HAND[0]).sum()) and "selection" not in follower.attrs
    saturated = truth.assign(delta=np.clip(truth["delta_cmd"], -0.2, 0.2))     # follows, up to its stop
    assert not unexplained_mask(saturated[saturated["t"] < HAND[0]].reset_index(drop=True))[0].any()
