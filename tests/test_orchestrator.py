"""Orchestrator: wiring checks, ordering, multirate stepping, loop refusal, errors and results."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.engine import RunError, Simulation
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.study import StudyError, load_study, parse_study
from tests.commands import cli

ROOT = Path(__file__).resolve().parents[1]


def study(components, connections, stop=1.0, base=0.1, **extra):
    data = {"study": {"name": "toy", "stop_time": stop, "base_step": base, "seed": 1, **extra},
            "components": components, "connections": connections}
    return parse_study(data, "toy.toml")


def run(components, connections, **kw):
    return Simulation(build_system(resolve(study(components, connections, **kw)))).run().to_frame()


def test_chain_declared_backwards_propagates_within_the_same_instant():
    comps = {"c": {"type": "tests.toy_components:Gain", "parameters": {"k": 3.0}},
             "b": {"type": "tests.toy_components:Gain", "parameters": {"k": 2.0}},
             "a": {"type": "tests.toy_components:Clock"}}
    f = run(comps, ["b.y -> c.u", "a.value -> b.u"])
    # outputs at t0 are propagated before anything steps, and nothing is one step late
    np.testing.assert_allclose(f["c.y"], 6.0 * f["t"], atol=1e-12)
    assert f["a.value"].iloc[0] == 0.0


def test_time_is_t0_plus_k_h_without_drift():
    comps = {"a": {"type": "tests.toy_components:Clock"}}
    f = run(comps, [], stop=1000.0, base=0.1, start_time=3.0)
    k = np.arange(len(f))
    assert len(f) == 9971          # stop_time is absolute: (1000 - 3) / 0.1 + 1 samples
    assert np.array_equal(f["t"].to_numpy(), 3.0 + k * 0.1)


def test_multirate_steps_at_integer_multiples_and_publishes_at_step_end():
    comps = {"clk": {"type": "tests.toy_components:Clock", "step": 0.5},
             "slow": {"type": "tests.toy_components:Counter", "step": 0.3},
             "fast": {"type": "tests.toy_components:Counter", "step": 0.1}}
    st = study(comps, ["clk.value -> slow.u", "clk.value -> fast.u"], stop=3.0, base=0.1)
    system = build_system(resolve(st))
    f = Simulation(system).run().to_frame()
    slow = system.nodes["slow"].component
    assert [round(t, 9) for t, _ in slow.calls] == [0.0, 0.3, 0.6, 0.9, 1.2, 1.5, 1.8, 2.1, 2.4, 2.7]
    assert all(math.isclose(dt, 0.3) for _, dt in slow.calls)
    assert len(system.nodes["fast"].component.calls) == 30
    # a continuous output recorded at t describes t: the slow counter's "time" output lags
    # by less than its step and is published only when its step ends
    np.testing.assert_allclose(f["fast.time"], f["t"], atol=1e-12)
    assert np.all(f["slow.time"] <= f["t"] + 1e-12) and np.all(f["t"] - f["slow.time"] < 0.3 - 1e-9)
    # the sampled clock holds its value for its 0.5 s step
    np.testing.assert_allclose(f["clk.value"], np.floor(f["t"] / 0.5 + 1e-9) * 0.5, atol=1e-12)
    # zero-order hold integral of the held clock, computed by hand
    expected = sum(0.1 * (math.floor(k * 0.1 / 0.5 + 1e-9) * 0.5) for k in range(30))
    assert math.isclose(f["fast.integral"].iloc[-1], expected, rel_tol=1e-12)


@pytest.mark.parametrize("order", [("a", "b", "c"), ("c", "b", "a")])
def test_continuous_components_read_each_other_at_t_k_whatever_the_order(order):
    """b and c integrate a.time (forward Euler): they must see a's value at t_k, never the one
    a reaches at t_k + h in the same macro step, in any declaration order."""
    specs = {"a": {"type": "tests.toy_components:Counter", "step": 0.1},
             "b": {"type": "tests.toy_components:Counter", "step": 0.1},
             "c": {"type": "tests.toy_components:Counter", "step": 0.3}}
    comps = {name: specs[name] for name in order}
    f = run(comps, ["a.time -> b.u", "a.time -> c.u", "b.time -> a.u"], stop=3.0, base=0.1)
    n = np.arange(len(f))
    np.testing.assert_allclose(f["b.integral"], 0.01 * n * (n - 1) / 2, atol=1e-9)
    np.testing.assert_allclose(f["a.integral"], 0.01 * n * (n - 1) / 2, atol=1e-9)
    # c steps at 0, 0.3, ...: sum of 0.3 * t_j over its steps that ended by t
    ends = np.floor(n / 3 + 1e-9)
    np.testing.assert_allclose(f["c.integral"], 0.09 * ends * (ends - 1) / 2, atol=1e-9)


def test_algebraic_loop_is_refused_with_the_loop_named():
    comps = {"a": {"type": "tests.toy_components:Gain"}, "b": {"type": "tests.toy_components:Gain"}}
    with pytest.raises(StudyError) as err:
        build_system(resolve(study(comps, ["a.y -> b.u", "b.y -> a.u"])))
    msg = str(err.value)
    assert "algebraic loop" in msg and "a.y" in msg and "b.u" in msg and "toy.toml" in msg


def test_a_continuous_component_breaks_a_loop():
    comps = {"a": {"type": "tests.toy_components:Gain"}, "c": {"type": "tests.toy_components:Counter"}}
    f = run(comps, ["a.y -> c.u", "c.integral -> a.u"])
    assert len(f) == 11


@pytest.mark.parametrize("connections, words", [
    (["a.value -> m.u"], ["unit mismatch", "'s'", "'m'"]),
    (["a.nope -> g.u"], ["has no output 'nope'", "outputs: value"]),
    (["a.value -> g.y"], ["has no input 'y'", "it is an output"]),
    (["zz.value -> g.u"], ["unknown component 'zz'"]),
    (["a.value -> g.u", "a.value -> g.u"], ["already driven"]),
])
def test_bad_connections_get_clear_messages(connections, words):
    comps = {"a": {"type": "tests.toy_components:Clock"}, "g": {"type": "tests.toy_components:Gain"},
             "m": {"type": "tests.toy_components:Metres"}}
    with pytest.raises(StudyError) as err:
        build_system(resolve(study(comps, connections)))
    for w in words:
        assert w in str(err.value)
    assert "toy.toml" in str(err.value) and "connections[" in str(err.value)


@pytest.mark.parametrize("components, words", [
    ({"g": {"type": "tests.toy_components:Gain", "parameters": {"kk": 1}}}, ["components.g.parameters.kk", "did you mean 'k'", "Known: k"]),
    ({"g": {"type": "tests.toy_components:Gain", "step": 0.25}}, ["components.g.step", "integer multiple"]),
    ({"g": {"type": "no_such_module"}}, ["cannot import", "components.no_such_module"]),
    ({"g": {"type": "tests.toy_components:Nope"}}, ["has no 'Nope'"]),
])
def test_bad_components_get_clear_messages(components, words):
    with pytest.raises(StudyError) as err:
        build_system(resolve(study(components, [])))
    for w in words:
        assert w in str(err.value)


def test_validation_errors_name_file_and_field():
    with pytest.raises(StudyError) as err:
        parse_study({"study": {"name": "x", "stop_time": -1, "base_step": 0.1, "seed": 1},
                     "components": {"g": {"type": "x", "colour": 1}}}, "bad.toml")
    msg = str(err.value)
    assert "bad.toml" in msg and "study.stop_time" in msg and "components.g.colour" in msg


def test_edge_units_are_converted_and_wrong_units_refused():
    st = study({"g": {"type": "figure8_reference", "parameters": {"speed": "7.2 km/h"}},
                "t": {"type": "tractor_yaw_plant", "parameters": {"psi0": "90 deg"}}}, [],
               allow_unconnected=["t.steer_angle", "t.speed"])
    system = build_system(resolve(st))
    assert math.isclose(system.nodes["g"].component.p["speed"], 2.0)
    assert math.isclose(system.nodes["t"].component.p["psi0"], math.pi / 2)
    with pytest.raises(StudyError) as err:
        build_system(resolve(study({"g": {"type": "figure8_reference", "parameters": {"speed": "3 deg"}}}, [])))
    assert "components.g.parameters.speed" in str(err.value) and "expected 'm/s'" in str(err.value)


def test_yaml_and_toml_studies_are_equivalent(tmp_path):
    import yaml
    import tomllib

    data = tomllib.loads((ROOT / "studies/figure8.toml").read_text())
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(data))
    a, b = load_study(ROOT / "studies/figure8.toml"), load_study(tmp_path / "s.yaml")
    assert a.model_dump(exclude={"path"}) == b.model_dump(exclude={"path"})


def test_failure_mid_run_keeps_recorded_results(tmp_path):
    (tmp_path / "metrics.json").write_text("{}")
    st = study({"f": {"type": "tests.toy_components:FailAt", "parameters": {"fail_time": 0.55}}}, [],
               stop=1.0, base=0.05, signals_format="csv")
    with pytest.raises(RunError) as err:
        run_study(st, tmp_path, overwrite=True)
    assert "deliberate failure" in str(err.value)
    import pandas as pd

    partial = pd.read_csv(tmp_path / "signals.csv")
    assert len(partial) == 11 and partial["f.value"].iloc[-1] == pytest.approx(0.5)
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert metrics["status"] == "failed" and "deliberate failure" in metrics["error"]
    assert not list(tmp_path.glob("*.tmp"))


@pytest.mark.parametrize("edit, words", [
    (lambda s: s.replace('"tracker.yaw_rate_desired -> mpc.yaw_rate_ref"', '"tracker.yaw_rate_wanted -> mpc.yaw_rate_ref"'),
     ["no output 'yaw_rate_wanted'"]),
    (lambda s: s.replace('"tracker.yaw_rate_desired -> mpc.yaw_rate_ref"', '"tracker.speed_desired -> mpc.yaw_rate_ref"'),
     ["unit mismatch"]),
    (lambda s: s.replace('"gps.x -> ekf.gps_x"', '"tracker.error_x -> ekf.gps_x"').replace(
        '"ekf.x_cg -> tracker.x"', '"ekf.x_rear -> tracker.x"'), ["algebraic loop"]),
    (lambda s: s.replace("stop_time = 160.0", "stop_time = -5"), ["study.stop_time"]),
])
def test_cli_reports_bad_study_without_traceback(tmp_path, edit, words):
    bad = tmp_path / "bad.toml"
    bad.write_text(edit((ROOT / "studies/figure8.toml").read_text()))
    proc = cli("run", str(bad), "--out", str(tmp_path / "o"))
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert str(bad) in proc.stderr
    for w in words:
        assert w in proc.stderr
    assert not (tmp_path / "o").exists()


def test_a_run_too_short_for_the_analysis_keeps_its_signals_and_says_why(tmp_path):
    proc = cli("run", str(ROOT / "studies/figure8.toml"), "--out", str(tmp_path), "--set", "study.stop_time=5")
    assert proc.returncode == 1 and "Traceback" not in proc.stderr
    assert "run too short for metrics" in proc.stderr and "study.analysis" in proc.stderr
    assert (tmp_path / "signals.parquet").exists()
    assert json.loads((tmp_path / "metrics.json").read_text())["status"] == "analysis_failed"


def test_infinite_times_are_refused_with_the_field_named(tmp_path):
    proc = cli("run", str(ROOT / "studies" / "figure8.toml"), "--out", str(tmp_path / "o"),
               "--set", "study.stop_time=inf")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "study.stop_time" in proc.stderr and "finite" in proc.stderr


def test_result_files_get_the_usual_permissions_not_mkstemps_0600(tmp_path):
    import os

    from agrobot.orchestrator.atomic_files import write_json

    mask = os.umask(0)
    os.umask(mask)
    path = write_json(tmp_path / "m.json", {"a": 1})
    assert path.stat().st_mode & 0o777 == 0o666 & ~mask
