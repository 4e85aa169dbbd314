"""The API's doors for identify and sweep, and results loaded back: each command's files written
through the command line and through agrobot.api alike, and ``agrobot.load_result(folder)`` giving
back the typed result that wrote the folder (its data equal to the one in memory)."""
from __future__ import annotations

import json
import math
import os
import re
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import agrobot
import agrobot.api
from agrobot.orchestrator.errors import InputError
from agrobot.orchestrator.study import StudyError
from harness.truth_tractor import make_log
from tests.test_two_doors import same_files

SWEEP = "speed_sweep"
SHORT = {"study.stop_time": 20}


def _same_values(a: dict, b: dict) -> None:
    assert a.keys() == b.keys()
    for k in a:
        both_nan = isinstance(a[k], float) and math.isnan(a[k]) and math.isnan(b[k])
        assert both_nan or a[k] == b[k], k


def _log(tmp_path: Path) -> Path:
    path = tmp_path / "drive.csv"
    make_log(3, None, duration=60.0)[0].to_csv(path, index=False)
    return path


@pytest.mark.slow
def test_identify_writes_alike_through_both_doors_and_loads_back(cli, tmp_path):
    log = _log(tmp_path)
    proc = cli("identify", log, "--method", "driving", "--out", tmp_path / "cli", "--no-plots")
    assert proc.returncode == 0, proc.stderr
    found = agrobot.identify(log, method="driving", out=tmp_path / "api", plots=False)
    same_files(tmp_path / "cli", tmp_path / "api")
    loaded = agrobot.load_result(tmp_path / "api")
    assert isinstance(loaded, agrobot.Identification) and loaded.method == "driving"
    assert loaded.summary() == found.summary()


def test_a_run_loads_back_as_it_ran(tmp_path):
    ran = agrobot.run("figure8", SHORT, out=tmp_path / "run", plots=False)
    loaded = agrobot.load_result(tmp_path / "run")
    assert isinstance(loaded, agrobot.RunResult)
    pd.testing.assert_frame_equal(loaded.signals, ran.signals, check_dtype=False)
    _same_values(loaded.values, ran.values)
    assert loaded.failed == ran.failed and loaded.study.study.stop_time == 20


@pytest.mark.slow
def test_sweep_runs_on_every_core_by_default_and_alike_through_both_doors(cli, tmp_path, monkeypatch):
    seen = []
    from agrobot.orchestrator import sweep as sweep_module

    real = sweep_module.SweepRun.run
    monkeypatch.setattr(sweep_module.SweepRun, "run", lambda self, workers, *a, **k: seen.append(workers)
                        or real(self, workers, *a, **k))
    found = agrobot.sweep(SWEEP, SHORT, out=tmp_path / "api")
    assert seen == [os.cpu_count()]
    proc = cli("sweep", "studies/speed_sweep.toml", "--set", "study.stop_time=20", "--out", tmp_path / "cli",
               "--no-progress")
    assert proc.returncode == 0, proc.stderr
    api, cmd = (pd.read_parquet(tmp_path / side / "results.parquet") for side in ("api", "cli"))
    volatile = [c for c in api.columns if "wall" in c]
    pd.testing.assert_frame_equal(api.drop(columns=volatile), cmd.drop(columns=volatile), check_dtype=False)
    assert found.folder == tmp_path / "api"


def test_a_sweep_in_memory_saves_and_loads_back(tmp_path):
    found = agrobot.sweep(SWEEP, SHORT, workers=2, engine="compiled")
    folder = found.save(tmp_path / "kept")
    loaded = agrobot.load_result(folder)
    assert isinstance(loaded, agrobot.SweepResult) and loaded.engine == "compiled"
    pd.testing.assert_frame_equal(loaded.table, found.table, check_dtype=False)
    assert loaded.summary == found.summary


def test_a_folder_of_no_result_is_refused_by_name(tmp_path):
    (tmp_path / "notes").mkdir()
    (tmp_path / "notes" / "a.txt").write_text("x")
    with pytest.raises(InputError, match="holds none of run.json, sweep.json"):
        agrobot.load_result(tmp_path / "notes")
    with pytest.raises(InputError, match="no such folder"):
        agrobot.load_result(tmp_path / "absent")
    (tmp_path / "half").mkdir()
    (tmp_path / "half" / "run.json").write_text("{}")
    with pytest.raises(InputError, match="metrics.json: missing"):
        agrobot.load_result(tmp_path / "half")
    (tmp_path / "plan").mkdir()
    (tmp_path / "plan" / "plan.json").write_text("{}")
    with pytest.raises(InputError, match="a plan .plan.json. is not read back"):
        agrobot.load_result(tmp_path / "plan")


ROOT = Path(__file__).resolve().parents[1]


def same_archive(a: Path, b: Path) -> None:
    """The same members, and the same bytes in every member but the built binaries (and the
    FMUs nested in an SSP, whose text members are compared in turn)."""
    with zipfile.ZipFile(a) as left, zipfile.ZipFile(b) as right:
        assert left.namelist() == right.namelist()
        for name in left.namelist():
            if name.endswith(".fmu"):
                nested = [Path(a).with_name(f"{side}-{Path(name).name}") for side in ("a", "b")]
                nested[0].write_bytes(left.read(name))
                nested[1].write_bytes(right.read(name))
                same_archive(*nested)
            elif not name.startswith("binaries/"):
                assert left.read(name) == right.read(name), name


@pytest.mark.slow
def test_the_exports_write_alike_through_both_doors(cli, tmp_path):
    study = ROOT / "studies/figure8.toml"
    for command, export, name, options in (("export-controller", agrobot.api.export_controller, "c.fmu", {}),
                                           ("export-fmu", agrobot.api.export_fmu, "tractor.fmu",
                                            {"components": ["tractor", "steering"]})):
        flags = ["--components", "tractor,steering"] if options else []
        proc = cli(command, study, "--out", tmp_path / f"cli-{name}", *flags)
        assert proc.returncode == 0, proc.stderr
        made = export(study, out=tmp_path / f"api-{name}", **options)
        assert made.path == tmp_path / f"api-{name}" and str(made.path.name) in proc.stdout.replace("cli-", "api-")
        same_archive(tmp_path / f"cli-{name}", made.path)
        assert made.note == "" or made.note in proc.stderr
        assert not [p.name for p in tmp_path.iterdir() if p.name.startswith(".")]


@pytest.mark.slow
def test_ssp_export_writes_alike_through_both_doors(cli, tmp_path):
    study = ROOT / "studies/figure8.toml"
    proc = cli("export-ssp", study, "--out", tmp_path / "cli.ssp")
    assert proc.returncode == 0, proc.stderr
    same_archive(tmp_path / "cli.ssp", agrobot.api.export_ssp(study, out=tmp_path / "api.ssp").path)


def _ports_named_alike(folder: Path) -> None:
    """The NMEA server's port (0: the system's choice, another on every run) as PORT in events.log."""
    events = folder / "events.log"
    events.write_text(re.sub(r"127\.0\.0\.1:\d+", "127.0.0.1:PORT", events.read_text()))


@pytest.mark.slow
def test_the_emulator_writes_alike_through_both_doors_and_when_saved(cli, tmp_path):
    study, seconds = ROOT / "studies/tractor_emulator.toml", "6"      # its analysis needs more than 5 s
    proc = cli("emulate", study, "--nmea-port", "0", "--duration", seconds, "--out", tmp_path / "cli", "--no-progress")
    assert proc.returncode == 0, proc.stderr
    done = agrobot.api.emulate(study, 0, duration=6.0, out=tmp_path / "api", progress=False)
    assert done.exit_status == 0 and done.stopped is None and len(done.signals) == 601      # 6 s of 10 ms steps
    kept = agrobot.api.emulate(study, 0, duration=6.0, progress=False).save(tmp_path / "saved")
    for folder in (tmp_path / "cli", tmp_path / "api", kept):
        _ports_named_alike(folder)
    same_files(tmp_path / "cli", tmp_path / "api")
    same_files(tmp_path / "cli", kept)


def test_an_emulator_that_stops_says_how(tmp_path, monkeypatch):
    from agrobot.orchestrator.errors import Interrupted

    def interrupted(*args, **kwargs):
        raise Interrupted("at t = 2 s; the signals up to then are in OUT", 130)

    monkeypatch.setattr(agrobot.api, "run_study", interrupted)
    done = agrobot.api.emulate(ROOT / "studies/tractor_emulator.toml", 0, duration=6.0, progress=False)
    assert (done.exit_status, done.status) == (130, "interrupted")
    assert done.stopped == "emulator stopped at t = 2 s; the signals up to then are in OUT"
    with pytest.raises(StudyError, match="--nmea-port 70000: expected a TCP port"):
        agrobot.api.emulate(ROOT / "studies/tractor_emulator.toml", 70000)


def test_margins_load_back_with_their_study_as_analysed(tmp_path):
    found = agrobot.margins("figure8", {"tracker.k_c": 2.0}, out=tmp_path / "m", plots=False)
    loaded = agrobot.load_result(tmp_path / "m")
    assert isinstance(loaded, agrobot.LoopMargins)
    assert loaded.as_dict() == found.as_dict() and loaded.report() == found.report()
    assert loaded.analysis.study.components["tracker"].parameters["k_c"] == 2.0      # the --set kept
    assert loaded.delay_limit == found.delay_limit and math.isfinite(loaded.delay_limit)


def _lonlat_field(tmp_path: Path) -> Path:
    """A 200 m x 150 m field near 48 N 11 E with an AB line along its south edge, in longitude/latitude."""
    lat0, per_lat = 48.0, 1 / 111_320.0
    per_lon = per_lat / math.cos(math.radians(lat0))
    corners = [(0, 0), (200, 0), (200, 150), (0, 150), (0, 0)]
    ring = [[11.0 + x * per_lon, lat0 + y * per_lat] for x, y in corners]
    line = [[11.0 + x * per_lon, lat0 + 10 * per_lat] for x in (10, 190)]
    path = tmp_path / "geo.geojson"
    path.write_text(json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {"name": "north"}, "geometry": {"type": "Polygon", "coordinates": [ring]}},
        {"type": "Feature", "properties": {"name": "AB 1", "field": "north"},
         "geometry": {"type": "LineString", "coordinates": line}}]}))
    return path


def test_fields_load_back_with_their_geometry_in_the_local_frame(tmp_path):
    found = agrobot.api.fields(_lonlat_field(tmp_path), out=tmp_path / "f", plots=False)
    loaded = agrobot.load_result(tmp_path / "f")
    assert isinstance(loaded, agrobot.FieldsResult) and loaded.skipped == []
    assert loaded.summaries() == json.loads(json.dumps(found.summaries()))
    for mine, theirs in zip(loaded.fields, found.fields, strict=True):
        assert abs(mine.area_ha - 3.0) < 0.01             # 200 m x 150 m, as planted (a spherical degree)
        assert mine.boundary.hausdorff_distance(theirs.boundary) < 1e-6          # m
        assert [g.name for g in mine.lines] == [g.name for g in theirs.lines]
        for a, b in zip(mine.lines, theirs.lines):
            assert abs(a.length - 180.0) < 0.5 and np.allclose(a.points, b.points, atol=1e-6)


def test_a_diagnosis_an_export_and_a_converted_log_load_back(tmp_path):
    from tests.test_two_doors import _drive, _short_log

    found = agrobot.diagnose(_short_log(tmp_path), out=tmp_path / "d")
    loaded = agrobot.load_result(tmp_path / "d")
    assert isinstance(loaded, agrobot.Diagnosis) and loaded.verdict == "cannot decide"
    assert loaded.result == json.loads(found.to_json())
    archive = agrobot.ExportedFile(".fmu", b"PK archive bytes").save(tmp_path / "c.fmu")
    assert agrobot.load_result(archive).data == b"PK archive bytes"
    log = agrobot.convert(_drive(tmp_path), out=tmp_path / "drive.csv")
    back = agrobot.load_result(tmp_path / "drive.csv")
    assert isinstance(back, agrobot.Recording) and back.report == json.loads(json.dumps(log.report, default=float))
    pd.testing.assert_frame_equal(back.log, log.log, check_dtype=False, rtol=1e-8)
    with pytest.raises(InputError, match="neither an exported .fmu or .ssp nor a log convert wrote"):
        agrobot.load_result(_short_log(tmp_path))


def test_a_diagnosis_shows_its_verdict_in_a_line_not_its_evidence():
    residuals = {"yaw": {"rms": 0.1, "series": list(range(20_000))}}      # what a long log's evidence weighs
    found = agrobot.Diagnosis({"verdict": "actuator_delay", "effects": [{"id": "actuator_delay"}],
                               "residuals": residuals})
    assert repr(found) == "Diagnosis(verdict='actuator_delay', effects=['actuator_delay'], folder=None)"
    assert str(found) == "verdict: actuator_delay"
