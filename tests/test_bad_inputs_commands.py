"""Bad input through each command that reads a log (convert, identify, diagnose): a file of zeros, a
table of text only, a heading that never updates (on a generated recording, harness.quirk_recordings),
and a --where naming a column the log lacks. Each exits 2 naming the file, the channel and what
was expected, with no traceback; convert and identify write nothing; diagnose writes a complete
'cannot decide' diagnosis for a log it cannot judge, and nothing for a --where that does not fit
the log (a usage error)."""
from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from agrobot.api import convert
from harness.quirk_recordings import compose
from tests.commands import refused

ZEROS_SIGNALS = ("--signal", "v=log.speed[m/s]", "--signal", "delta=log.steer[rad]", "--signal", "yaw_rate=log.yaw[rad/s]")
CASES = {        # input: (the words the refusal must hold: its channel and what was expected)
    "zeros": ("v (", "delta (", "expected measurements that change"),
    "text": ("time,speed,steer", "expected a header and rows of numbers"),
    "heading": ("channel heading", "never updates", "expected a heading that changes"),
}


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    root = tmp_path_factory.mktemp("bad")
    zeros = root / "zeros"
    zeros.mkdir()
    n = 400
    pd.DataFrame({"time": 1.7e9 + 0.05 * np.arange(n), "speed": np.zeros(n), "steer": np.zeros(n),
                  "yaw": np.zeros(n)}).to_csv(zeros / "log.csv", index=False)
    text = root / "text"
    text.mkdir()
    (text / "log.csv").write_text("time,speed,steer\n" + "".join(f"row{k},fast,left\n" for k in range(50)))
    heading = root / "heading"
    compose(2, heading, classes=["heading_no_gyro"], layout="table", machine="mower", duration=40.0)
    table = pd.read_csv(heading / "log.csv", dtype=str)
    table["heading"] = "123.4"                      # a compass heading frozen while the machine turns
    table.to_csv(heading / "log.csv", index=False)
    return {"zeros": zeros, "text": text, "heading": heading}


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("command", ["convert", pytest.param("identify", marks=pytest.mark.slow),
                                     pytest.param("diagnose", marks=pytest.mark.slow)])
def test_a_bad_input_exits_2_naming_it_and_writes_nothing_half(cli, inputs, tmp_path, case, command):
    out = tmp_path / ("out.csv" if command == "convert" else "out")
    extra = ZEROS_SIGNALS if case == "zeros" else ()
    proc = cli(command, inputs[case], "--out", out, *extra, *(("--no-plots",) if command != "convert" else ()))
    err = refused(proc, str(inputs[case]), *CASES[case])
    if command != "diagnose":
        assert not out.exists() and not out.with_suffix(".import.json").exists()
        return
    written = json.loads((out / "diagnosis.json").read_text())        # a log it cannot judge: said, complete
    assert written["verdict"] == "cannot decide" and written["reason"] in err
    assert sorted(p.name for p in out.iterdir()) == ["diagnosis.json", "report.md"]


@pytest.mark.parametrize("command", ["identify", "diagnose"])
def test_a_where_naming_a_column_the_log_lacks_writes_nothing(cli, tmp_path, command):
    compose(3, tmp_path / "rec", classes=[], layout="table", machine="tractor", duration=60.0)
    convert(tmp_path / "rec", tmp_path / "log.csv")
    out = tmp_path / "out"
    proc = cli(command, tmp_path / "log.csv", "--where", "mode == auto", "--out", out, "--no-plots")
    refused(proc, "log.csv", "no column 'mode'", "the log has t, delta_cmd, delta, v, yaw_rate")
    assert not out.exists()
