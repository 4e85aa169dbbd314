"""Other people's data. Every file of the real sets (copies in tests/data) through the new readers (real
receivers' NMEA, an ISO 11783-10 TaskData with 21 binary time logs, partfields, Fields2Cover's
fields, a test field in a Japanese plane-rectangular CRS), ROS bags written here from real NMEA
positions, AgOpenGPS field folders written from real fields, partial recordings, and a vehicle
other than the tractor."""
from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from agrobot.fields import FieldError, read_fields
from agrobot.measurements.raw_nmea import read_nmea_file
from agrobot.measurements.recording import ImportOptions, import_recording
from tests.commands import cli

ROOT = Path(__file__).resolve().parents[1]
REAL = ROOT / "tests" / "data"             # copies of the published real sets, with their licences (tests/data/README.md)
NMEA = REAL / "nmea_gpsd_testlogs"
ISOXML = REAL / "isoxml_dev4ag_timelogs"
F2C = REAL / "fields2cover_data"
IAM = REAL / "iam_field_open_autonomous_tractor"


# --- every real receiver -------------------------------------------------------------------------------
@pytest.mark.parametrize("capture", sorted(p.name for p in NMEA.glob("*.log")) if NMEA.is_dir() else [])
def test_every_real_receivers_nmea_imports_with_no_line_refused(capture, tmp_path):
    rec = read_nmea_file(NMEA / capture)
    refused = {k: v for k, v in rec.counts.items() if k in ("malformed", "bad checksum", "not a sentence")}
    assert refused == {}, refused                           # comments are comments, proprietary lines counted
    comments = sum(1 for line in (NMEA / capture).read_text(errors="replace").splitlines() if line.startswith("#"))
    assert rec.counts["comment"] == comments
    proc = cli("convert", NMEA / capture, "--out", tmp_path / "log.csv")
    assert proc.returncode == 0, proc.stderr
    log = pd.read_csv(tmp_path / "log.csv")
    assert {"t", "x", "y", "fix_quality"} <= set(log.columns) and len(log) >= 3
    report = json.loads((tmp_path / "log.import.json").read_text())
    assert set(report["missing"]) == {"delta_cmd", "delta", "v", "yaw_rate"}
    assert "missing yaw_rate" in proc.stdout and "columns: t, x, y" in proc.stdout


def test_receiver_details_are_kept_qualities_heading_error_talkers():
    rtk = read_nmea_file(NMEA / "nmea-rtk.log").epochs
    assert set(rtk["quality"]) == {2, 4}                        # DGPS and RTK fixed, as the receiver said
    for capture in ("hemi.log", "rst39.log"):                   # HDT: a dual antenna's heading
        rec = read_nmea_file(NMEA / capture)
        assert rec.counts["HDT"] > 0 and rec.epochs["heading"].notna().any()
    rst = read_nmea_file(NMEA / "rst39.log")
    hdt = float(next(line for line in (NMEA / "rst39.log").read_text().splitlines()
                     if "HDT," in line and ",T*" in line and not line.startswith("#")).split(",")[1])
    assert math.degrees(math.pi / 2 - rst.epochs["heading"].dropna().iloc[0]) == pytest.approx(hdt, abs=1e-9)
    assert rst.counts["unused proprietary"] == 100              # $PASHR at 25 Hz: counted, not refused
    sky = read_nmea_file(NMEA / "skytraq-dgps.log").epochs
    assert sky["position_std"].notna().all() and (sky["position_std"] > 0).all()     # GST
    boat = read_nmea_file(NMEA / "humminbird-M37.log")           # talker IN, a clock that steps back:
    assert len(boat.epochs) == 6 and boat.epochs["utc"].is_monotonic_increasing     # 2 of 8 masked, split there
    assert [b["masked"] for b in boat.breaks] == [2]
    hp = read_nmea_file(NMEA / "ublox-f9p-hpnmea.log").epochs     # high-precision GGA: 7 decimals of minutes
    assert abs(hp["lat"].iloc[0] - (44 + 4.1306024 / 60)) < 1e-10


@pytest.mark.parametrize("stamp", ["unix", "candump", "iso"])
def test_host_stamps_in_the_common_forms_before_the_sentence(stamp, tmp_path):
    import datetime

    lines = [ln for ln in (NMEA / "nmea-rtk.log").read_text().splitlines() if ln.startswith("$")]
    out = []
    for i, line in enumerate(lines):
        t = 1795000000.0 + 0.05 * i
        prefix = {"unix": f"{t:.3f} ", "candump": f"({t:.6f}) ",
                  "iso": datetime.datetime.fromtimestamp(t, datetime.timezone.utc).isoformat().replace("+00:00", "Z") + " "}[stamp]
        out.append(prefix + line)
    (tmp_path / "stamped.nmea").write_text("\n".join(out) + "\n")
    rec = read_nmea_file(tmp_path / "stamped.nmea")
    plain = read_nmea_file(NMEA / "nmea-rtk.log")
    assert np.isfinite(rec.epochs["host"]).all()
    np.testing.assert_allclose(rec.epochs[["lat", "lon"]].to_numpy(), plain.epochs[["lat", "lon"]].to_numpy())


# --- ROS bags -------------------------------------------------------------------------------------------
def _navsat(store, cls_name: str, utc: float, lat: float, lon: float, height: float, quality: int):
    T = store.types
    sec, ns = int(utc), int(round((utc - int(utc)) * 1e9))
    header = T["std_msgs/msg/Header"]
    fields = {"stamp": T["builtin_interfaces/msg/Time"](sec=sec, nanosec=ns), "frame_id": "gps"}
    if "seq" in header.__dataclass_fields__:
        fields["seq"] = 0
    status = {1: 0, 2: 1, 4: 2, 5: 2}.get(int(quality), -1)
    return T[cls_name](header=header(**fields), status=T["sensor_msgs/msg/NavSatStatus"](status=status, service=1),
                       latitude=lat, longitude=lon, altitude=height, position_covariance=np.zeros(9),
                       position_covariance_type=0)


def _imu(store, utc: float, yaw_rate: float):
    T = store.types
    header = T["std_msgs/msg/Header"]
    fields = {"stamp": T["builtin_interfaces/msg/Time"](sec=int(utc), nanosec=int(round((utc - int(utc)) * 1e9))),
              "frame_id": "imu"}
    if "seq" in header.__dataclass_fields__:
        fields["seq"] = 0
    v3 = T["geometry_msgs/msg/Vector3"]
    return T["sensor_msgs/msg/Imu"](header=header(**fields), orientation=T["geometry_msgs/msg/Quaternion"](x=0, y=0, z=0, w=1),
                                    orientation_covariance=np.zeros(9), angular_velocity=v3(x=0, y=0, z=yaw_rate),
                                    angular_velocity_covariance=np.zeros(9), linear_acceleration=v3(x=0, y=0, z=9.81),
                                    linear_acceleration_covariance=np.zeros(9))


def write_bag(path: Path, kind: str, epochs: pd.DataFrame, receive_delay: float = 0.03) -> Path:
    """A bag of ``kind`` (ros1, ros2, mcap) with /fix NavSatFix from the epochs and /imu Imu with a
    made-up yaw rate, received ``receive_delay`` after their header stamps."""
    from rosbags.rosbag1 import Writer as W1
    from rosbags.rosbag2 import StoragePlugin, Writer as W2
    from rosbags.typesys import Stores, get_typestore

    from agrobot.measurements.rosbag import typestore

    yaw = 0.2 * np.sin(0.1 * (epochs["utc"].to_numpy() - epochs["utc"].iloc[0]))     # a gyro's reading, rad/s
    if kind == "ros1":
        store = get_typestore(Stores.ROS1_NOETIC)
        writer, serialize = W1(path), store.serialize_ros1
    else:
        store = typestore()
        writer = W2(path, version=8, storage_plugin=StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3)
        serialize = store.serialize_cdr
    with writer as w:
        fix = w.add_connection("/fix", "sensor_msgs/msg/NavSatFix", typestore=store)
        imu = w.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=store)
        for r, g in zip(epochs.itertuples(), yaw):
            stamp = int((r.utc + receive_delay) * 1e9)
            w.write(fix, stamp, serialize(_navsat(store, "sensor_msgs/msg/NavSatFix", r.utc, r.lat, r.lon, r.height,
                                                  r.quality), "sensor_msgs/msg/NavSatFix"))
            w.write(imu, stamp, serialize(_imu(store, r.utc, g), "sensor_msgs/msg/Imu"))
    return path


@pytest.fixture(scope="module")
def bags(tmp_path_factory):
    """The same real positions (a walked square, haicom-305N) as a ROS 1 bag, a ROS 2 bag and an MCAP."""
    folder = tmp_path_factory.mktemp("bags")
    epochs = read_nmea_file(NMEA / "haicom-305N.log").epochs
    epochs = epochs[epochs["quality"] > 0].reset_index(drop=True)
    out = {kind: write_bag(folder / name, kind, epochs) for kind, name in
           (("ros1", "walk.bag"), ("ros2", "walk_ros2"), ("mcap", "walk_mcap"))}
    out["bare_mcap"] = next((folder / "walk_mcap").glob("*.mcap"))
    return out


def test_ros1_ros2_and_mcap_bags_round_trip_to_the_same_log_as_the_receivers_nmea(bags):
    options = ImportOptions(time_range=(0.0, 60.0))
    base, _ = import_recording(NMEA / "haicom-305N.log", options)
    logs = {}
    for kind, path in bags.items():
        frame, report = import_recording(path, options)
        logs[kind] = frame
        assert report["bag"]["topics"]["/fix"]["time"] == "header stamps"      # not the 30 ms later receive time
        assert report["bag"]["topics"]["/imu"]["type"] == "sensor_msgs/msg/Imu"
        assert len(frame) == len(base)
        np.testing.assert_allclose(frame[["x", "y"]].to_numpy(), base[["x", "y"]].to_numpy(), atol=1e-6)
        np.testing.assert_array_equal(frame["fix_quality"].to_numpy(), base["fix_quality"].to_numpy())
        assert "yaw_rate" in frame and {"delta_cmd", "delta", "v"} <= set(report["missing"])
    for kind in ("ros2", "mcap", "bare_mcap"):
        pd.testing.assert_frame_equal(logs[kind], logs["ros1"], check_exact=False, atol=1e-9)


@pytest.mark.slow
def test_any_topic_field_by_signal_and_bad_bags_are_named(bags, tmp_path):
    proc = cli("convert", bags["ros1"], "--out", tmp_path / "a.csv", "--signal", "gyro_z=/imu.angular_velocity.z",
               "--signal", "v=/fix.altitude[m/s]")     # a declared unit overrides the field's own
    assert proc.returncode == 0, proc.stderr
    log = pd.read_csv(tmp_path / "a.csv")
    assert "gyro_z" in log and np.allclose(log["gyro_z"], log["yaw_rate"])
    bad = tmp_path / "broken.bag"
    bad.write_bytes(b"#ROSBAG V2.0\n" + b"\x00" * 64)
    cases = [
        (("convert", bad, "--out", tmp_path / "b.csv"), ["broken.bag", "cannot read as a ROS bag"]),
        (("convert", bags["ros1"], "--out", tmp_path / "c.csv", "--signal", "v=/odom.twist"),
         ["no topic '/odom'", "/fix (sensor_msgs/msg/NavSatFix)", "/imu (sensor_msgs/msg/Imu)"]),
        (("convert", bags["ros1"], "--out", tmp_path / "d.csv", "--signal", "v=/imu.linear_velocity.x"),
         ["topic /imu", "no field 'linear_velocity'", "angular_velocity"]),
        (("convert", bags["ros1"], "--out", tmp_path / "e.csv", "--signal", "v=/imu"),
         ["the message has several fields"]),
    ]
    for args, words in cases:
        proc = cli(*args)
        assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
        for w in words:
            assert w in proc.stderr, (w, proc.stderr)
    assert not any((tmp_path / f"{c}.csv").exists() for c in "bcde")


# --- ISO 11783-10 ----------------------------------------------------------------------------------------
def test_every_binary_time_log_is_read_to_its_last_byte():
    from agrobot.measurements.isoxml_log import read_header, read_timelog

    heads = sorted(ISOXML.glob("TLG*.xml"))
    assert len(heads) == 21
    for head in heads:
        table, info = read_timelog(head)
        logged, dlvs, _ = read_header(head)
        size = head.with_suffix(".bin").stat().st_size
        assert info["records"] == len(table) >= 187
        assert np.allclose(np.diff(table["utc"]).min(), 1.0) or np.median(np.diff(table["utc"])) == pytest.approx(1.0)
        assert table["lat"].between(54.3, 54.7).all() and table["lon"].between(9.9, 10.3).all()
        assert set(table["status"]) == {15}                     # PositionStatus 'not available' (the README)
        assert len(info["units"]) == len(dlvs) == 26 and size > 6 * len(table)
        assert any(unit.startswith("mm ") for unit in info["units"].values())        # working width in mm


@pytest.mark.slow
def test_a_taskdata_converts_to_a_log_and_bad_time_logs_are_named(tmp_path):
    proc = cli("convert", ISOXML, "--out", tmp_path / "tlg.csv")
    assert proc.returncode == 0, proc.stderr
    log = pd.read_csv(tmp_path / "tlg.csv")
    report = json.loads((tmp_path / "tlg.import.json").read_text())
    assert report["rate_hz"] == 1.0 and "ddi0116_total_area" in log and "track_speed" in log
    assert 0.5 < log["track_speed"].median() < 3.0                    # a forage harvester at work
    assert "PositionStatus is 15" in " ".join(report["notes"])
    bad = tmp_path / "bad"
    bad.mkdir()
    shutil.copy(ISOXML / "TLG00006.xml", bad)
    (bad / "TLG00006.bin").write_bytes((ISOXML / "TLG00006.bin").read_bytes()[:-7])       # cut off
    (tmp_path / "notim").mkdir()
    (tmp_path / "notim" / "TLG00001.xml").write_text('<?xml version="1.0"?><PTN A="" B=""/>')
    (tmp_path / "notim" / "TLG00001.bin").write_bytes(b"")
    for folder, words in ((bad, ["TLG00006.bin", "does not match its header"]),
                          (tmp_path / "notim", ["TLG00001.xml", "expected a time-log header (root element TIM)"])):
        proc = cli("convert", folder, "--out", tmp_path / "x.csv")
        assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
        for w in words:
            assert w in proc.stderr, proc.stderr


def test_a_one_hertz_harvester_track_gets_the_limit_named_not_a_verdict(tmp_path):
    proc = cli("diagnose", ISOXML, "--out", tmp_path / "d")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "nothing to judge" in proc.stderr and "no delta_cmd" in proc.stderr
    res = json.loads((tmp_path / "d" / "diagnosis.json").read_text())
    assert res["verdict"] == "cannot decide"


# --- fields ------------------------------------------------------------------------------------------------
def test_isoxml_partfields_with_holes_across_the_globe_match_the_files_own_areas():
    fields = read_fields(ISOXML / "PARTFIELDS_TASKDATA.XML")
    assert len(fields) == 13
    for f in fields:
        assert not f.problems(), (f.name, f.problems())
        assert f.boundary.area == pytest.approx(f.properties["area_m2_in_file"], rel=0.01), f.name
    holes = {f.name: f.holes for f in fields}
    assert holes["NM_Oxted_NullMeridian_Hole"] == 1 and holes["MW_LaConc_EC_Equator_Hole"] == 1
    assert len(read_fields(ISOXML / "TASKDATA.XML")) == 21


def test_fields2cover_fields_read_and_a_broken_boundary_is_named(tmp_path):
    f = next(f for f in read_fields(F2C / "test1.xml") if f.name == "boundary")
    assert f.area_ha == pytest.approx(17.2581, rel=1e-3)                 # the parcel's own 'area' attribute
    assert f.properties["swath_width"] == 3.0 and "EPSG:4258" in f.crs
    ring = read_fields(F2C / "test_ring.json")[0]
    assert ring.origin is None and ring.holes == 1 and ring.boundary.area == pytest.approx(36.0)
    strips = read_fields(F2C / "strips.geojson")
    assert len(strips) == 3 and all(s.boundary.is_valid and "Self-intersection" in s.properties["repaired"]
                                    and "sliver" in s.properties["repaired"] for s in strips)
    proc = cli("fields", F2C, "--out", tmp_path / "f")
    assert proc.returncode == 0, proc.stderr
    assert "not read:" in proc.stdout and "swaths.geojson: no Polygon" in proc.stdout
    assert "repaired: the polygon was invalid (Self-intersection" in proc.stdout
    assert (tmp_path / "f" / "fields.png").stat().st_size > 20000
    back = read_fields(tmp_path / "f" / "fields.geojson")
    assert sorted(round(x.area_ha, 2) for x in back if x.origin) == \
        sorted(round(x.area_ha, 2) for x in read_fields(F2C) if x.origin)


def test_a_field_in_a_japanese_plane_rectangular_crs_lands_at_its_saved_origin():
    import yaml

    fields = read_fields(IAM / "datasets" / "iam_field" / "field_boundaries.csv", crs="EPSG:6677")
    assert len(fields) == 4
    for f in fields:
        minx, miny, maxx, maxy = f.boundary.minimum_rotated_rectangle.bounds
        assert 1200 < f.boundary.area < 1600                               # about 50 x 30 m
    saved = yaml.safe_load((IAM / "config" / "localization" / "saved_origins.yaml").read_text())
    text = json.dumps(saved)
    lat = float(next(v for k, v in _walk(saved) if "lat" in k.lower()))
    lon = float(next(v for k, v in _walk(saved) if "lon" in k.lower()))
    origin = fields[0].origin
    assert abs(origin[0] - lat) < 0.01 and abs(origin[1] - lon) < 0.01, (origin, text)
    with pytest.raises(FieldError, match="unknown CRS 'EPSG:999999'"):
        read_fields(IAM / "datasets" / "iam_field" / "field_boundaries.csv", crs="EPSG:999999")


def _walk(d, prefix=""):
    if isinstance(d, dict):
        for k, v in d.items():
            yield from _walk(v, f"{prefix}.{k}")
    elif isinstance(d, list):
        for i, v in enumerate(d):
            yield from _walk(v, f"{prefix}[{i}]")
    else:
        yield prefix, d


def write_agopengps(folder: Path, field, lines: list[tuple[str, np.ndarray]], headland_inset: float = 6.0) -> Path:
    """An AgOpenGPS field folder (Field.txt, Boundary.txt, Headland.txt, TrackLines.txt) in its
    text layout, from a field in local metres about its origin."""
    folder.mkdir(parents=True)
    lat, lon = field.origin
    (folder / "Field.txt").write_text(f"2026-Nov-24 10:00:00\n$FieldDir\n{folder.name}\n$Offsets\n0,0\nConvergence\n0\n"
                                      f"StartFix\n{lat:.9f},{lon:.9f}\n")

    def ring_lines(ring):
        pts = np.asarray(ring.coords)[:-1]
        return [str(len(pts))] + [f"{e:.3f},{n:.3f},0.00000" for e, n in pts]

    boundary = ["$Boundary", "False"] + ring_lines(field.boundary.exterior)
    for hole in field.boundary.interiors:
        boundary += ["True"] + ring_lines(hole)
    (folder / "Boundary.txt").write_text("\n".join(boundary) + "\n")
    inner = field.boundary.buffer(-headland_inset)
    (folder / "Headland.txt").write_text("\n".join(["$Headland"] + ring_lines(inner.exterior)) + "\n")
    track = ["$TrackLines"]
    for name, pts in lines:
        heading = math.atan2(pts[-1][0] - pts[0][0], pts[-1][1] - pts[0][1])
        track += [name, f"{heading:.5f}", f"{pts[0][0]:.3f},{pts[0][1]:.3f}", f"{pts[-1][0]:.3f},{pts[-1][1]:.3f}", "0",
                  "2" if len(pts) == 2 else "4", "True", str(len(pts) if len(pts) > 2 else 0)]
        if len(pts) > 2:
            track += [f"{e:.3f},{n:.3f},0" for e, n in pts]
    (folder / "TrackLines.txt").write_text("\n".join(track) + "\n")
    return folder


def test_an_agopengps_field_folder_reads_as_the_field_it_was_written_from(tmp_path):
    real = next(f for f in read_fields(ISOXML / "PARTFIELDS_TASKDATA.XML") if f.name == "NM_Oxted_NullMeridian_Hole")
    c = np.asarray(real.boundary.centroid.coords)[0]
    ab = np.array([c + [-40.0, -20.0], c + [40.0, 20.0]])
    s = np.linspace(0, 1, 30)
    curve = np.column_stack([c[0] - 50 + 100 * s, c[1] + 15 * np.sin(3 * s)])
    folder = write_agopengps(tmp_path / "Oxted", real, [("AB 63.4", ab), ("Cu 90", curve)])
    f = read_fields(folder)[0]
    assert f.origin == pytest.approx(real.origin) and f.holes == 1
    assert f.boundary.area == pytest.approx(real.boundary.area, rel=1e-5)
    assert f.headland is not None and f.headland.area < f.boundary.area
    assert [g.kind for g in f.lines] == ["AB line", "curve"] and f.lines[1].length == pytest.approx(
        float(np.sum(np.hypot(*np.diff(curve, axis=0).T))), rel=1e-4)
    np.testing.assert_allclose(f.to_geodetic(np.asarray(f.boundary.exterior.coords)),
                               real.to_geodetic(np.asarray(real.boundary.exterior.coords)), atol=1e-7)
    proc = cli("fields", folder)
    assert proc.returncode == 0 and "AB line 'AB 63.4'" in proc.stdout and "curve 'Cu 90'" in proc.stdout
    (folder / "Field.txt").write_text("no origin here\n")
    proc = cli("fields", folder)
    assert proc.returncode == 2 and "Field.txt: no StartFix line" in proc.stderr


@pytest.mark.slow
def test_geojson_wkt_and_isoxml_guidance_patterns_and_bad_field_files(tmp_path):
    real = read_fields(F2C / "test.json")[0]
    lonlat = real.to_geodetic(np.asarray(real.boundary.exterior.coords))
    wkt = "POLYGON ((" + ", ".join(f"{x:.9f} {y:.9f}" for x, y in lonlat) + "))\n\nLINESTRING (" + \
        f"{lonlat[0][0]:.9f} {lonlat[0][1]:.9f}, {lonlat[2][0]:.9f} {lonlat[2][1]:.9f})\n"
    (tmp_path / "parcel.wkt").write_text(wkt)
    f = read_fields(tmp_path / "parcel.wkt")[0]
    assert f.area_ha == pytest.approx(real.area_ha, rel=1e-4) and len(f.lines) == 1
    pts = lambda ring: "".join(f'<PNT A="{t}" C="{la:.9f}" D="{lo:.9f}"/>' for t, (lo, la) in ring)  # noqa: E731
    task = (f'<?xml version="1.0" encoding="UTF-8"?><ISO11783_TaskData VersionMajor="4" VersionMinor="3" '
            f'DataTransferOrigin="1"><PFD A="PFD1" C="guided" D="1"><PLN A="1"><LSG A="1">'
            f'{pts([(2, p) for p in lonlat])}</LSG></PLN><GGP A="GGP1" B="lines"><GPN A="GPN1" B="AB north" C="1">'
            f'<LSG A="5">{pts([(6, lonlat[0]), (7, lonlat[2])])}</LSG></GPN></GGP></PFD></ISO11783_TaskData>')
    (tmp_path / "TASKDATA.XML").write_text(task)
    g = read_fields(tmp_path / "TASKDATA.XML")[0]
    assert g.area_ha == pytest.approx(real.area_ha, rel=1e-4)
    assert [x.name for x in g.lines] == ["AB north"] and g.lines[0].kind == "AB line"
    (tmp_path / "bad.json").write_text('{"type": "FeatureCollection", "features": [{"type": "Feature", "geometry": '
                                       '{"type": "Polygon", "coordinates": "nope"}}]}')
    (tmp_path / "notask.xml").write_text("<ISO11783_TaskData><PFD A=\"x\"></PFD></ISO11783_TaskData>")
    for path, crs, words in ((tmp_path / "bad.json", None, ["bad.json", "feature 0", "not a geometry"]),
                             (tmp_path / "notask.xml", None, ["notask.xml"]),
                             (tmp_path / "parcel.wkt", "EPSG:123456789", ["unknown CRS 'EPSG:123456789'"]),
                             (tmp_path / "nowhere.geojson", None, ["nowhere.geojson: no such file"])):
        proc = cli("fields", path, *(("--crs", crs) if crs else ()))
        assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
        for w in words:
            assert w in proc.stderr, (w, proc.stderr)


def test_the_test_fields_road_points_agree_in_both_their_coordinate_columns():
    """road_boundary_points.csv gives each point twice: latitude/longitude and the plane-rectangular
    zone IX metres (x east, y north); the reader's projection of the metres must land on the degrees."""
    from agrobot.fields.readers import Coordinates

    table = pd.read_csv(IAM / "datasets" / "iam_field" / "road_boundary_points.csv")
    table = table[(table["latitude"] != 0) | (table["longitude"] != 0)]
    xy = table[["x", "y"]].to_numpy(float)
    lonlat = Coordinates("road points", None, "EPSG:6677", xy).lonlat(xy)
    north = (lonlat[:, 1] - table["latitude"].to_numpy()) * 111_000
    east = (lonlat[:, 0] - table["longitude"].to_numpy()) * 111_000 * math.cos(math.radians(36.0))
    assert len(table) > 300 and np.abs(north).max() < 0.01 and np.abs(east).max() < 0.01
    links = pd.read_csv(IAM / "datasets" / "iam_field" / "road_boundary_links.csv")
    assert set(links["start_id"]) | set(links["end_id"]) <= set(pd.read_csv(
        IAM / "datasets" / "iam_field" / "road_boundary_points.csv")["id"])
