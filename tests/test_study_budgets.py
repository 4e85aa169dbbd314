"""Budgets before work: the step schedule of coprime rates costs nothing (built lazily), a run
past the limits is refused with its numbers and a base step that serves, and study files that
would explode (YAML alias bombs, a study that uses itself) are refused with a short message."""
from __future__ import annotations

import math
import resource
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.engine import Simulation
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.schedule import Schedule, common_step
from agrobot.orchestrator.study import StudyError, load_study, parse_study

SENSOR_STEPS = (0.07, 0.11, 0.13, 0.17, 0.19, 0.23)       # six sensors at 70-230 ms


def _sensors(base: float, stop: float, steps=SENSOR_STEPS):
    comps = {f"s{k}": {"type": "tests.toy_components:Clock", "step": s} for k, s in enumerate(steps)}
    return parse_study({"study": {"name": "sensors", "stop_time": stop, "base_step": base, "seed": 1},
                        "components": comps}, Path("sensors.toml"))


def test_six_coprime_sensor_rates_on_a_1_ms_base_step_cost_nothing():
    """The period of the schedule is lcm(70, 110, 130, 170, 190, 230) base steps (~7.4e7); a
    1-second run steps each sensor exactly when k is a multiple of its ratio, in well under a
    second and a few MB, the due lists made only for the sets that occur."""
    system = build_system(resolve(_sensors(0.001, 1.0)))
    tracemalloc.start()
    began = time.perf_counter()
    sim = Simulation(system)
    rec = sim.run()
    took = time.perf_counter() - began
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    ratios = [round(s / 0.001) for s in SENSOR_STEPS]
    assert sim._period == math.lcm(*ratios) > 7e7
    assert took < 5.0 and peak < 50e6, (took, peak)
    frame = rec.to_frame()
    k = np.arange(len(frame))
    for j, r in enumerate(ratios):              # the sample held is the one of the last multiple of r
        expected = (k // r) * r * 0.001
        assert np.allclose(frame[f"s{j}.value"].to_numpy(), expected), j
    # the distinct due sets met in 1001 steps: at most one per combination that occurs
    occurs = {tuple(r for r in ratios if kk % r == 0) for kk in range(1001)}
    assert sim._due.sets == len(occurs)


def test_the_lazy_schedule_is_the_table_where_both_exist():
    items = [("a", 2), ("b", 3), ("c", 4), ("d", 6)]
    table = Schedule(items, lambda i: i[1])
    lazy = Schedule(items, lambda i: i[1], table_limit=0)
    assert table.period == lazy.period == 12
    for phase in range(12):
        assert table[phase] == lazy[phase] == [i for i in items if phase % i[1] == 0]


def test_common_step_is_the_greatest_step_dividing_all():
    assert common_step([0.07, 0.11, 0.13]) == pytest.approx(0.01)
    assert common_step([0.05, 0.1, 0.25]) == pytest.approx(0.05)
    assert common_step([0.001]) == pytest.approx(0.001)


def test_a_run_past_the_budget_is_refused_before_anything_is_built_with_a_base_step_that_serves():
    system = build_system(resolve(_sensors(1e-12, 1.0, (0.05, 0.1))))
    began = time.perf_counter()
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    with pytest.raises(StudyError) as err:
        Simulation(system)
    message = str(err.value)
    assert time.perf_counter() - began < 2.0
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 100_000      # kB: nothing was built
    assert "1e+12 base steps" in message and "study.base_step = 0.05" in message, message
    assert len(message) < 400


def test_the_command_line_says_it_in_one_line(tmp_path, capsys):
    from agrobot.orchestrator.cli import main

    path = tmp_path / "tiny_step.toml"
    path.write_text('[study]\nname = "t"\nstop_time = 10.0\nbase_step = 1e-9\nseed = 1\n\n'
                    '[components.c]\ntype = "tests.toy_components:Clock"\nstep = 0.1\n')
    assert main(["run", str(path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "1e+10 base steps" in err and "study.base_step = 0.1" in err, err
    assert not (tmp_path / "o").exists() and not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


BOMB = """study: {name: bomb, stop_time: 1.0, base_step: 0.1, seed: 1}
components:
  c: {type: "tests.toy_components:Clock", step: 0.1}
my_tool:
  a: &a [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]
  b: &b [*a, *a, *a, *a, *a, *a, *a, *a, *a, *a]
  c: &c [*b, *b, *b, *b, *b, *b, *b, *b, *b, *b]
  d: &d [*c, *c, *c, *c, *c, *c, *c, *c, *c, *c]
  e: &e [*d, *d, *d, *d, *d, *d, *d, *d, *d, *d]
  f: &f [*e, *e, *e, *e, *e, *e, *e, *e, *e, *e]
  g: &g [*f, *f, *f, *f, *f, *f, *f, *f, *f, *f]
  h: &h [*g, *g, *g, *g, *g, *g, *g, *g, *g, *g]
  i: &i [*h, *h, *h, *h, *h, *h, *h, *h, *h, *h]
"""


def test_a_yaml_alias_bomb_is_refused_at_once(tmp_path):
    path = tmp_path / "bomb.yaml"
    path.write_text(BOMB)
    assert len(BOMB) < 700
    began = time.perf_counter()
    with pytest.raises(StudyError) as err:
        load_study(path)
    assert time.perf_counter() - began < 2.0
    assert "alias bomb" in str(err.value) and "my_tool" in str(err.value) and len(str(err.value)) < 300
    fine = tmp_path / "fine.yaml"                 # aliases as such are fine
    fine.write_text(BOMB.split("  b:")[0] + "  b: [*a, *a]\n")
    assert load_study(fine).sections["my_tool"]["b"] == [[1] * 10] * 2


def test_a_yaml_alias_that_contains_itself_is_refused(tmp_path):
    path = tmp_path / "loop.yaml"
    path.write_text(BOMB.split("my_tool:")[0] + "my_tool:\n  a: &a [1, *a]\n")
    with pytest.raises(StudyError, match="cycle"):
        load_study(path)


def test_a_study_that_uses_itself_is_refused_naming_the_cycle(tmp_path):
    me = tmp_path / "me.toml"
    me.write_text('[study]\nname = "me"\nstop_time = 1.0\nbase_step = 0.1\nseed = 1\n\n'
                  '[components.inner]\ntype = "other.toml"\n\n[exports]\noutputs = { v = "inner.value" }\n')
    (tmp_path / "other.toml").write_text('[study]\nname = "other"\nstop_time = 1.0\nbase_step = 0.1\nseed = 1\n\n'
                                         '[components.back]\ntype = "me.toml"\n\n'
                                         '[exports]\noutputs = { value = "back.v" }\n')
    with pytest.raises(StudyError) as err:
        build_system(resolve(load_study(me)))
    message = str(err.value)
    assert "me.toml -> other.toml -> me.toml" in message and len(message) < 600, message
    (tmp_path / "self.toml").write_text('extends = "self.toml"\n')
    with pytest.raises(StudyError, match=r"circular .*self.toml -> .*self.toml"):
        load_study(tmp_path / "self.toml")
