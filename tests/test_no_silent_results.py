"""No silent wrong result: an input nothing drives is refused or said; a built system run twice
gives the same signals bit for bit; every nan and FAIL of a run's table says why; units travel
with the signals and the logs."""
from __future__ import annotations

import math
import types
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from agrobot.results import judged_metrics

from agrobot.components.kinematic_tracker import KinematicTracker
from agrobot.components.tractor_yaw_plant import TractorYawPlant
from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.engine import Simulation
from agrobot.orchestrator.key_figures import bounds, run_table
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.atomic_files import read_table, write_frame, write_table
from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.signal_table import SignalTable
from agrobot.orchestrator.study import Study, StudyError
from agrobot.studies import shipped
from tests.commands import cli

ROOT = Path(__file__).resolve().parents[1]
CUT = "reference.x_ref -> tracker.x_ref"


def _figure8(*overrides: str) -> Study:
    return Study.load(shipped("figure8.toml"), list(overrides))


# --- 1. unconnected inputs ---------------------------------------------------------------------

def test_a_deleted_connection_is_refused_naming_the_input_and_the_three_ways_to_drive_it():
    cut = _figure8().with_connections(remove=[CUT])
    with pytest.raises(StudyError) as err:
        build_system(resolve(cut))
    message = str(err.value)
    assert "tracker.x_ref" in message and "allow_unconnected" in message and "[components.tracker.inputs]" in message
    assert "\n" not in message
    # allowed by the study: it holds the start value the tracker declares
    allowed = build_system(resolve(cut.with_values({"study.allow_unconnected": ["tracker.x_ref"]})))
    held = {port: (value, why) for port, value, _, why in allowed.held_inputs}
    assert held["tracker.x_ref"] == (KinematicTracker.declared("input")["x_ref"].start, "study.allow_unconnected")
    # declared optional by the component: held without a word from the study
    assert KinematicTracker.declared("input")["lateral_velocity"].optional
    assert "declared optional" in held["tracker.lateral_velocity"][1]
    # a constant drives it too
    build_system(resolve(cut.with_values({"tracker.inputs.x_ref": 1.0})))
    with pytest.raises(StudyError, match=r"study.allow_unconnected\[0\].*no input 'x_rf'.*x_ref"):
        build_system(resolve(cut.with_values({"study.allow_unconnected": ["tracker.x_rf"]})))


def test_the_cli_refuses_a_deleted_connection_in_one_line_and_says_the_held_inputs_once(tmp_path):
    study = tmp_path / "cut.toml"
    study.write_text(f'extends = "{shipped("figure8.toml")}"\nconnections_remove = ["{CUT}"]\n'
                     '[study]\nstop_time = 0.5\n')
    done = cli("run", str(study), "--out", str(tmp_path / "out"), timeout=120)
    assert done.returncode == 2, done.stderr
    assert "tracker.x_ref" in done.stderr and "Traceback" not in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert not (tmp_path / "out").exists()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import contextlib
        import io

        def notes(study: Study) -> list[str]:
            said = io.StringIO()
            with contextlib.redirect_stderr(said):
                run_study(study.with_values({"study.analysis": None}), None, plots=False)
            return [line for line in said.getvalue().splitlines() if line.startswith("note: ")]

        # the shipped figure-8 names the held input in study.allow_unconnected: recorded, not said
        shipped_study = _figure8("study.stop_time=0.2")
        assert shipped_study.study.allow_unconnected == ["tracker.lateral_velocity"] and notes(shipped_study) == []
        # a study that does not name it is told once
        said = notes(shipped_study.with_values({"study.allow_unconnected": []}))
    assert said == ["note: tracker.lateral_velocity is unconnected: it holds 0 m/s for the whole run "
                    "(declared optional: " + KinematicTracker.declared("input")["lateral_velocity"].description + ")"]


# --- 2. a run is a function of its study and seed -----------------------------------------------

# Every shipped study but the HIL one (it needs the tractor emulator listening on a socket). The
# fast ones together hold every component type of the others; the others are marked slow.
SLOW = {"field_coverage.toml", "field_plot_mounted.toml", "field_plot_pure_pursuit.toml", "field_plot_stanley.toml",
        "field_speed_sweep.toml", "robustness.toml", "robustness_pure_pursuit.toml", "robustness_stanley.toml",
        "figure8_pure_pursuit.toml", "figure8_stanley.toml", "speed_sweep.toml", "tractor_emulator.toml",
        "figure8_rlfr.toml"}
STUDIES = sorted(p.name for p in shipped().glob("*.toml") if p.name != "figure8_hil.toml")


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in SLOW else n for n in STUDIES])
def test_a_built_system_run_twice_gives_every_signal_bit_for_bit(name):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        study = Study.load(shipped(name))
        study = study.with_values({"study.stop_time": min(study.study.stop_time, study.study.start_time + 1.0)})
        system = build_system(resolve(study))
        first, second = Simulation(system).run(), Simulation(system).run()
    assert first.columns == second.columns and first.data.shape == second.data.shape
    assert first.data.tobytes() == second.data.tobytes(), \
        [c for i, c in enumerate(["t"] + first.columns) if first.data[:, i].tobytes() != second.data[:, i].tobytes()]


def test_a_noisy_sensor_restarts_its_stream_and_its_parameters():
    study = _figure8("study.stop_time=0.5")
    system = build_system(resolve(study))
    gps = system.nodes["gps"].component
    first = Simulation(system).run().to_frame()["gps.x"].to_numpy()
    gps.p["position_noise_std"] = 5.0            # changed after a run: the next run starts as built
    gps.rng.standard_normal(1000)
    again = Simulation(system).run().to_frame()["gps.x"].to_numpy()
    fresh = Simulation(build_system(resolve(study))).run().to_frame()["gps.x"].to_numpy()
    assert np.array_equal(first, again) and np.array_equal(first, fresh)
    assert np.std(np.diff(first)) > 0          # noisy: the comparison is not between constants


# --- 5. every nan and FAIL says why -----------------------------------------------------------

def _line(summary: str, figure: str) -> str:
    return next(line for line in summary.splitlines() if line.startswith(figure + " "))


def test_a_short_figure8_says_why_it_has_no_straight_and_how_long_to_run():
    from agrobot.analysis import figure8

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        long = run_study(_figure8("study.stop_time=36"), None, plots=False)
    frame = long.frame
    t, segment = frame["t"].to_numpy(), frame["reference.segment"].to_numpy()
    settled = long.metrics["metrics_from_time_s"]
    # the truth, from the recorded reference: the first straight sample after the settling
    first = float(t[(t >= settled) & (segment < 0.5)][0])
    end = math.floor(first) - 1.0
    short = frame[frame["t"] <= end]
    values = {**figure8.metrics(short, long_study := _figure8(f"study.stop_time={end:g}")), "sim_time_s": end}
    table, failed = run_table(values, figure8, bounds(figure8), long_study)
    line = _line(table, "euclid_max_straight")
    # too short to reach a straight: shown, neither passed nor failed
    assert "nan" in line and "not judged" in line and "FAIL" not in line and not failed
    assert (f"no straight after the {settled:.0f} s settling (the run ends at {end:.0f} s): "
            f"run at least {math.ceil(first + 1.0)} s") in line, (line, first)
    assert "run at least" in _line(table, "euclid_mean_straight")
    assert judged_metrics(values, long_study)["euclid_max_straight"].passed is None
    # a run as long as it says judges a straight
    assert math.isfinite(long.metrics["euclid_max_straight"]) and math.ceil(first + 1.0) <= 36
    assert "nan" not in _line(long.summary, "euclid_max_straight")


def test_coverage_bounds_follow_what_was_run():
    from agrobot.analysis import field_coverage

    values = {"field_coverage_share": 0.011, "coverage_share": 0.011, "overlap_share": 0.0, "boundary_crossings": 0.0,
              "implement_xte_p95_m": 0.014, "swaths_planned": 2.0, "route_done_share": 1.0,
              "pass_to_pass_p95_m": math.nan}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        section = Study.load(shipped("field_line_test.toml"))
        whole = Study.load(shipped("field_coverage.toml"))
    judged = bounds(field_coverage)
    table, failed = run_table(values, field_coverage, judged, section)
    assert not failed
    assert "not judged  bounds for the whole field; this run plans 2 swaths (max_swaths = 2)" in _line(table, "coverage_share")
    assert "no two adjacent passes" in _line(table, "pass_to_pass_p95_m")
    # the whole field's plan, its route done: the same shares fail, each with its reason
    table, failed = run_table(values, field_coverage, judged, whole)
    assert sorted(f.split(" ")[0] for f in failed) == ["coverage_share", "field_coverage_share"]
    assert "0.979 below the bound" in _line(table, "coverage_share")
    # ended before its route did
    _, failed = run_table({**values, "route_done_share": 0.4}, field_coverage, judged, whole)
    assert not failed
    # a number on the wrong side of its bound says how far, not why a figure would be missing
    table, failed = run_table({**values, "implement_xte_p95_m": 0.0595}, field_coverage, judged, whole)
    line = _line(table, "implement_xte_p95_m")
    assert "FAIL" in line and "0.0095 m above the bound" in line and "never on a swath" not in line, line
    table, failed = run_table({**values, "implement_xte_p95_m": math.nan}, field_coverage, judged, whole)
    assert "the implement was never on a swath in this run" in _line(table, "implement_xte_p95_m")


def test_a_fail_or_nan_without_the_analysis_reason_still_says_why():
    analysis = types.SimpleNamespace(METRICS={"a": ("m", "< 0.4"), "b": ("m", None)})
    table, failed = run_table({"a": 0.5, "b": math.nan}, analysis, bounds(analysis))
    assert _line(table, "a").endswith("0.1 m above the bound") and failed
    assert _line(table, "b").endswith("not computed (the analysis says no more)")


# --- 7. units travel with the data -------------------------------------------------------------

@pytest.mark.parametrize("fmt", ["parquet", "csv"])
def test_units_go_with_the_signals_into_the_file_and_back(tmp_path, fmt):
    study = _figure8("study.stop_time=0.5", f"study.signals_format={fmt}").with_values({"study.analysis": None})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        frame = Simulation(build_system(resolve(study))).run().to_frame()
        result = run_study(study, tmp_path / "out", plots=False, progress=False)
    plant = TractorYawPlant.declared("output")
    expected = {"t": "s", "tractor.heading": "rad", "tractor.yaw_rate": "rad/s", "tractor.x_cg": "m"}
    assert plant["heading"].unit == "rad" and plant["yaw_rate"].unit == "rad/s"
    assert set(frame.attrs["units"]) == set(frame.columns)
    assert {k: frame.attrs["units"][k] for k in expected} == expected
    table = SignalTable(tmp_path / "out" / f"signals.{fmt}")
    assert table.units == frame.attrs["units"]
    assert table["tractor.yaw_rate"].attrs["unit"] == "rad/s"
    assert table.to_pandas().attrs["units"] == frame.attrs["units"]
    assert isinstance(result.frame, SignalTable)
    back = read_table(write_table(tmp_path / "copy", frame, fmt))
    assert back.attrs["units"] == frame.attrs["units"]


def test_a_log_keeps_its_units_and_a_log_without_them_gets_the_canonical_ones(tmp_path):
    from agrobot.measurements.log import read_log

    t = np.arange(0, 10, 0.05)
    log = pd.DataFrame({"t": t, "delta": 0.01 * np.sin(t), "v": 2.0 + 0 * t, "yaw_rate": 0.02 * np.sin(t),
                        "fix_quality": 4.0 + 0 * t})
    log.attrs["units"] = {"t": "s", "delta": "rad", "v": "m/s", "yaw_rate": "rad/s", "fix_quality": "1"}
    for suffix in (".parquet", ".csv"):
        back = read_log(write_frame(tmp_path / f"log{suffix}", log), required=("t",))
        assert back.attrs["units"] == log.attrs["units"], suffix
    plain = tmp_path / "plain.csv"
    log.to_csv(plain, index=False)
    assert read_log(plain, required=("t",)).attrs["units"] == {"t": "s", "delta": "rad", "v": "m/s", "yaw_rate": "rad/s"}
