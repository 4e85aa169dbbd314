"""One Study API for every variant, composite subsystems, an orchestrator that is a
library. Composites are checked against the same system wired flat (a second method)."""
from __future__ import annotations

import ast
import re
from pathlib import Path

import numpy as np
import pytest

from agrobot.components.models.yaw_dynamics import TractorParameters
from agrobot.components.tractor_yaw_plant import TractorYawPlant
from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.engine import Simulation
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study, StudyError, parse_study
from tests.commands import cli

ROOT = Path(__file__).resolve().parents[1]
FIGURE8 = ROOT / "studies" / "figure8.toml"
CONTROLLERS = ("tracker", "mpc", "speed_controller")


def frame_of(study: Study):
    return Simulation(build_system(resolve(study))).run().to_frame()


# --- variants ---------------------------------------------------------------------------------

def test_with_values_derives_a_new_study_and_leaves_the_original_alone():
    base = Study.load(FIGURE8)
    variant = base.with_values({"reference.speed": 1.5, "study.seed": 7, "tractor.inputs.speed": 0.0,
                                "tractor.C_f": "9000 N/rad"})
    assert variant.components["reference"].parameters["speed"] == 1.5 and variant.study.seed == 7
    assert variant.components["tractor"].inputs == {"speed": 0.0}
    assert base.components["reference"].parameters["speed"] == 2.0 and base.study.seed == 2024
    assert base.components["tractor"].inputs == {}
    assert resolve(variant).parameters("tractor")["C_f"] == 9000.0          # the unit string parsed in one place
    with pytest.raises(StudyError, match=r"no component 'referee' \(did you mean 'reference'\?\); components: .*reference"):
        base.with_values({"referee.speed": 1.0})


def test_set_overrides_go_through_the_same_path_as_with_values():
    by_set = Study.load(FIGURE8, ["reference.speed=1.5", "study.stop_time=20"])
    by_api = Study.load(FIGURE8).with_values({"reference.speed": 1.5, "study.stop_time": 20})
    assert by_set.to_data() == by_api.to_data()


def test_resolved_parameters_accept_units_wherever_they_are_read(tmp_path):
    """The speed-sweep analysis used to fail on C_f = "8000 N/rad", which the study loader accepts."""
    from agrobot.analysis.speed_sweep import tractor_parameters

    study = Study.load(FIGURE8, ['tractor.C_f="8000 N/rad"', 'tractor.l_r="40 cm"'])
    p = tractor_parameters(study)
    assert p.C_f == 8000.0 and p.l_r == pytest.approx(0.4)
    declared = TractorYawPlant.declared("parameter")
    full = resolve(study).parameters("tractor")
    assert set(full) == set(declared) and full["psi0"] == pytest.approx(np.radians(30))
    assert TractorParameters.of(full) == TractorParameters(l_r=full["l_r"])


def test_to_toml_round_trips_and_runs_the_same(tmp_path):
    study = Study.load(FIGURE8, ["study.stop_time=10"])
    path = tmp_path / "copy.toml"
    path.write_text(study.to_toml())
    again = Study.load(path)
    assert again.to_data() == study.to_data()
    np.testing.assert_array_equal(frame_of(again).to_numpy(), frame_of(study).to_numpy())


def test_find_by_role_or_type_and_without_and_replace():
    study = Study.load(FIGURE8)
    assert resolve(study).find(role="yaw_plant") == ["tractor"] == resolve(study).find(type=TractorYawPlant)
    assert resolve(study).find(type="tractor_yaw_plant") == ["tractor"]
    assert resolve(study).one(role="yaw_rate_controller") == "mpc"
    with pytest.raises(StudyError, match="exactly one component with role 'nmea_server', found 0"):
        resolve(study).one(role="nmea_server")
    smaller = study.without("ekf")
    assert "ekf" not in smaller.components
    assert not [c for c in smaller.connections if "ekf" in (c.source, c.target)]
    assert len(smaller.connections) == len(study.connections) - sum("ekf" in (c.source, c.target) for c in study.connections)
    replaced = study.replace_component("gps", "gps_sensor", parameters={"latency": 0.1})
    assert replaced.components["gps"].parameters == {"latency": 0.1} and replaced.connections == study.connections


# --- composite subsystems -----------------------------------------------------------------------

def test_controllers_as_a_composite_subsystem_give_the_flat_trajectory(tmp_path):
    """Extract the three controllers into a study of their own, use it as ONE component in their
    place: the sampled composite (inner feedthrough) must reproduce the flat study exactly."""
    flat = Study.load(FIGURE8, ["study.stop_time=30"])
    sub = resolve(flat).extract(CONTROLLERS, name="guidance")
    (tmp_path / "guidance.toml").write_text(sub.to_toml())
    host = resolve(flat).collapse(CONTROLLERS, into="guidance", type=str(tmp_path / "guidance.toml"), step=0.05)
    cls = resolve(host).component_class("guidance")
    assert cls.sampled and set(cls.feedthrough["mpc_steer_angle_cmd"]) >= {"tracker_x", "mpc_yaw_rate"}
    a, b = frame_of(flat), frame_of(host)
    for port in ("x_cg", "y_cg", "heading"):
        np.testing.assert_array_equal(a[f"tractor.{port}"], b[f"tractor.{port}"])
    np.testing.assert_array_equal(a["mpc.steer_angle_cmd"], b["guidance.mpc_steer_angle_cmd"])


def _inline(k1: float, k2: float, extra_connections=()) -> Study:
    return parse_study({
        "study": {"name": "inline", "stop_time": 1.0, "base_step": 0.1, "seed": 1},
        "components": {"clock": {"type": "tests.toy_components:Clock"}},
        "subsystems": {"chain": {
            "components": {"a": {"type": "tests.toy_components:Gain", "parameters": {"k": k1}},
                           "b": {"type": "tests.toy_components:Gain", "parameters": {"k": k2}}},
            "connections": ["a.y -> b.u"],
            "exports": {"inputs": {"u": "a.u"}, "outputs": {"y": "b.y", "y_first": "a.y"}}}},
        "connections": ["clock.value -> chain.u", *extra_connections]}, "inline.toml")


def test_inline_subsystem_steps_with_its_feedthrough_in_the_same_instant():
    frame = frame_of(_inline(2.0, 3.0))
    np.testing.assert_allclose(frame["chain.y"], 6.0 * frame["t"], atol=1e-12)
    np.testing.assert_allclose(frame["chain.y_first"], 2.0 * frame["t"], atol=1e-12)
    # a parameter of an inner component, named component.parameter, set from the host
    varied = _inline(2.0, 3.0).with_values({"chain.b.k": 5.0})
    np.testing.assert_allclose(frame_of(varied)["chain.y"], 10.0 * frame["t"], atol=1e-12)


def test_a_loop_through_a_composites_feedthrough_is_refused():
    study = _inline(1.0, 1.0, ["chain.y -> chain.u"])
    with pytest.raises(StudyError) as err:
        build_system(resolve(study))
    assert "already driven" in str(err.value) or "algebraic loop" in str(err.value)
    loop = parse_study({**_inline(1.0, 1.0).to_data(), "connections": ["chain.y -> chain.u"]}, "loop.toml")
    with pytest.raises(StudyError, match="algebraic loop"):
        build_system(resolve(loop))


def test_subsystem_errors_name_the_file_and_the_field(tmp_path):
    sub = tmp_path / "sub.toml"
    sub.write_text('[study]\nname = "s"\nstop_time = 1.0\nbase_step = 0.1\nseed = 1\n'
                   '[components.g]\ntype = "tests.toy_components:Gain"\n'
                   '[exports.inputs]\nu = "g.nope"\n')
    host = parse_study({"study": {"name": "h", "stop_time": 1.0, "base_step": 0.1, "seed": 1},
                        "components": {"s": {"type": "sub.toml"}}}, tmp_path / "host.toml")
    with pytest.raises(StudyError, match=r"exports.inputs.u: g.nope is not an input of the subsystem; g's inputs: u"):
        build_system(resolve(host))
    sub.write_text('[study]\nname = "s"\nstop_time = 1.0\nbase_step = 0.1\nseed = 1\n'
                   '[components.g]\ntype = "tests.toy_components:Gain"\n')
    with pytest.raises(StudyError, match=r"has no \[exports\] table"):
        build_system(resolve(host))


def test_the_simulated_tractor_is_the_tractor_side_study_as_one_component():
    rt = Study.load(ROOT / "studies" / "figure8_hardware_layout.toml", ["study.stop_time=20"])
    cls = resolve(rt).component_class("tractor")
    assert cls.sampled is False and "tractor" in cls.roles
    frame = frame_of(rt)
    assert np.all(frame["tractor.fix_quality"] == 4.0)          # RTK fixed throughout (no outage)
    assert frame["tractor.speed_measured"].iloc[-1] > 1.5        # the inner engine runs


# --- the orchestrator as a library ------------------------------------------------------------

def test_the_orchestrator_knows_nothing_of_tractors_and_imports_nothing_above_it():
    words = re.compile(r"tractor|steer|yaw|gps|mpc|agrobot|identification", re.I)
    above = {"components", "analysis", "identification", "diagnosis", "fmu_export", "measurements"}
    for path in sorted((ROOT / "orchestrator").glob("*.py")):
        text = path.read_text()
        assert not words.search(text), f"{path.name}: {words.search(text).group(0)!r}"
        for node in ast.walk(ast.parse(text)):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module or ""] if isinstance(node, ast.ImportFrom) and node.level == 0 else []
            assert not [n for n in names if n.removeprefix("agrobot.").split(".")[0] in above], \
                f"{path.name} imports {names}"


def test_tools_register_their_commands_and_tables():
    from agrobot.orchestrator.registry import registry

    reg = registry()
    assert {"identify", "diagnose", "export-controller", "emulate"} <= set(reg.commands)
    assert "identification" in reg.sections and "agrobot.components" in reg.component_packages
    proc = cli("--help")
    for name in ("run", "sweep", "identify", "diagnose", "export-controller", "emulate"):
        assert name in proc.stdout


def test_an_unknown_top_level_table_is_refused_by_name(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(FIGURE8.read_text() + '\n[identifcation]\nspeeds = [1.0]\n')
    proc = cli("run", str(bad), "--out", str(tmp_path / "o"))
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "unknown table 'identifcation'" in proc.stderr and "identification" in proc.stderr


def test_a_study_file_edits_its_parents_connections_like_with_connections(tmp_path):
    """connections_remove / connections_add in a file that extends another are the file form of
    Study.with_connections (studies/figure8_rlfr.toml inserts a notch that way)."""
    edited = Study.load(ROOT / "studies" / "figure8_rlfr.toml")
    by_api = Study.load(ROOT / "studies" / "figure8.toml").with_connections(
        add=["tractor.yaw_rate -> yaw_notch.yaw_rate", "yaw_notch.yaw_rate_filtered -> mpc.yaw_rate"],
        remove=["tractor.yaw_rate -> mpc.yaw_rate"])
    assert sorted(map(str, edited.connections)) == sorted(map(str, by_api.connections))
    (tmp_path / "alone.toml").write_text('connections_add = ["a.x -> b.y"]\n[study]\nname = "x"\n')
    with pytest.raises(StudyError, match="only with extends"):
        Study.load(tmp_path / "alone.toml")
