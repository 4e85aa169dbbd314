"""The figure-8 as an SSP (export-ssp: one C FMU per component) run by foreign co-simulation
engines: libcosim (libcosimpy) reads the SSP itself; fmpy's SSP master and cofmupy run its FMUs and
connections. Each is compared with this project's own run of the same SSP, and libcosim's whole
160 s run is held to the paper's tracking bounds.

The foreign masters are Jacobi-type: an output reaches its reader one communication step later
(10 ms here), where this project's orchestrator orders declared feedthrough within the instant.
Over a feedthrough chain (reference -> tracker -> MPC -> command link -> steering) the commands
arrive up to four steps later, and the GPS noise generator differs from numpy's: the trajectories
agree within 10 cm over the first 20 s (measured: libcosim, fmpy 5 cm, cofmupy 8 cm; another GPS
seed alone moves the run by 3 cm), not to round-off."""
from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from agrobot.fmu_export.foreign_engines import cg_distance, cofmupy_run, fmpy_ssp_run, libcosim_run
from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.engine import Simulation
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study
from tests.commands import cli

ROOT = Path(__file__).resolve().parents[1]
H = 0.01


@pytest.fixture(scope="module")
def figure8_ssp(tmp_path_factory) -> Path:
    from agrobot.api import export_ssp

    out = tmp_path_factory.mktemp("ssp") / "figure8.ssp"
    return export_ssp(Study.load(ROOT / "studies/figure8.toml"), out=out).path


@pytest.fixture(scope="module")
def unpacked(figure8_ssp, tmp_path_factory) -> Path:
    import zipfile

    where = tmp_path_factory.mktemp("unpacked")
    with zipfile.ZipFile(figure8_ssp) as zf:
        zf.extractall(where)
    return where


@pytest.fixture(scope="module")
def own_run(figure8_ssp):
    study = Study.load(figure8_ssp)
    return study, Simulation(build_system(resolve(study))).run().to_frame()


def _position_difference(frame: pd.DataFrame, other: pd.DataFrame, until: float) -> float:
    distance, common = cg_distance(frame, other, until)
    assert common > until / H * 0.9
    return distance


def test_the_ssp_runs_in_this_orchestrator_as_the_study_does(own_run):
    """Same components, same seed: only the GPS noise generator differs (C xoshiro vs numpy), so
    the tracking statistics agree, and the run keeps the paper's bounds."""
    from agrobot.analysis.figure8 import metrics

    study, frame = own_run
    assert {"tractor.x_cg", "reference.x_ref", "ekf.heading", "speed_filter.vel_east"} <= set(frame.columns)
    m = metrics(frame, study)
    assert m["euclid_max_straight"] < 0.40 and m["euclid_max_curved"] < 0.60
    py_study = Study.load(ROOT / "studies/figure8.toml")
    py = metrics(Simulation(build_system(resolve(py_study))).run().to_frame(), py_study)
    assert abs(m["euclid_mean_straight"] - py["euclid_mean_straight"]) < 0.02
    assert abs(m["euclid_mean_curved"] - py["euclid_mean_curved"]) < 0.02


def test_libcosim_runs_the_figure8_ssp_within_the_paper_bounds(unpacked, own_run):
    from agrobot.analysis.figure8 import metrics

    study, ours = own_run
    frame = libcosim_run(unpacked, study.study.stop_time, H)
    m = metrics(frame, study)
    assert m["euclid_max_straight"] < 0.40 and m["euclid_max_curved"] < 0.60
    assert abs(m["euclid_mean_straight"] - metrics(ours, study)["euclid_mean_straight"]) < 0.05
    assert _position_difference(ours, frame, 20.0) < 0.10


def test_fmpy_ssp_master_runs_the_figure8_ssp(figure8_ssp, own_run):
    _, ours = own_run
    # fmpy's master reads each output after doStep: row k holds the state at t_k + h
    assert _position_difference(ours, fmpy_ssp_run(figure8_ssp, 20.0, H), 20.0) < 0.10


def test_cofmupy_runs_the_figure8_fmus(unpacked, own_run):
    _, ours = own_run
    assert _position_difference(ours, cofmupy_run(unpacked, 20.0, H), 20.0) < 0.10


@pytest.mark.parametrize("args, words", [
    (["export-ssp", "studies/figure8_hil.toml", "--out", "{tmp}/hil.ssp"],
     ["figure8_hil.toml", "no FMU form for", "watchdog (SafetyWatchdog)", "tractor (HardwareTractor)"]),
    (["export-ssp", "studies/figure8.toml", "--out", "{tmp}/x.fmu"], ["--out", "expected a path ending in .ssp"]),
    (["export-ssp", "studies/figure8.toml", "--out", "{tmp}/mf.ssp", "--set", "tractor.tyre_friction=0.8"],
     ["figure8.toml: components.tractor: tyre_friction = 0.8 has no C form"]),
    (["run", "{tmp}/bad.ssp", "--out", "{tmp}/out"], ["bad.ssp: not an SSP archive"]),
])
def test_bad_ssp_invocations_are_named_without_a_traceback(tmp_path, args, words):
    (tmp_path / "bad.ssp").write_text("hello")
    res = cli(*[a.format(tmp=tmp_path) for a in args])
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert all(w in res.stderr for w in words), res.stderr
    assert not list(tmp_path.glob("*.ssp.tmp")) and not (tmp_path / "hil.ssp").exists()
