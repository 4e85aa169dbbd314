"""Both doors, one implementation: each command run on the command line and through agrobot.api
on the same small input writes the same files with the same contents (wall times and the paths
of the inputs aside); every result's ``save`` follows the command line's output rule."""
from __future__ import annotations

import json
import math
import re
from pathlib import Path

import pandas as pd
import pytest

import agrobot
from agrobot import api
from agrobot.orchestrator.output import OutputError
from agrobot.orchestrator.study import StudyError
from agrobot.results import ExportedFile

SHORT = "study.stop_time=15"
VOLATILE = {"wall_time_s", "realtime", "log", "study_file", "source"}


def _content(path: Path):
    if path.suffix == ".json":
        return _stable(json.loads(path.read_text()))
    if path.suffix in (".csv", ".parquet"):
        return pd.read_parquet(path) if path.suffix == ".parquet" else pd.read_csv(path)
    if path.suffix == ".png":
        return "figure"
    return path.read_text()


def _stable(data):
    if isinstance(data, dict):
        return {k: _stable(v) for k, v in data.items() if k not in VOLATILE}
    if isinstance(data, list):
        return [_stable(v) for v in data]
    return data


def same_files(a: Path, b: Path) -> None:
    names = sorted(p.name for p in a.iterdir())
    assert names == sorted(p.name for p in b.iterdir())
    for name in names:
        left, right = _content(a / name), _content(b / name)
        if isinstance(left, pd.DataFrame):
            pd.testing.assert_frame_equal(left, right, check_dtype=False)
        else:
            assert left == right, name


def test_run_writes_alike_through_both_doors_and_when_saved(cli, tmp_path):
    proc = cli("run", "studies/figure8.toml", "--out", tmp_path / "cli", "--set", SHORT, "--no-plots")
    assert proc.returncode == 0, proc.stderr
    agrobot.run("figure8", {"study.stop_time": 15}, out=tmp_path / "api", plots=False)
    same_files(tmp_path / "cli", tmp_path / "api")
    saved = agrobot.run("figure8", {"study.stop_time": 15}).save(tmp_path / "saved", plots=False)
    same_files(tmp_path / "cli", saved)


def _drive(tmp_path: Path) -> Path:
    from harness.generated_recordings import write_nmea

    return write_nmea(tmp_path / "drive.nmea", 20.0)


def test_convert_writes_alike_through_both_doors(cli, tmp_path):
    nmea = _drive(tmp_path)
    (tmp_path / "cli").mkdir()
    proc = cli("convert", nmea, "--out", tmp_path / "cli" / "drive.csv")
    assert proc.returncode == 0, proc.stderr
    agrobot.convert(nmea, out=tmp_path / "api" / "drive.csv")
    same_files(tmp_path / "cli", tmp_path / "api")


def _short_log(tmp_path: Path) -> Path:
    log = tmp_path / "short.csv"
    log.write_text("t,delta_cmd,delta,v,yaw_rate,x,y\n0,0,0,1,0,0,0\n0.1,0,0,1,0,0.1,0\n")
    return log


def test_diagnose_writes_alike_through_both_doors(cli, tmp_path):
    log = _short_log(tmp_path)
    proc = cli("diagnose", log, "--out", tmp_path / "cli")
    assert proc.returncode == 2 and "cannot decide" in proc.stderr
    agrobot.diagnose(log, out=tmp_path / "api")
    same_files(tmp_path / "cli", tmp_path / "api")


def _field(tmp_path: Path) -> Path:
    field = tmp_path / "rect.geojson"
    ring = [[x, y] for x, y in [(0, 0), (200, 0), (200, 150), (0, 150), (0, 0)]]
    field.write_text(json.dumps({"type": "FeatureCollection", "features": [{"type": "Feature", "properties":
                     {"name": "rect"}, "geometry": {"type": "Polygon", "coordinates": [ring]}}]}))
    return field


@pytest.mark.slow     # 6 CPU s; the other doors stay in the fast tier
def test_plan_writes_alike_through_both_doors(cli, tmp_path):
    field = _field(tmp_path)
    proc = cli("plan", field, "--out", tmp_path / "cli", "--width", "6", "--angle", "0", "--headland-passes", "3")
    assert proc.returncode == 0, proc.stderr
    agrobot.plan(field, out=tmp_path / "api", working_width=6.0, driving_angle=0.0, headland_passes=3)
    same_files(tmp_path / "cli", tmp_path / "api")


def test_a_diagnosis_never_replaces_a_run(tmp_path):
    run = agrobot.run("figure8", {"study.stop_time": 15}, out=tmp_path / "out", plots=False)
    before = sorted(p.name for p in run.folder.iterdir())
    with pytest.raises(OutputError, match="not a diagnosis result"):
        agrobot.diagnose(_short_log(tmp_path), out=tmp_path / "out", overwrite=True)
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == before


def test_a_diagnosis_saved_twice_is_replaced_with_overwrite_only(tmp_path):
    found = agrobot.diagnose(_short_log(tmp_path))
    found.save(tmp_path / "d")
    with pytest.raises(OutputError, match="earlier diagnosis result"):
        found.save(tmp_path / "d")
    found.save(tmp_path / "d", overwrite=True)
    assert (tmp_path / "d" / "diagnosis.json").is_file()


def test_a_recording_is_never_saved_over_its_input(tmp_path):
    log = tmp_path / "drive.csv"
    agrobot.convert(_drive(tmp_path), out=log)
    text = log.read_text()
    with pytest.raises(OutputError, match="is the input"):
        agrobot.convert(log, out=log, overwrite=True)
    assert log.read_text() == text
    with pytest.raises(OutputError, match="exists"):
        agrobot.convert(tmp_path / "drive.nmea").save(log)


def test_a_saved_run_holds_run_json_and_events_log(tmp_path):
    folder = agrobot.run("figure8", {"study.stop_time": 15}).save(tmp_path / "run", plots=False)
    assert json.loads((folder / "run.json").read_text())["status"] == "completed"
    assert (folder / "events.log").is_file()


def test_margins_write_alike_through_both_doors_and_when_saved(cli, tmp_path):
    study = Path(__file__).resolve().parents[1] / "studies/figure8.toml"
    proc = cli("margins", study, "--out", tmp_path / "cli", "--no-plots")
    assert proc.returncode == 0, proc.stderr
    found = agrobot.margins(study, out=tmp_path / "api", plots=False)
    same_files(tmp_path / "cli", tmp_path / "api")
    assert found.report() in proc.stdout and "written to" in proc.stdout
    same_files(tmp_path / "cli", found.save(tmp_path / "saved", plots=False))
    with pytest.raises(OutputError, match="earlier margins result"):
        found.save(tmp_path / "saved")


def test_fields_write_alike_through_both_doors(cli, tmp_path):
    field = _field(tmp_path)
    proc = cli("fields", field, "--out", tmp_path / "cli")
    assert proc.returncode == 0, proc.stderr
    found = api.fields(field, out=tmp_path / "api")
    same_files(tmp_path / "cli", tmp_path / "api")
    assert [f.name for f in found.fields] == ["rect"] and "rect" in proc.stdout
    assert abs(found.fields[0].area_ha - 3.0) < 1e-9           # 200 m x 150 m
    with pytest.raises(OutputError, match="lies inside the input"):
        api.fields(tmp_path, out=tmp_path / "cli" / "inner")


def _track(tmp_path: Path) -> Path:
    """A lat/lon table of four 100 m passes 6 m apart joined by turns (1 fix a second)."""
    lat0, rows, t = 48.0, ["t,lat,lon"], 0
    per_lat, per_lon = 1 / 111_320.0, 1 / (111_320.0 * math.cos(math.radians(lat0)))
    for k in range(4):
        xs = [2.0 * i for i in range(51)][:: -1 if k % 2 else 1]
        turn = [(xs[-1] + (2.0 if k % 2 == 0 else -2.0) * math.sin(math.pi * a / 5), 6.0 * (k + a / 5))
                for a in range(1, 5)]
        for x, y in [(x, 6.0 * k) for x in xs] + turn:
            rows.append(f"{t},{lat0 + y * per_lat:.9f},{11.0 + x * per_lon:.9f}")
            t += 1
    path = tmp_path / "track.csv"
    path.write_text("\n".join(rows) + "\n")
    return path


def test_a_field_from_a_track_alike_through_both_doors(cli, tmp_path):
    track, columns = _track(tmp_path), ["track.lat[deg]", "track.lon[deg]"]
    proc = cli("fields", track, "--from-track", "--width", "6", "--signal", f"lat={columns[0]}", "--signal",
               f"lon={columns[1]}", "--time", "t[s]", "--out", tmp_path / "cli", "--no-plots")
    assert proc.returncode == 0, proc.stderr
    found = api.fields(track, from_track=True, width=6.0, signals=[f"lat={columns[0]}", f"lon={columns[1]}"],
                       time="t[s]", out=tmp_path / "api", plots=False)
    same_files(tmp_path / "cli", tmp_path / "api")
    assert found.track in proc.stdout and "4 straight passes" in found.track
    assert len(found.fields[0].lines) == 4


def test_an_exported_file_is_written_aside_and_refused_over_a_file_or_an_input(tmp_path):
    made = ExportedFile(".fmu", b"PK archive bytes", inputs=[tmp_path / "study.toml"])
    stale = tmp_path / ".c.fmu.tmp"                  # another writer's temporary file: never ours
    stale.write_text("someone else's")
    assert made.save(tmp_path / "c.fmu").read_bytes() == b"PK archive bytes"
    assert stale.read_text() == "someone else's"
    assert sorted(p.name for p in tmp_path.iterdir()) == [".c.fmu.tmp", "c.fmu"]
    with pytest.raises(OutputError, match="exists; pass --overwrite"):
        ExportedFile(".fmu", b"other").save(tmp_path / "c.fmu")
    assert made.save(tmp_path / "c.fmu", overwrite=True) == tmp_path / "c.fmu"
    with pytest.raises(OutputError, match="expected a path ending in .fmu"):
        made.save(tmp_path / "c.ssp")
    (tmp_path / "study.toml").write_text("x")
    with pytest.raises(OutputError, match="is the input"):
        ExportedFile(".fmu", b"x", inputs=[tmp_path / "s.fmu"]).save(tmp_path / "s.fmu", overwrite=True)


def test_an_export_refuses_its_output_before_it_builds(tmp_path, monkeypatch):
    import agrobot.fmu_export.controller as controller

    monkeypatch.setattr(controller, "export_controller", lambda *a: pytest.fail("built before the check"))
    (tmp_path / "c.fmu").write_text("earlier")
    with pytest.raises(OutputError, match="exists"):
        api.export_controller("figure8", out=tmp_path / "c.fmu")
    assert (tmp_path / "c.fmu").read_text() == "earlier"


def test_tune_writes_alike_through_both_doors_and_when_saved(cli, tmp_path):
    study = Path(__file__).resolve().parents[1] / "studies/figure8.toml"
    coarse = ["--grid", "0.25", "--no-simulation"]
    proc = cli("tune", study, "--out", tmp_path / "cli.toml", *coarse)
    assert proc.returncode == 0, proc.stderr
    found = api.tune(study, out=tmp_path / "api.toml", grid=0.25, simulate=False)
    assert (tmp_path / "api.toml").read_text() == (tmp_path / "cli.toml").read_text()
    assert found.comparison() in proc.stdout and found.checked == []
    assert found.save(tmp_path / "saved.toml").read_text() == found.text
    tuned = agrobot.load(tmp_path / "api.toml")                  # the file extends the study, with the gains set
    for key, value in found.values.items():
        component, parameter = key.split(".", 1)
        assert tuned.components[component].parameters[parameter] == value
    with pytest.raises(OutputError, match="exists"):
        found.save(tmp_path / "cli.toml")
    with pytest.raises(OutputError, match="is the input"):
        api.tune(tmp_path / "api.toml", out=tmp_path / "api.toml", overwrite=True, simulate=False)


def test_tune_refuses_its_numbers_and_output_before_it_computes(tmp_path, monkeypatch):
    import agrobot.analysis.tune as tune

    monkeypatch.setattr(tune, "propose", lambda *a, **k: pytest.fail("computed before the checks"))
    for options, words in (({"grid": 0}, "--grid 0: expected a number in (0, 4]"),
                           ({"delay_margin": -1.0}, "--delay-margin -1: expected a number >= 0"),
                           ({"duration": 0.0}, "--duration 0: expected a positive")):
        with pytest.raises(StudyError, match=re.escape(words)):
            api.tune("figure8", out=tmp_path / "t.toml", **options)
    with pytest.raises(OutputError, match=".toml"):
        api.tune("figure8", out=tmp_path / "t.txt")
    assert list(tmp_path.iterdir()) == []
