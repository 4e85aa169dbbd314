"""The compiled engine (orchestrator.compiled) against the Python engine: the same study run both
ways gives the same signals (noise off), on every shipped study the compiled engine takes; run-time
parameters (delays, the seed) reuse one compiled shape, shape parameters (the yaw model) make
another; a library of another shape is refused; the bad inputs of the issue exit 2 with their
message; a Monte Carlo of a few hundred draws on a Dask LocalCluster gives the metrics of the
same draws run one by one.

With noise off the loop is deterministic; the steering potentiometer's 1-degree quantisation is
off too: a 1e-16 difference of arithmetic order (matrix exponential by Taylor series against
scipy's Pade, sums in another order) that meets a quantisation threshold flips one level and
the loops part at the quantisation's scale (benchmarks/compiled_engine.py measures that case).
"""
from __future__ import annotations

import json
import os

import numpy as np
import pytest

from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.engine import Simulation
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study
from agrobot.studies import shipped

QUIET = ["gps.position_noise_std=0", "gps.velocity_noise_std=0", "steering.potentiometer_resolution=0"]


def system_of(name: str, overrides=()):
    study = Study.load(shipped(name), list(overrides))
    if study.sweep is not None:
        study = study.without("sweep")
    return build_system(resolve(study))


def compiled_run(name: str, overrides=()):
    from agrobot.orchestrator.compiled import CompiledSimulation

    sim = CompiledSimulation(system_of(name, overrides))
    return sim, sim.run()


def assert_same_signals(a, b, rtol=1e-9):
    """Every column within rtol of the signal's own scale (its largest magnitude)."""
    assert a.columns == b.columns
    assert a.data.shape == b.data.shape
    scale = np.maximum(np.abs(b.data).max(axis=0), 1e-12)
    worst = np.abs(a.data - b.data).max(axis=0) / scale
    bad = {c: float(w) for c, w in zip(["t"] + a.columns, worst) if w > rtol}
    assert not bad, f"signals differing by more than {rtol:g} of their scale: {bad}"


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    """One cache folder for the module: each shape is compiled once (into it: the libraries an
    earlier test file loaded in this process are set aside, or a shape they hold would not be built)."""
    from agrobot.orchestrator.compiled import toolchain

    folder = tmp_path_factory.mktemp("compiled-cache")
    old = os.environ.get("AGROBOT_CACHE")
    os.environ["AGROBOT_CACHE"] = str(folder)
    loaded = dict(toolchain._LOADED)
    toolchain._LOADED.clear()
    yield folder
    toolchain._LOADED.update(loaded)
    if old is None:
        os.environ.pop("AGROBOT_CACHE", None)
    else:
        os.environ["AGROBOT_CACHE"] = old


def test_the_shipped_studies_it_takes_are_the_figure8_family(cache):
    from agrobot.orchestrator.compiled import cores_of
    from agrobot.orchestrator.compiled.simulation import refusal

    takes = set()
    for name in ("figure8.toml", "robustness.toml", "speed_sweep.toml", "figure8_pure_pursuit.toml", "field_test.toml"):
        system = system_of(name)
        if not refusal(system, cores_of(system)[1]):
            takes.add(name)
    assert takes == {"figure8.toml", "robustness.toml", "speed_sweep.toml"}


@pytest.mark.parametrize("name, overrides", [
    ("figure8.toml", []),                                              # the whole 160 s
    ("robustness.toml", ["study.stop_time=40", "tractor.model=transfer_function", "steering.command_delay=0.13",
                         "command_link.samples=1", "gps.latency=0.1"]),
    ("speed_sweep.toml", ["study.stop_time=40", "reference.speed=2.75", "tractor.model=rlfr"]),
])
def test_compiled_signals_equal_the_python_engines(cache, name, overrides):
    sim, compiled = compiled_run(name, QUIET + overrides)
    python = Simulation(system_of(name, QUIET + overrides)).run()
    assert compiled.completed
    assert_same_signals(compiled, python)


def test_run_time_values_share_a_shape_and_shape_values_do_not(cache):
    a, _ = compiled_run("figure8.toml", QUIET + ["study.stop_time=1"])
    b, _ = compiled_run("figure8.toml", QUIET + ["study.stop_time=1", "steering.command_delay=0.2", "gps.latency=0.05",
                                                  "command_link.samples=1", "tractor.m=800", "study.seed=5"])
    c, _ = compiled_run("figure8.toml", QUIET + ["study.stop_time=1", "tractor.model=rlfr"])
    assert a.key == b.key and a.key != c.key
    assert {a.key, c.key} <= {p.name for p in (cache / "compiled").iterdir()}


def test_a_library_of_another_shape_is_never_used(cache, monkeypatch):
    """A cache folder holding the library of another shape (a stale or copied cache) is refused:
    the library answers its own shape's key."""
    from agrobot.orchestrator.compiled import CompileError
    from agrobot.orchestrator.compiled import toolchain

    a, _ = compiled_run("figure8.toml", QUIET + ["study.stop_time=1"])
    wrong = "f" * 32
    (cache / "compiled" / wrong).mkdir()
    for name in ("libloop.so", "libloop.sha256"):       # a whole cached library (its digest too), of another shape
        (cache / "compiled" / wrong / name).write_bytes((cache / "compiled" / a.key / name).read_bytes())
    monkeypatch.setattr(toolchain, "shape_key", lambda *args: wrong)
    with pytest.raises(CompileError, match=f"answers another shape \\({a.key}\\)"):
        compiled_run("figure8.toml", QUIET + ["study.stop_time=1", "tractor.model=rlfr"])


def test_noise_is_deterministic_under_the_seed_and_has_the_configured_spread(cache):
    _, one = compiled_run("figure8.toml", ["study.stop_time=30"])
    _, two = compiled_run("figure8.toml", ["study.stop_time=30"])
    _, other = compiled_run("figure8.toml", ["study.stop_time=30", "study.seed=7"])
    np.testing.assert_array_equal(one.data, two.data)
    frame = one.to_frame()
    assert not np.array_equal(frame["gps.x"], other.to_frame()["gps.x"])
    lag = 0                                                        # the default latency is 0
    error = (frame["gps.x"] - frame["tractor.x_antenna"].shift(lag))[frame["t"] % 0.05 < 1e-9].to_numpy()
    assert np.std(error) == pytest.approx(0.02, rel=0.1)          # position_noise_std = 2 cm


def test_the_api_and_run_write_what_a_python_run_writes(cache, tmp_path):
    from agrobot.orchestrator.runner import run_study

    study = Study.load(shipped("figure8.toml"), ["study.stop_time=15"])
    python = run_study(study, tmp_path / "python", plots=False, engine="python")
    compiled = run_study(study, tmp_path / "compiled", plots=False, engine="compiled")
    assert sorted(p.name for p in python.files) == sorted(p.name for p in compiled.files)
    assert set(python.metrics) == set(compiled.metrics)
    import pyarrow.parquet as pq

    a, b = pq.read_table(tmp_path / "python" / "signals.parquet"), pq.read_table(tmp_path / "compiled" / "signals.parquet")
    assert a.column_names == b.column_names and a.num_rows == b.num_rows == 1501
    written = json.loads((tmp_path / "compiled" / "metrics.json").read_text())
    assert written["status"] == "completed" and written["engine"] == "compiled"
    assert json.loads((tmp_path / "python" / "metrics.json").read_text())["engine"] == "python"


def test_engine_compiled_on_a_study_it_cannot_take_exits_2_naming_the_components(cache, tmp_path, capsys):
    from agrobot.orchestrator.cli import main

    code = main(["run", str(shipped("figure8_pure_pursuit.toml")), "--out", str(tmp_path / "r"), "--engine", "compiled"])
    err = capsys.readouterr().err
    assert code == 2
    assert "figure8_pure_pursuit.toml: --engine compiled: components without a C core: tracker (type PurePursuit " \
           "has no C core)" in err
    assert not (tmp_path / "r").exists()


def test_auto_says_why_it_runs_in_python(cache, tmp_path, capsys):
    from agrobot.orchestrator.cli import main

    code = main(["run", str(shipped("figure8_pure_pursuit.toml")), "--out", str(tmp_path / "r"), "--engine", "auto",
                 "--no-plots", "--set", "study.stop_time=15"])
    assert code == 0
    assert "engine: python (auto: the compiled engine cannot take this study: components without a C core: tracker" \
           in capsys.readouterr().err


def test_a_missing_compiler_names_the_package(cache, monkeypatch, tmp_path):
    from agrobot.orchestrator.compiled import CompilerMissing, select_engine
    from agrobot.orchestrator.engine import Simulation as PythonEngine

    monkeypatch.setenv("CC", "")
    monkeypatch.setenv("PATH", str(tmp_path))
    system = system_of("figure8.toml", ["study.stop_time=1"])
    with pytest.raises(CompilerMissing, match=r"install the Debian package gcc \(apt-get install gcc\)"):
        select_engine(system, "compiled")
    factory, note = select_engine(system, "auto")
    assert factory is PythonEngine and "apt-get install gcc" in note


@pytest.mark.slow
def test_a_monte_carlo_on_a_dask_local_cluster_matches_the_draws_run_one_by_one(cache, tmp_path):
    from agrobot.orchestrator.sweep import SweepRun, _metrics_only, expand, point_study
    from agrobot.orchestrator.compiled import select_engine

    study = Study.load(shipped("robustness.toml"), ["sweep.samples=200", "study.stop_time=15"])
    table = SweepRun(study, tmp_path / "sweep", engine="compiled").run(2, scheduler="local", progress=False)
    assert len(table) == 200 and (table["status"] == "completed").all()
    assert not list((tmp_path / "sweep" / "points").glob("*/signals.*"))          # signals not kept
    for point in [expand(study)[i] for i in (0, 77, 199)]:
        one = point_study(study, point)
        system = build_system(resolve(one))
        alone = _metrics_only(one, system, select_engine(system, "compiled")[0])["metrics"]
        row = table[table["point"] == point.key].iloc[0]
        assert np.isfinite(alone["euclid_max_straight"])
        assert row["euclid_max_straight"] == pytest.approx(alone["euclid_max_straight"], rel=1e-12)
        assert row["steer_angle_rms"] == pytest.approx(alone["steer_angle_rms"], rel=1e-12)


def test_a_sweep_folder_keeps_its_engine(cache, tmp_path):
    from agrobot.orchestrator.study import StudyError
    from agrobot.orchestrator.sweep import SweepRun

    study = Study.load(shipped("robustness.toml"), ["sweep.samples=2", "study.stop_time=20"])
    SweepRun(study, tmp_path / "mc", engine="compiled").validate()
    with pytest.raises(StudyError, match="holds points run with --engine compiled"):
        SweepRun(study, tmp_path / "mc", engine="python").validate()


def test_a_large_sweep_checks_each_parameters_extremes_and_choices_first(tmp_path):
    from agrobot.orchestrator.sweep import SweepRun

    study = Study.load(shipped("robustness.toml"), ["sweep.samples=600"])
    run = SweepRun(study, tmp_path / "mc", engine="compiled")
    checked = run.checked_points()
    assert len(checked) < 40 and checked[0].index == 0
    for name in ("tractor.m", "reference.speed", "steering.command_delay"):
        values = [p.values[name] for p in run.points]
        assert min(values) in [p.values[name] for p in checked] and max(values) in [p.values[name] for p in checked]
    assert {p.values["tractor.model"] for p in checked} == {"bicycle", "rlf", "rlfr", "transfer_function"}
    assert {p.values["gps.latency"] for p in checked} == {0.0, 0.05, 0.1}


@pytest.mark.parametrize("study, engine, why", [
    ("figure8.toml", "compiled", "engine: compiled (auto: a C compiler was found and every component has a C core; "
                                 "--engine python for the reference engine)"),
    ("figure8_pure_pursuit.toml", "python", "engine: python (auto: the compiled engine cannot take this study: "
                                            "components without a C core: tracker (type PurePursuit has no C core)"),
])
def test_run_without_engine_is_auto_and_says_which_engine_ran_and_why(cache, tmp_path, capsys, study, engine, why):
    """No --engine: the compiled engine where every component has a C core and a compiler is found,
    the Python engine otherwise; stderr says which and why, metrics.json records the one that ran;
    ``sweep`` and the API share the default."""
    import inspect

    import agrobot
    from agrobot.orchestrator.cli import build_parser, main

    code = main(["run", str(shipped(study)), "--out", str(tmp_path / "r"), "--no-plots", "--no-progress",
                 "--set", "study.stop_time=15"])
    assert code == 0
    assert why in capsys.readouterr().err
    assert json.loads((tmp_path / "r" / "metrics.json").read_text())["engine"] == engine
    assert build_parser().parse_args(["sweep", "s.toml", "--out", "o"]).engine == "auto"
    assert {inspect.signature(f).parameters["engine"].default for f in (agrobot.run, agrobot.sweep)} == {"auto"}
