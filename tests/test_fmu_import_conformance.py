"""FMUs in a study, read as the FMI standard writes them: direct feedthrough ordered from
ModelStructure (no lag, loops refused), inputs at the start taken from their sources, every FMI 2.0
and 3.0 type, FMI 3.0 arrays (whole or by element), units compared by dimension and factor,
terminate requests ending the run cleanly, clocks named, structured names connectable, model
exchange integrated with a solver. The FMUs are the tests' own, built from C (tests/fmu_sources)."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.engine import Simulation
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import StudyError, parse_study
from tests.fmu_build import build_test_fmu


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    where = tmp_path_factory.mktemp("conformance")
    return {name: build_test_fmu(name, where) for name in ("conformance2", "conformance3", "bouncing_ball")}


def study(components, connections, stop=1.0, base=0.1):
    data = {"study": {"name": "conformance", "stop_time": stop, "base_step": base, "seed": 1},
            "components": components, "connections": connections}
    return parse_study(data, "conformance.toml")


def run(st):
    return Simulation(build_system(resolve(st))).run()


def test_declared_feedthrough_has_no_lag_and_inputs_start_from_their_sources(fmus):
    st = study({"src": {"type": "tests.toy_components:RateSource"}, "fmu": {"type": str(fmus["conformance2"])},
                "sink": {"type": "tests.toy_components:RateSink"}},
               ["src.rate -> fmu.u", "fmu.y_direct -> sink.u"])
    frame = run(st).to_frame()
    t = frame["t"].to_numpy()
    # y_direct = k u = 3 (1 + t) at every instant, t = 0 included, and the sink sees it at once
    np.testing.assert_allclose(frame["fmu.y_direct"], 3 * (1 + t), rtol=1e-12)
    np.testing.assert_allclose(frame["sink.y"], 3 * (1 + t), rtol=1e-12)
    # x integrates u with the input of each step's start: x(t_k) = h sum_{j<k} (1 + t_j)
    expected = np.concatenate([[0.0], np.cumsum(0.1 * (1 + t[:-1]))])
    np.testing.assert_allclose(frame["fmu.x"], expected, rtol=1e-12)


def test_an_algebraic_loop_through_declared_feedthrough_is_refused(fmus):
    st = study({"fmu": {"type": str(fmus["conformance2"])}, "sink": {"type": "tests.toy_components:RateSink"}},
               ["fmu.y_direct -> sink.u", "sink.y -> fmu.u"])
    with pytest.raises(StudyError, match="algebraic loop.*fmu.u"):
        build_system(resolve(st))


def test_every_fmi2_type_and_structured_names(fmus):
    st = study({"src": {"type": "tests.toy_components:RateSource"},
                "fmu": {"type": str(fmus["conformance2"]), "parameters": {"label": "tractor", "k": 2.0}},
                "ints": {"type": "tests.toy_components:RateSink", "inputs": {"u": 0.0}}},
               ["src.rate -> fmu.u", "src.count -> fmu.n_in", "src.on -> fmu.flag_in"])
    rec = run(st)
    frame = rec.to_frame()
    t = frame["t"].to_numpy()
    np.testing.assert_array_equal(frame["fmu.n_out"].to_numpy(), 2 * (1 + np.floor(t + 1e-9)))
    np.testing.assert_array_equal(frame["fmu.flag_out"].to_numpy().astype(bool), t < 0.5 - 1e-9)
    np.testing.assert_array_equal(frame["fmu.mode"].to_numpy(), np.ones(len(t)))
    np.testing.assert_allclose(frame["fmu.body.speed"], 2 * frame["fmu.x"])      # a structured name
    comp = build_system(resolve(st)).nodes["fmu"].component
    assert comp.declared("output")["label_out"].start == ""
    sim = Simulation(build_system(resolve(st)))
    sim.start()
    assert sim.system.nodes["fmu"].component.y["label_out"] == "tractor"         # String parameter and output
    sim.terminate()


def test_structured_names_connect_and_units_compare_by_dimension_and_factor(fmus):
    # body.speed is in 'grad' (BaseUnit rad, factor pi/200): not the same scale as rad
    st = study({"fmu": {"type": str(fmus["conformance2"])}, "sink": {"type": "tests.toy_components:AngleSink"}},
               ["fmu.body.speed -> sink.angle"])
    with pytest.raises(StudyError, match=r"unit mismatch: output is in 'grad', input expects 'rad' \(not the same"):
        build_system(resolve(st))
    # 'x' is in rad (BaseUnit rad=1): connects to a 'rad' input; u is 'rad.s-1', fed from 'rad/s'
    st = study({"src": {"type": "tests.toy_components:RateSource"}, "fmu": {"type": str(fmus["conformance2"])},
                "sink": {"type": "tests.toy_components:AngleSink"}}, ["src.rate -> fmu.u", "fmu.x -> sink.angle"])
    assert build_system(resolve(st)).nodes["sink"].sources[0][2] == "x"


def test_fmi3_arrays_whole_and_by_element_and_every_type(fmus):
    st = study({"src": {"type": "tests.toy_components:RateSource"},
                "fmu": {"type": str(fmus["conformance3"]), "parameters": {"k": 2.0, "name": "rows"}},
                "first": {"type": "tests.toy_components:RateSink"}},
               ["src.rate -> fmu.u", "src.count -> fmu.gains[2]", "src.count -> fmu.small", "fmu.scaled[3] -> first.u"])
    frame = run(st).to_frame()
    t = frame["t"].to_numpy()
    u = 1 + t
    np.testing.assert_allclose(frame["fmu.scaled[1]"], 2 * 1.0 * u)         # gains[1] keeps its start value 1
    count = 1 + np.floor(t + 1e-9)
    np.testing.assert_allclose(frame["fmu.scaled[2]"], 2 * count * u)       # gains[2] driven by element
    np.testing.assert_allclose(frame["first.y"], 2 * 3.0 * u)               # an element output, no lag
    np.testing.assert_array_equal(frame["fmu.small_twice"], 2 * count)
    np.testing.assert_allclose(frame["fmu.u32"], u.astype(np.float32))
    assert set(frame["fmu.gear"]) == {3} and frame["fmu.on"].all()
    np.testing.assert_array_equal(frame["fmu.count"], np.arange(len(t)))
    sim = Simulation(build_system(resolve(st)))
    sim.start()
    y = sim.system.nodes["fmu"].component.y
    assert isinstance(y["scaled"], np.ndarray) and y["scaled"].shape == (3,)
    sim.terminate()


def test_a_whole_array_connects_and_one_connected_both_ways_is_refused(tmp_path):
    from agrobot.orchestrator.engine import ParameterError

    def unitless(xml: str) -> str:        # scaled without a unit, so that it may feed gains (unit 1)
        return xml.replace('<Float64 name="scaled" valueReference="5" causality="output" unit="rad/s">',
                           '<Float64 name="scaled" valueReference="5" causality="output">')
    fmu = str(build_test_fmu("conformance3", tmp_path, xml_edit=unitless))
    comps = {"src": {"type": "tests.toy_components:RateSource"}, "a": {"type": fmu}, "b": {"type": fmu}}
    frame = run(study(comps, ["src.rate -> a.u", "src.rate -> b.u", "a.scaled -> b.gains"])).to_frame()
    u = 1 + frame["t"].to_numpy()
    for i, gain in enumerate((1.0, 2.0, 3.0), start=1):       # b.scaled = gains u = (gain u) u, no lag
        np.testing.assert_allclose(frame[f"b.scaled[{i}]"], gain * u * u)
    with pytest.raises(ParameterError, match="connected whole and by element"):
        run(study(comps, ["a.scaled -> b.gains", "a.scaled[1] -> b.gains[1]"]))


@pytest.mark.parametrize("name", ["conformance2", "conformance3"])
def test_a_terminate_request_ends_the_run_cleanly_and_is_reported(fmus, name, tmp_path):
    from agrobot.orchestrator.runner import run_study

    st = study({"fmu": {"type": str(fmus[name]), "parameters": {"stop_time": 0.55}}}, [], stop=2.0)
    rec = run(st)
    assert rec.completed and rec.ended_by["component"] == "fmu"
    assert rec.ended_by["t"] == pytest.approx(0.5)
    assert rec.to_frame()["t"].iloc[-1] == pytest.approx(0.5)
    result = run_study(st, tmp_path / "out", plots=False)
    metrics = json.loads((tmp_path / "out/metrics.json").read_text())
    assert metrics["status"] == "ended" and metrics["ended_by"]["t"] == pytest.approx(0.5)
    assert json.loads((tmp_path / "out/run.json").read_text())["t_reached_s"] == pytest.approx(0.5)
    assert len(result.frame) == 6


def test_clocks_are_named_in_a_clear_refusal(fmus, tmp_path):
    def with_clock(xml: str) -> str:
        return xml.replace('<String name="name"', '<Clock name="tick" valueReference="20" causality="input" '
                           'intervalVariability="constant" intervalDecimal="0.1"/>\n    <String name="name"')
    fmu = build_test_fmu("conformance3", tmp_path, xml_edit=with_clock)
    st = study({"fmu": {"type": str(fmu)}}, [])
    with pytest.raises(StudyError, match="clocks are not supported; clocked variables: tick"):
        build_system(resolve(st))


def test_a_model_exchange_fmu_runs_with_a_solver_and_its_events(fmus):
    """The bouncing ball against its closed form: first impact at sqrt(2 h0 / g), then flights of
    2 e v_impact / g; the height between impacts follows the parabola."""
    st = study({"ball": {"type": str(fmus["bouncing_ball"]), "parameters": {"e": 0.8}}}, [], stop=1.5, base=0.01)
    frame = run(st).to_frame()
    g, h0, e = 9.81, 1.0, 0.8
    t1 = math.sqrt(2 * h0 / g)
    v1 = g * t1
    t2 = t1 + 2 * e * v1 / g
    t = frame["t"].to_numpy()

    def exact(tt):
        if tt < t1:
            return h0 - 0.5 * g * tt**2
        if tt < t2:
            return e * v1 * (tt - t1) - 0.5 * g * (tt - t1) ** 2
        return (e * e * v1) * (tt - t2) - 0.5 * g * (tt - t2) ** 2

    np.testing.assert_allclose(frame["ball.h"], [exact(tt) for tt in t], atol=1e-6)
    assert frame["ball.bounces"].iloc[-1] == 2 and frame["ball.h"].min() > -1e-6
