"""Every number a study gives is checked before any work: a component parameter against the physical
range of its class (mass, delay, wait, port, count; NaN never, an infinite mass never), a sweep's
points against the bound on what a sweep may hold, and an output folder that is the working folder
(``agrobot.run(..., out='')``) refused by name."""
from __future__ import annotations

import time
from pathlib import Path

import pytest

import agrobot
from agrobot.orchestrator.cli import main
from agrobot.orchestrator.output import OutputError
from agrobot.orchestrator.parameter_ranges import range_refusal

ROOT = Path(__file__).resolve().parent.parent
FIGURE8 = ROOT / "studies" / "figure8.toml"


def _cli(argv, capsys) -> tuple[int, str]:
    code = main([str(a) for a in argv])
    return code, capsys.readouterr().err


@pytest.mark.parametrize("setting, words", [
    ("tractor.m=inf", ["tractor.parameters.m", "got inf", "mass"]),
    ("tractor.m=-700", ["tractor.parameters.m", "got -700", "mass"]),
    ("steering.command_delay=nan", ["steering.parameters.command_delay", "got nan"]),
    ("steering.command_delay=-0.1", ["steering.parameters.command_delay", "delay"]),
])
def test_an_impossible_parameter_is_refused_before_the_run(tmp_path, capsys, setting, words):
    code, err = _cli(["run", FIGURE8, "--out", tmp_path / "o", "--set", setting, "--engine", "compiled",
                      "--no-plots"], capsys)
    assert code == 2 and all(w in err for w in words) and "Traceback" not in err, err
    assert not (tmp_path / "o").exists()


def test_the_classes_ranges_from_their_units_and_names():
    assert range_refusal("port", "1", 10110, 99999) and range_refusal("port", "1", 10110, 80.5)
    assert range_refusal("port", "1", 10110, 8080) is None
    assert range_refusal("connect_timeout", "s", 5.0, 0.0) and range_refusal("connect_timeout", "s", 5.0, float("inf")) is None
    assert range_refusal("n_swaths", "1", 4, -1) and range_refusal("max_fix_age", "s", 1.0, float("inf")) is None
    assert range_refusal("host_clock_offset", "s", 0.0, -3600.0) is None      # an offset may be negative
    assert range_refusal("gain", "1", 1.0, float("nan"))


SWEEP = """[study]
name = "toy"
stop_time = 1.0
base_step = 0.05
seed = 1

[components.clock]
type = "tests.toy_components:Clock"

[sweep]
{sweep}
"""


@pytest.mark.parametrize("sweep, words", [
    ('mode = "monte_carlo"\nsamples = 1000000000000\nparameters = { "study.stop_time" = { uniform = [1.0, 2.0] } }',
     ["1e+12 points", "samples = 1000000000000"]),
    ('parameters = { "study.stop_time" = { start = 1.0, stop = 2.0, num = 100000 }, '
     '"study.seed" = { start = 1, stop = 100, step = 1 } }', ["1e+07 points"]),
])
def test_a_sweep_past_the_points_it_may_hold_is_refused_at_once(tmp_path, capsys, sweep, words):
    study = tmp_path / "sweep.toml"
    study.write_text(SWEEP.format(sweep=sweep))
    began = time.perf_counter()
    code, err = _cli(["sweep", study, "--out", tmp_path / "o", "--workers", "1"], capsys)
    assert code == 2 and all(w in err for w in words) and "1,000,000" in err, err
    assert time.perf_counter() - began < 10 and not (tmp_path / "o").exists()


def test_run_into_the_working_folder_is_refused(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "keep.txt").write_text("mine")
    for out in ("", ".", str(tmp_path.parent)):
        with pytest.raises(OutputError, match="working folder"):
            agrobot.run(FIGURE8, out=out)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.txt"]


def test_an_error_message_line_is_bounded():
    from agrobot.orchestrator.errors import MESSAGE_LINE_LIMIT, exit_code
    from agrobot.orchestrator.study import StudyError

    code, message = exit_code(StudyError("study.base_step: " + ", ".join(f"{k * 1e-9:.9g}" for k in range(40_000))))
    assert code == 2 and len(message) < MESSAGE_LINE_LIMIT + 200 and "characters cut" in message
    assert message.startswith("error: study.base_step: 0, 1e-09") or "study.base_step: 0, 1e-09" in message
