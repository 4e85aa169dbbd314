"""A header written as a comment line (numpy.savetxt's ``# time(s),delta(deg),...``, as the
deep-dynamics racecar logs come): its names and their units in brackets are the columns', and the
log holds the generated truth (degrees, km/h, deg/s) in radians and m/s. A comment line of prose,
or one whose fields do not match the rows, leaves the table header-less (col1, col2 ...)."""
from __future__ import annotations

import math

import numpy as np

from agrobot.measurements.options import ImportOptions
from agrobot.measurements.recording import import_recording
from agrobot.measurements.tables import read_table
from tests.test_tables_as_they_come import drive

HEAD = {"t": "t(s)", "delta_cmd": "delta_cmd(deg)", "delta": "delta(deg)", "v": "v(km/h)", "yaw_rate": "yaw_rate(deg/s)"}


def write(path, head: str):
    truth = drive()
    rows = [",".join(repr(float(truth[n][k])) for n in truth) for k in range(len(truth["t"]))]
    path.write_text("\n".join([head] + rows) + "\n")
    return truth


def test_a_commented_header_names_the_columns_with_their_units(tmp_path):
    path = tmp_path / "racecar.csv"
    truth = write(path, "# " + ",".join(HEAD.values()))
    table = read_table(path)
    assert list(table.frame.columns) == ["t", "delta_cmd", "delta", "v", "yaw_rate"] and not table.headerless
    assert table.units == {"t": "s", "delta_cmd": "deg", "delta": "deg", "v": "km/h", "yaw_rate": "deg/s"}
    frame, report = import_recording(path, ImportOptions())
    start = report["used"]["utc_start_s"]
    assert abs(start - truth["t"][0]) < 0.2
    for c, scale in (("delta", math.pi / 180), ("v", 1 / 3.6), ("yaw_rate", math.pi / 180)):
        want = np.interp(start + frame["t"].to_numpy(), truth["t"], truth[c] * scale)
        assert np.allclose(frame[c].to_numpy(), want, atol=1e-9), c
    assert any("header is a comment line" in n for n in report["notes"])


def test_a_comment_of_prose_or_of_another_width_is_not_a_header(tmp_path):
    for head in ("# exported by the logger, firmware 2.1", "# " + ",".join(list(HEAD.values())[:4]),
                 "# 1.0,2.0,3.0,4.0,5.0"):
        path = tmp_path / "plain.csv"
        write(path, head)
        table = read_table(path)
        assert table.headerless and list(table.frame.columns)[:2] == ["col1", "col2"], head
