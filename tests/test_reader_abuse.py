"""The readers under abuse: files that are not files, clocks that step back, impossible or jumping
positions, padding, damaged TaskData, parcels of one name, swapped coordinates, deep nesting,
bad lines among good ones. Each input is generated small (harness/generated_recordings.py) from known
values, so the tests compare what the readers return with what was written; the large cases
(a million NMEA lines, a day-long log, a long CAN log) are in benchmarks/reader_limits.py."""
from __future__ import annotations

import json
import math
import os
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from harness.generated_recordings import LAT0, write_candump, write_nmea, write_timelog
from tests.commands import cli, refused

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"
NMEA = DATA / "nmea_gpsd_testlogs"
ISOXML = DATA / "isoxml_dev4ag_timelogs"


def converted(proc, *words):
    assert proc.returncode == 0, proc.stderr
    for w in words:
        assert w in proc.stdout, (w, proc.stdout)
    return proc.stdout


def steps_m(log: pd.DataFrame) -> np.ndarray:
    return np.hypot(np.diff(log["x"]), np.diff(log["y"]))


# --- only regular files, a size limit that names itself ------------------------------------------------------
@pytest.mark.slow
def test_devices_links_loops_and_sizes_are_refused_before_anything_is_read(tmp_path):
    for name in ("zero.geojson", "zero.nmea", "zero.log", "zero.bag"):
        (tmp_path / name).symlink_to("/dev/zero")
    for name in ("zero.nmea", "zero.log", "zero.bag"):
        refused(cli("convert", tmp_path / name, "--out", tmp_path / "a.csv", timeout=60),
                "a character device", "/dev/zero", "not a regular file")
    refused(cli("fields", tmp_path / "zero.geojson", timeout=60), "a character device", "not a regular file")
    (tmp_path / "loop.nmea").symlink_to(tmp_path / "loop.nmea")
    refused(cli("convert", tmp_path / "loop.nmea", "--out", tmp_path / "a.csv", timeout=60), "symbolic link loop")
    assert not (tmp_path / "a.csv").exists()
    # a folder of fields names the device and the loop and reads the rest
    (tmp_path / "loop.geojson").symlink_to(tmp_path / "loop.geojson")
    shutil.copy(DATA / "fields2cover_data" / "test.json", tmp_path / "field.json")
    proc = cli("fields", tmp_path, timeout=60)
    assert proc.returncode == 0 and "symbolic link loop" in proc.stdout and "character device" in proc.stdout
    # the size limit names itself and the option that raises it
    log = write_nmea(tmp_path / "drive.nmea", 30.0)
    size = log.stat().st_size
    assert size > 4096
    refused(cli("convert", log, "--out", tmp_path / "b.csv", "--max-file-size", "4K"),
            "above the 4 kB limit", "--max-file-size")
    converted(cli("convert", log, "--out", tmp_path / "b.csv", "--max-file-size", f"{size}"))
    refused(cli("convert", log, "--out", tmp_path / "b.csv", "--overwrite", "--max-file-size", "lots"), "500M")


# --- NMEA -----------------------------------------------------------------------------------------------------
def _pynmeagps_fixes(path: Path) -> list[tuple[float, float, float, int]]:
    """(time of day, lat, lon, quality) of every GGA with a valid checksum and a fix, by pynmeagps:
    the second method the streamed reader is compared with."""
    from pynmeagps import VALCKSUM, NMEAReader

    out = []
    for line in path.read_bytes().decode("ascii", "replace").splitlines():
        if "$" not in line or line.lstrip().startswith("#"):
            continue
        sentence = line[line.index("$"):].strip()
        if sentence[3:6] != "GGA":
            continue
        try:
            msg = NMEAReader.parse(sentence.encode() + b"\r\n", validate=VALCKSUM)
        except Exception:              # noqa: BLE001 - pynmeagps refuses a bad sentence: so must the reader
            continue
        if msg.time != "" and msg.quality not in ("", 0) and msg.lat != "":
            t = msg.time
            out.append((t.hour * 3600 + t.minute * 60 + t.second + t.microsecond * 1e-6, float(msg.lat),
                        float(msg.lon), int(msg.quality)))
    return out


def test_the_streamed_nmea_reader_agrees_with_pynmeagps_on_every_real_capture():
    from agrobot.measurements.raw_nmea import read_nmea_file

    for path in sorted(NMEA.glob("*.log")):
        rec = read_nmea_file(path)
        fixes = rec.epochs[rec.epochs["quality"] > 0]
        tod = np.mod(fixes["utc"].to_numpy(), 86400.0)
        ref = {round(t, 3): (lat, lon, q) for t, lat, lon, q in _pynmeagps_fixes(path)}
        masked = sum(b["masked"] for b in rec.breaks)
        assert len(ref) - masked <= len(fixes) <= len(ref), path.name
        for t, lat, lon, q in zip(tod, fixes["lat"], fixes["lon"], fixes["quality"]):
            assert round(t, 3) in ref, (path.name, t)
            assert ref[round(t, 3)][0] == pytest.approx(lat, abs=1e-9) and ref[round(t, 3)][1] == pytest.approx(lon, abs=1e-9)
            assert ref[round(t, 3)][2] == q


def test_a_receiver_clock_that_steps_back_splits_the_run_and_is_named(tmp_path):
    log = write_nmea(tmp_path / "step.nmea", 150.0, step_back=(60.0, 30.0))
    out = converted(cli("convert", log, "--out", tmp_path / "s.csv", "--all-runs"),
                    "the clock steps back 30 s", "300 record(s)", "line 1201", "split")
    assert "gaps: 0" not in out
    runs = sorted(tmp_path.glob("s_run*.csv"))
    assert len(runs) == 2
    for path in runs:                   # no splice: 2 m/s at 10 Hz is 0.2 m a step
        assert steps_m(pd.read_csv(path)).max() < 0.25
    report = json.loads((tmp_path / "s_run01.import.json").read_text())
    assert any("split" in g["stream"] for g in report["gaps"])


def test_a_receiver_clock_that_steps_forward_is_a_named_gap_between_two_runs(tmp_path):
    log = write_nmea(tmp_path / "ahead.nmea", 150.0, step_back=(60.0, -30.0))    # 60 s on, the clock reads 30 s more
    converted(cli("convert", log, "--out", tmp_path / "a.csv", "--all-runs"),
              "gaps: 1: gnss 59.90-90.00 s", "runs: 1: 0.0-59.8 s", "2: 90.0-179.9 s")
    first, second = (pd.read_csv(tmp_path / f"a_run0{k}.csv") for k in (1, 2))
    assert (len(first), len(second)) == (599, 900)       # 60 s and 90 s at 10 Hz, the last sample of run 1 at the grid's end
    for run in (first, second):                             # no splice: 2 m/s at 10 Hz is 0.2 m a step
        assert steps_m(run).max() < 0.25


def test_binary_bytes_between_and_before_sentences_are_skipped_and_counted(tmp_path):
    clean = write_nmea(tmp_path / "clean.nmea", 40.0)
    ubx = bytes([0xB5, 0x62, 0x01, 0x07, 0x5C, 0x00, 0xE8, 0x03, 0x00, 0x00, 0x0A, 0x1B])
    lines = clean.read_bytes().split(b"\n")
    dirty = []
    for i, line in enumerate(lines):
        if i % 40 == 5:
            dirty.append(ubx * 3)                       # a binary message on lines of its own
        dirty.append(ubx + line if i % 40 == 9 else line)   # and one glued before a sentence
    (tmp_path / "dirty").mkdir()
    (tmp_path / "dirty" / "gps.nmea").write_bytes(b"\n".join(dirty))
    out = converted(cli("convert", tmp_path / "dirty", "--out", tmp_path / "d.csv"),
                    "skipped: binary data (UBX", "the first at line 6")
    assert "binary data before '$' (UBX or another binary protocol) removed" in out
    converted(cli("convert", clean, "--out", tmp_path / "c.csv"))
    a, b = pd.read_csv(tmp_path / "d.csv"), pd.read_csv(tmp_path / "c.csv")
    assert len(a) == len(b) and np.allclose(a["x"], b["x"]) and np.allclose(a["y"], b["y"])


def test_a_bad_host_stamp_is_a_counted_line_and_nothing_usable_names_the_format(tmp_path):
    log = write_nmea(tmp_path / "drive.nmea", 30.0)
    lines = log.read_text().splitlines()
    lines[20] = "yesterday " + lines[20]
    (tmp_path / "one").mkdir()
    (tmp_path / "one" / "gps.nmea").write_text("\n".join(lines) + "\n")
    converted(cli("convert", tmp_path / "one", "--out", tmp_path / "o.csv"), "line 21", "neither UNIX seconds")
    (tmp_path / "junk.nmea").write_text("hello\n$GPGGA,nonsense*00\n")
    refused(cli("convert", tmp_path / "junk.nmea", "--out", tmp_path / "j.csv"),
            "no GGA sentence", "$..GGA,hhmmss.ss", "bad checksum first at line 2")


# --- ISO 11783-10 time logs -------------------------------------------------------------------------------------
@pytest.mark.parametrize("fault, words", [
    ({"lat_at": {100: 200.0}}, ["1 fix(es) with impossible coordinates", "latitude 200", "at 100.00 s", "masked"]),
    ({"lat_at": {150: LAT0 + 26.0}}, ["1 position spike(s)", "2.89e+06 m/s", "at 150.00 s", "masked"]),
    ({"step_back": (200, 40)}, ["the clock steps back 40 s at record 200", "40 record(s)", "split"]),
    ({"padding": 100}, ["100 record(s) dated 1980-01-01", "records 300-399", "masked"]),
])
def test_a_time_logs_faults_are_named_with_counts_and_times_and_never_spliced(tmp_path, fault, words):
    folder = write_timelog(tmp_path / "task", 300, **fault)
    converted(cli("convert", folder, "--out", tmp_path / "t.csv", "--all-runs"), *words)
    for path in sorted(tmp_path.glob("t_run*.csv")):
        log = pd.read_csv(path)
        assert np.isfinite(log[["x", "y"]].to_numpy()).all()
        assert steps_m(log).max() < 2.5 and log["track_speed"].max() < 2.5     # 2 m/s at 1 Hz, nothing else
        assert log["t"].iloc[-1] >= 9.0


def test_a_damaged_or_duplicated_taskdata_is_named(tmp_path):
    folder = write_timelog(tmp_path / "task", 120)
    (folder / "TASKDATA.XML").write_bytes(np.random.default_rng(3).integers(0, 256, 2000, dtype=np.uint8).tobytes())
    converted(cli("convert", folder, "--out", tmp_path / "a.csv"), "TASKDATA.XML: not readable XML", "damaged")
    (folder / "TASKDATA.XML").unlink()
    write_timelog(folder, 120, name="TLG00002")
    converted(cli("convert", folder, "--out", tmp_path / "b.csv"), "TLG00002 repeats TLG00001", "120 records",
              "duplicated TaskData")
    twice = folder / "TLG00001.bin"
    twice.write_bytes(twice.read_bytes() * 2)        # the same records written twice into one log
    out = converted(cli("convert", folder / "TLG00001.xml", "--out", tmp_path / "c.csv"),
                    "120 record(s) repeat earlier ones", "dropped")
    assert "clock steps back" not in out
    assert len(pd.read_csv(tmp_path / "c.csv")) == 120


# --- fields -----------------------------------------------------------------------------------------------------
def _square(x: float, y: float, side: float = 0.001) -> list:
    return [[x, y], [x + side, y], [x + side, y + side], [x, y + side], [x, y]]


def test_parcels_of_one_feature_and_repeated_names_get_distinct_names(tmp_path):
    from agrobot.fields import read_fields

    parcels = {"type": "Feature", "properties": {"name": "f0"},
               "geometry": {"type": "MultiPolygon", "coordinates": [[_square(7 + 0.002 * i, 51)] for i in range(50)]}}
    twin = {"type": "Feature", "properties": {"name": "home"}, "geometry": {"type": "Polygon", "coordinates": [_square(7, 52)]}}
    path = tmp_path / "farm.geojson"
    path.write_text(json.dumps({"type": "FeatureCollection", "features": [parcels, twin, twin]}))
    fields = read_fields(path)
    names = [f.name for f in fields]
    assert len(fields) == 52 and len(set(names)) == 52
    assert names[:3] == ["f0_1", "f0_2", "f0_3"] and names[50:] == ["home", "home_2"]
    # the 50 parcels are 50 different places, in the order written
    xs = [f.to_geodetic(np.asarray(f.boundary.exterior.coords))[:, 0].min() for f in fields[:50]]
    assert np.allclose(xs, 7 + 0.002 * np.arange(50), atol=1e-9)


def test_swapped_coordinates_and_coordinates_beyond_the_earth_are_refused_by_value(tmp_path):
    swapped = tmp_path / "swapped.geojson"
    ring = [[45.0 + p[1] - 51, 95.0 + p[0]] for p in _square(0, 51)]        # a field at 95 E, 45 N written lat, lon
    swapped.write_text(json.dumps({"type": "Polygon", "coordinates": [ring]}))
    refused(cli("fields", swapped), "latitude 95", "swapped", "longitude first")
    huge = tmp_path / "huge.geojson"
    huge.write_text(json.dumps({"type": "Polygon", "coordinates": [[[0, 0], [1e30, 0], [1e30, 1e30], [0, 0]]]}))
    refused(cli("fields", huge), "coordinate 1e+30", "beyond the Earth")
    csv = tmp_path / "plots.csv"
    csv.write_text("name,x1,y1,x2,y2,x3,y3\nA,0,0,100,0,100,1e300\n")
    refused(cli("fields", csv), "coordinate 1e+300")


@pytest.mark.slow
def test_bad_geometry_text_area_deep_nesting_and_agopengps_without_field_txt_are_named(tmp_path):
    cases = {"ragged": {"type": "Polygon", "coordinates": [[[0, 0], [1], [1, 1], [0, 0]]]},
             "text": {"type": "Polygon", "coordinates": [[["a", "b"], [1, 0], [1, 1], [0, 0]]]},
             "null": {"type": "Feature", "geometry": None, "properties": {}},
             "flat": {"type": "MultiPolygon", "coordinates": [[[0, 0]]]}}
    for name, data in cases.items():
        (tmp_path / f"{name}.geojson").write_text(json.dumps(data))
    for name, words in {"ragged": ["position [0][1]", "[longitude, latitude]"], "text": ["['a', 'b']"],
                        "null": ["not a geometry: none given"], "flat": ["needs 4 or more"]}.items():
        err = refused(cli("fields", tmp_path / f"{name}.geojson"), *words)
        assert "inhomogeneous" not in err and "NoneType" not in err and "object is not" not in err
    (tmp_path / "deep.geojson").write_text("[" * 100_000 + "]" * 100_000)
    refused(cli("fields", tmp_path / "deep.geojson"), "nested deeper")
    shutil.copy(DATA / "fields2cover_data" / "test.json", tmp_path / "good.json")
    proc = cli("fields", tmp_path)                     # one deep file does not abort the folder
    assert proc.returncode == 0 and "nested deeper" in proc.stdout and "1 field(s)" in proc.stdout
    text = (ISOXML / "PARTFIELDS_TASKDATA.XML").read_text()
    first = text.index('<PFD ')
    end = text.index(">", first)
    tag = text[first:end]
    import re

    (tmp_path / "TASKDATA.XML").write_text(text[:first] + re.sub(r' D="\d+"', ' D="abc"', tag) + text[end:])
    err = refused(cli("fields", tmp_path / "TASKDATA.XML"), "D (area, m2) is 'abc'", "expected a number")
    assert "warning" not in err.lower()
    aog = tmp_path / "aog"
    aog.mkdir()
    (aog / "Boundary.txt").write_text("$Boundary\nFalse\n4\n0,0,0\n100,0,0\n100,100,0\n0,100,0\n")
    refused(cli("fields", aog), "without Field.txt", "StartFix")


# --- ROS bags whose topics are all of unknown types ---------------------------------------------------------------
def _custom_bags(folder: Path) -> list[Path]:
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    definition = "float64 steer_deg\nfloat64 gyro_dps\n"
    bags = []
    for store_name, writer in ((Stores.ROS2_HUMBLE, "mcap"), (Stores.ROS1_NOETIC, "ros1")):
        store = get_typestore(store_name)
        store.register(get_types_from_msg(definition, "agro_msgs/msg/Drive"))
        drive = store.types["agro_msgs/msg/Drive"]
        path = folder / ("mcap" if writer == "mcap" else "drive.bag")
        with (Writer2(path, version=8, storage_plugin=StoragePlugin.MCAP) if writer == "mcap" else Writer1(path)) as w:
            c = w.add_connection("/tractor/drive", "agro_msgs/msg/Drive", typestore=store)
            for k in range(200):
                msg = drive(steer_deg=1.0, gyro_dps=2.0)
                data = store.serialize_cdr(msg, "agro_msgs/msg/Drive") if writer == "mcap" else \
                    store.serialize_ros1(msg, "agro_msgs/msg/Drive")
                w.write(c, int((1000 + 0.05 * k) * 1e9), data)
        bags.append(path)
    return bags


@pytest.mark.slow
def test_bags_with_only_unknown_types_are_refused_by_every_command_naming_the_topics(tmp_path):
    for bag in _custom_bags(tmp_path):
        for command in ("convert", "identify", "diagnose"):
            refused(cli(command, bag, "--out", tmp_path / (f"{command}.csv" if command == "convert" else command),
                        "--overwrite"),
                    "no topic of a known type",
                    "/tractor/drive (agro_msgs/msg/Drive)", "--signal")
        refused(cli("fields", bag, "--from-track"), "no topic of a known type")
        listing = cli("convert", bag, "--list")
        assert listing.returncode == 0 and "/tractor/drive.gyro_dps" in listing.stdout


# --- CAN ---------------------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_a_malformed_candump_line_is_skipped_with_its_line_number_and_the_format(tmp_path):
    clean = write_candump(tmp_path / "clean.log", 30.0)
    bad = write_candump(tmp_path / "bad.log", 30.0, bad={100: "(1777622405.000000) can0 280#ZZZZ",
                                                         200: "can0  280   [8]  00 00 00 00 00 00 00 00"})
    out = converted(cli("convert", bad, "--out", tmp_path / "b.csv"), "2 line(s) that are not CAN frames skipped",
                    "line 101", "line 202", "(SECONDS) BUS ID#HEXDATA")
    assert "Traceback" not in out
    converted(cli("convert", clean, "--out", tmp_path / "c.csv"))
    a, b = pd.read_csv(tmp_path / "b.csv"), pd.read_csv(tmp_path / "c.csv")
    assert a.shape == b.shape and np.allclose(a.to_numpy(), b.to_numpy())
    # the decoded wheel angle is what was encoded: 0.2 sin(0.5 t) rad, to the DBC's 1e-4 quantum
    assert np.abs(b["delta"] - 0.2 * np.sin(0.5 * b["t"])).max() < 1.5e-4
    (tmp_path / "text.log").write_text("hello world\nthis is not candump\n")
    refused(cli("convert", tmp_path / "text.log", "--out", tmp_path / "t.csv"), "no CAN frame", "line 1: 'hello world'",
            "(SECONDS) BUS ID#HEXDATA")
    assert not (tmp_path / "t.csv").exists()


def test_no_symlinked_file_is_followed_into_something_that_is_not_a_file(tmp_path):
    if not os.path.exists("/dev/null"):
        pytest.skip("no /dev/null")
    (tmp_path / "rec").mkdir()
    write_nmea(tmp_path / "rec" / "gps.nmea", 30.0)
    (tmp_path / "rec" / "null.log").symlink_to("/dev/null")       # a device inside a folder is left out, not read
    converted(cli("convert", tmp_path / "rec", "--out", tmp_path / "r.csv"))
    assert math.isclose(len(pd.read_csv(tmp_path / "r.csv")), 300, abs_tol=1)
