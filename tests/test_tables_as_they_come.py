"""Tables as loggers write them: a units row under the header (its units used as declared),
a header of several rows, comment lines, every row one quoted field, and any of , ; tab | or
white space between fields, read from the content. The truth is the generated drive written in
degrees, km/h and deg/s: the log must hold it in radians and m/s. A table of text only is
refused by name, and a column holding no number is named with why."""
from __future__ import annotations

import math

import numpy as np
import pytest

from agrobot.measurements import LogError
from agrobot.measurements.options import ImportOptions
from agrobot.measurements.recording import import_recording
from agrobot.measurements.signal_expressions import parse_signal
from agrobot.measurements.tables import read_table

T0 = 1_777_622_400.0


def drive(seconds: float = 40.0, rate: float = 10.0):
    """Known truth: time, wheel angle [deg], its command [deg], speed [km/h], yaw rate [deg/s]."""
    t = np.arange(0.0, seconds, 1.0 / rate)
    delta = 8.0 * np.sin(0.4 * t)
    return {"t": T0 + t, "delta_cmd": delta + 1.0, "delta": delta, "v": 7.2 + 0.5 * np.sin(0.1 * t),
            "yaw_rate": 3.0 * np.sin(0.4 * t + 0.3)}


UNITS = {"t": "Unix epoch seconds", "delta_cmd": "deg", "delta": "deg", "v": "km/h", "yaw_rate": "deg/s"}


def write(path, sep: str, quoted: bool = False, comments: bool = False, groups: bool = False):
    truth = drive()
    names = list(truth)
    units = [UNITS[n] for n in names] if sep != " " else ["s", "deg", "deg", "km/h", "deg/s"]
    rows = [sep.join(names), sep.join(units)]
    if groups:         # a group row over the names: 'time' over t, 'steering' over delta_cmd and delta ...
        rows.insert(0, sep.join(["time", "steering", "", "motion", ""]))
    rows += [sep.join(repr(float(truth[n][k])) for n in names) for k in range(len(truth["t"]))]
    if quoted:
        rows = [f'"{r}"' for r in rows]
    if comments:
        rows = ["# exported by a logger", "// firmware 2.1"] + rows[:3] + ["# a comment in the middle"] + rows[3:]
    path.write_text("\n".join(rows) + "\n")
    return truth


@pytest.mark.parametrize("sep,suffix", [(",", ".csv"), (";", ".csv"), ("\t", ".txt"), ("|", ".csv"), (" ", ".dat")])
@pytest.mark.parametrize("quoted,comments", [(False, False), (True, True)])
def test_a_units_row_is_the_columns_units_whatever_the_delimiter(tmp_path, sep, suffix, quoted, comments):
    path = tmp_path / f"drive{suffix}"
    truth = write(path, sep, quoted and sep != " ", comments)
    frame, report = import_recording(path, ImportOptions(time="t[s]"))
    start = report["used"]["utc_start_s"]
    for c, scale in (("delta", math.pi / 180), ("delta_cmd", math.pi / 180), ("v", 1 / 3.6), ("yaw_rate", math.pi / 180)):
        want = np.interp(start + frame["t"].to_numpy(), truth["t"], truth[c] * scale)
        assert np.allclose(frame[c].to_numpy(), want, atol=1e-9), c
    notes = " ".join(report["notes"])
    assert "units row" in notes and "delta [deg]" in notes and "v [km/h]" in notes


def test_the_time_unit_of_a_units_row_reads_as_seconds_without_being_told(tmp_path):
    truth = write(tmp_path / "drive.csv", ",")
    table = read_table(tmp_path / "drive.csv")
    assert table.units == {"t": "s", "delta_cmd": "deg", "delta": "deg", "v": "km/h", "yaw_rate": "deg/s"}
    frame, report = import_recording(tmp_path / "drive.csv")
    assert abs(report["used"]["utc_start_s"] - truth["t"][0]) < 0.2
    assert np.allclose(frame["v"].to_numpy(), np.interp(report["used"]["utc_start_s"] + frame["t"], truth["t"],
                                                        truth["v"] / 3.6), atol=1e-9)


def test_a_header_of_two_rows_of_names_joins_them_and_keeps_the_units(tmp_path):
    truth = write(tmp_path / "drive.csv", ";", groups=True)
    table = read_table(tmp_path / "drive.csv")
    assert list(table.frame.columns) == ["time_t", "steering_delta_cmd", "steering_delta", "motion_v", "motion_yaw_rate"]
    assert table.units["steering_delta"] == "deg" and table.units["motion_v"] == "km/h"
    signals = [parse_signal(s) for s in ("delta=steering_delta", "v=motion_v", "yaw_rate=motion_yaw_rate")]
    frame, report = import_recording(tmp_path / "drive.csv", ImportOptions(signals=signals, time="time_t"))
    start = report["used"]["utc_start_s"]
    assert np.allclose(frame["delta"], np.interp(start + frame["t"], truth["t"], np.radians(truth["delta"])), atol=1e-9)
    assert np.allclose(frame["yaw_rate"], np.interp(start + frame["t"], truth["t"], np.radians(truth["yaw_rate"])),
                       atol=1e-9)


def test_a_column_of_text_is_named_with_why_and_a_table_of_text_only_is_refused(tmp_path, cli):
    truth = drive(10.0)
    rows = ["t,v,mode", "s,m/s,"] + [f"{float(t)!r},{float(v)!r},{'auto' if k % 20 < 10 else 'manual'}"
                                     for k, (t, v) in enumerate(zip(truth["t"], truth["v"]))]
    (tmp_path / "modes.csv").write_text("\n".join(rows) + "\n")
    notes = " ".join(read_table(tmp_path / "modes.csv").notes)
    assert "column 'mode' holds no number: text such as 'auto'" in notes
    text = tmp_path / "text.csv"
    text.write_text("name,kind\nleft,wheel\nright,wheel\nfront,axle\n")
    with pytest.raises(LogError, match="text.csv: a table of text only, no column to take: no row holds a number"):
        read_table(text)
    run = cli("convert", text, "--out", tmp_path / "out.csv")
    assert run.returncode == 2 and "text.csv" in run.stderr and "Traceback" not in run.stderr
    assert "a table of text only" in run.stderr and not (tmp_path / "out.csv").exists()
