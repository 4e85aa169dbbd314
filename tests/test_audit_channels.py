"""Each channel judged by what it carries (measurements.channel_updates): a small Ackermann machine
(harness.held_channels) logs a 5 Hz heading and 10 Hz positions held in 20 Hz rows, and a wheel
speed that is 0.9 of the true speed; the audit must name the holds with their rates, derive the
track's speed from the positions' own updates (so the speed scale comes out as the truth's 0.9, not
a spiky ratio), and refuse a heading that never updates and a file of zeros."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from agrobot.measurements import LogError
from agrobot.measurements.recording import ImportOptions, import_recording
from agrobot.measurements.signal_expressions import parse_signal
from harness.held_channels import L, signals, write_machine_log

SCALE = 0.9


def options(signal_list, **kw) -> ImportOptions:
    return ImportOptions(signals=[parse_signal(s) for s in signal_list], wheelbase=L, **kw)


@pytest.fixture(scope="module")
def held(tmp_path_factory):
    rec = write_machine_log(tmp_path_factory.mktemp("held") / "rec", seconds=80.0, speed_scale=SCALE)
    return import_recording(rec, options(signals()))


def test_held_channels_are_named_with_their_update_rates_and_the_speed_scale_is_the_truths(held):
    frame, report = held
    rows = {r["channel"]: r for r in report["audit"]["channels"]}
    heading = next(r for name, r in rows.items() if "heading" in name.split(", "))
    fixes = next(r for name, r in rows.items() if "gnss" in name.split(", "))
    # the truth: heading 5 Hz, fixes 10 Hz, rows 20 Hz
    assert abs(heading["rate_hz"] - 5.0) < 0.1 and abs(heading["rows_hz"] - 20.0) < 0.5 and round(heading["held"]) == 4
    assert abs(fixes["rate_hz"] - 10.0) < 0.2 and round(fixes["held"]) == 2
    held_kinds = {tuple(f["channels"]) for f in frame.attrs["audit"] if f["kind"] == "held_samples"}
    assert held_kinds == {("gnss",), ("heading",)}          # the speed and the steering update on every row
    scale = [f for f in frame.attrs["audit"] if f["kind"] == "scale_disagreement" and f["channels"] == ["gnss_speed", "v"]]
    assert len(scale) == 1 and abs(scale[0]["value"] - SCALE) < 0.03, scale
    # the track's speed from the updates is smooth: within 10 % of the true speed (independent truth)
    from harness.held_channels import truth

    drive = truth(80.0, 3)
    t = frame["t"].to_numpy() + report["used"]["start"] + 0.5
    true = np.abs(np.interp(t, drive["t"], drive["v"]))
    track = frame["track_speed"].to_numpy()
    assert np.percentile(np.abs(track - true), 95) < 0.1 * true.mean()


def test_a_heading_that_never_updates_is_refused(tmp_path):
    rec = write_machine_log(tmp_path / "rec", seconds=40.0)
    table = pd.read_csv(rec / "log.csv", dtype=str)
    table["heading"] = "123.4"
    table.to_csv(rec / "log.csv", index=False)
    with pytest.raises(LogError, match=rf"rec: channel heading \(heading=log\.heading.*never updates.*{np.radians(123.4):.5g}.*expected a heading"):
        import_recording(rec, options(signals()))


def test_a_file_of_zeros_exits_2_naming_it(tmp_path, capsys):
    from agrobot.orchestrator.cli import main

    rec = tmp_path / "zeros"
    rec.mkdir()
    n = 400
    pd.DataFrame({"time": 1.7e9 + 0.05 * np.arange(n), "speed": np.zeros(n), "steer": np.zeros(n),
                  "yaw": np.zeros(n)}).to_csv(rec / "log.csv", index=False)
    args = ["convert", str(rec), "--out", str(tmp_path / "out.csv"), "--signal", "v=log.speed[m/s]",
            "--signal", "delta=log.steer[rad]", "--signal", "yaw_rate=log.yaw[rad/s]"]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "no channel changes" in err and "v (" in err and "expected measurements that change" in err
    assert str(rec) in err and not (tmp_path / "out.csv").exists()
