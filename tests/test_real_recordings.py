"""Real recordings as they come: every maker's DBC, signals as expressions with declared units,
other tools' tables joined on time, quirks named (spikes, float32 positions, boot-time clocks),
fields from KML, ISOXML v3, AgOpenGPS folders in any letter case and from a GNSS track. The data
are the copies in tests/data (tests/data/README.md); CAN logs are written here by encoding known
values with the makers' own DBCs, so that the decoded log can be compared with what was sent."""
from __future__ import annotations

import json
import math
import re
import shutil
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from tests.commands import cli, refused

ROOT = Path(__file__).resolve().parents[1]
REAL = ROOT / "tests" / "data"
OPENDBC = REAL / "opendbc"
F1 = REAL / "f1tenth_frictionmaps" / "DataSets"
STEPS = REAL / "f1tenth_autokoopman_steps" / "F1tenthCar"
NMEA = REAL / "nmea_gpsd_testlogs"
ISOXML = REAL / "isoxml_dev4ag_timelogs"
TOYOTA = OPENDBC / "dbc" / "generator" / "toyota" / "_toyota_2017.dbc"
F1_SIGNALS = ("--signal", "delta_cmd=commandData.delta[rad]", "--signal", "yaw_rate=imuData.wz[deg/s]",
              "--signal", "v=pfOdomData.vx[m/s]", "--signal", "x=pfOdomData.x[m]", "--signal", "y=pfOdomData.y[m]")


# --- every maker's DBC ---------------------------------------------------------------------------------
@pytest.mark.slow
def test_every_makers_dbc_loads_and_nothing_is_lost_unnamed():
    import cantools

    from agrobot.measurements.dbc import load_dbc_file

    files = sorted(OPENDBC.rglob("*.dbc"))
    assert len(files) == 118
    strict = 0
    for path in files:
        try:
            cantools.database.load_file(str(path))
            strict += 1
        except Exception:          # noqa: BLE001 - counting cantools' own strict refusals
            pass
        db, report = load_dbc_file(path)
        declared = len(re.findall(r"^BO_ \d+ (?!VECTOR__INDEPENDENT_SIG_MSG)", path.read_text(errors="replace"), re.M))
        assert len(db.messages) > 0, path
        assert len(db.messages) + len(report.skipped) >= declared, (path, report.as_dict())   # loaded or named
    assert strict == 84                                   # the README's count: the rest need the repairs


def test_repairs_are_named_and_names_beginning_with_a_digit_keep_their_own_name():
    from agrobot.measurements.dbc import load_dbc_file

    db, report = load_dbc_file(OPENDBC / "dbc" / "mazda_2017.dbc")
    assert "2017_5" in [m.name for m in db.messages]
    assert report.repairs["message or signal names beginning with a digit"] >= 1
    db, report = load_dbc_file(OPENDBC / "dbc" / "toyota_2017_ref_pt.dbc")
    assert "BDB1F01_14" in report.skipped and "0x40140639" in report.skipped["BDB1F01_14"]      # wider than 29 bits
    db, report = load_dbc_file(OPENDBC / "dbc" / "gm_global_a_lowspeed.dbc")
    door = db.get_message_by_name("DriverDoorStatus")
    assert door.is_extended_frame and door.frame_id == 274923520          # 0x10630000, a 29-bit identifier


def _candump(path: Path, frames: list[tuple[float, str, int, bytes, bool]]) -> Path:
    lines = [f"({t:.6f}) {bus} {ident:08X}#{data.hex().upper()}" if ext else f"({t:.6f}) {bus} {ident:03X}#{data.hex().upper()}"
             for t, bus, ident, data, ext in frames]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def toyota_log(tmp_path_factory):
    """A candump of a Toyota's steering-angle sensor and kinematics at 50 Hz on a boot-time clock:
    a handwheel angle of 90 sin(0.5 t) deg sent as 1.5-deg coarse steps plus a 0.1-deg fraction,
    a yaw rate of 20 sin(0.3 t) deg/s (outside the DBC's declared [0|65535]: a signed value)."""
    from agrobot.measurements.dbc import load_dbc_file

    db, _ = load_dbc_file(TOYOTA)
    steer, kin = db.get_message_by_name("STEER_ANGLE_SENSOR"), db.get_message_by_name("KINEMATICS")
    t = 12.0 + np.arange(0, 40, 0.02)                  # the logger counts from its boot
    angle = 90 * np.sin(0.5 * (t - 12.0))
    coarse = 1.5 * np.round(angle / 1.5)
    frac = np.clip(np.round((angle - coarse) / 0.1), -7, 7) * 0.1
    yaw = 20 * np.sin(0.3 * (t - 12.0))
    frames = []
    for k, tk in enumerate(t):
        frames.append((tk, "can0", steer.frame_id, steer.encode({"STEER_ANGLE": coarse[k], "STEER_FRACTION": frac[k],
                                                                 "STEER_RATE": 0}, strict=False), False))
        frames.append((tk + 0.001, "can0", kin.frame_id, kin.encode({"YAW_RATE": yaw[k], "ACCEL_X": 0, "ACCEL_Y": 0},
                                                                    strict=False), False))
    folder = tmp_path_factory.mktemp("toyota")
    _candump(folder / "drive.log", frames)
    return folder / "drive.log", t, coarse + frac, yaw


def test_a_split_handwheel_angle_is_summed_and_a_declared_range_is_a_note_not_a_filter(toyota_log, tmp_path):
    log, t, angle, yaw = toyota_log
    out = tmp_path / "toyota.csv"
    proc = cli("convert", log, "--dbc", TOYOTA, "--out", out, "--steering-ratio", 15,
               "--signal", "delta=STEER_ANGLE_SENSOR.STEER_ANGLE+STEER_ANGLE_SENSOR.STEER_FRACTION",
               "--signal", "yaw_rate=KINEMATICS.YAW_RATE")
    assert proc.returncode == 0, proc.stderr
    frame = pd.read_csv(out)
    report = json.loads(out.with_name("toyota.import.json").read_text())
    assert len(frame) > 1900                                 # the whole 40 s, not 14 rows
    t0 = 12.0 + report["used"]["start"]
    truth = np.interp(t0 + frame["t"], t, angle)
    np.testing.assert_allclose(frame["delta"], np.radians(truth) / 15, atol=np.radians(0.051) / 15)
    assert np.ptp(np.diff(np.unique(np.round(np.degrees(frame["delta"] * 15), 3)))) < 1.5    # no 1.5-deg steps left
    np.testing.assert_allclose(frame["yaw_rate"], np.radians(np.interp(t0 + frame["t"], t, yaw)), atol=np.radians(0.25))
    outside = report["can"]["outside_declared_range"]["KINEMATICS.YAW_RATE"]
    assert outside["outside"] > 0.4 * outside["of"] and outside["declared"] == [0, 65535]
    assert "plausibility: KINEMATICS.YAW_RATE" in proc.stdout
    assert "on the logger's clock (since its start, not a date)" in proc.stdout and "1970" not in proc.stdout


@pytest.mark.slow
def test_can_list_and_bad_dbc_signal_and_unit_are_named(toyota_log, tmp_path):
    log = toyota_log[0]
    proc = cli("convert", log, "--dbc", TOYOTA, "--list")
    assert proc.returncode == 0, proc.stderr
    assert re.search(r"STEER_ANGLE_SENSOR \(0x25\): 2000 frames at 50 Hz", proc.stdout), proc.stdout
    assert "STEER_ANGLE_SENSOR.STEER_FRACTION [deg]" in proc.stdout and "KINEMATICS.YAW_RATE [deg/s]" in proc.stdout
    notdbc = tmp_path / "notes.dbc"
    notdbc.write_text("this is a shopping list\nmilk\n")
    refused(cli("convert", log, "--dbc", notdbc, "--out", tmp_path / "a.csv"), "notes.dbc", "not a DBC")
    refused(cli("convert", log, "--dbc", TOYOTA, "--out", tmp_path / "b.csv", "--signal", "yaw_rate=KINEMATICS.YAW_RTE"),
            "no signal 'KINEMATICS.YAW_RTE'", "near names: KINEMATICS.YAW_RATE")
    refused(cli("convert", log, "--dbc", TOYOTA, "--out", tmp_path / "c.csv", "--signal", "yaw_rate=KINEMATICS.YAW_RATE[wibble/s]"),
            "unit 'wibble/s' is not one pint knows")
    assert not list(tmp_path.glob("*.csv"))


def test_extended_frames_on_two_buses_and_a_multiplexed_message(tmp_path):
    from agrobot.measurements.dbc import load_dbc_file
    from agrobot.measurements.raw_can import read_can_file

    gm = OPENDBC / "dbc" / "gm_global_a_lowspeed.dbc"
    db, _ = load_dbc_file(gm)
    door = db.get_message_by_name("DriverDoorStatus")
    name = door.signals[0].name
    frames = []
    for k in range(200):
        for bus, value in (("can0", 0), ("can1", 1)):
            frames.append((100 + 0.1 * k, bus, door.frame_id, door.encode({s.name: value if s.name == name else 0
                                                                           for s in door.signals}), True))
    log = _candump(tmp_path / "two.log", frames)
    with pytest.raises(Exception, match=r"frames from 2 buses \(can0: 200 frames, can1: 200 frames\); choose one with --bus"):
        read_can_file(log, db)
    rec = read_can_file(log, db, "can1")
    assert rec.counts["decoded"] == 200 and set(rec.messages["DriverDoorStatus"][name]) == {1.0}
    tesla, _ = load_dbc_file(OPENDBC / "dbc" / "tesla_can.dbc")
    mux = next(m for m in tesla.messages if m.is_multiplexed())
    selector = next(s for s in mux.signals if s.is_multiplexer)
    frames = []
    for k in range(40):
        sel = k % 2
        body = {s.name: 0 for s in mux.signals if s.multiplexer_ids is None or sel in s.multiplexer_ids}
        body[selector.name] = sel
        frames.append((1.0 + 0.05 * k, "can0", mux.frame_id, mux.encode(body), mux.is_extended_frame))
    rec = read_can_file(_candump(tmp_path / "mux.log", frames), tesla)
    table = rec.messages[mux.name]
    only1 = next(s.name for s in mux.signals if s.multiplexer_ids == [1])
    assert len(table) == 40 and table[only1].notna().sum() == 20        # a mux-1 signal only in the mux-1 frames


# --- tables --------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_the_f1tenth_tables_join_on_time_with_the_gyro_declared_in_degrees(tmp_path):
    out = tmp_path / "ds1.csv"
    proc = cli("convert", F1 / "DS1", *F1_SIGNALS, "--out", out)
    assert proc.returncode == 0, proc.stderr
    log = pd.read_csv(out)
    assert list(log.columns) == ["t", "delta_cmd", "v", "yaw_rate", "x", "y"] and log["t"].iloc[-1] > 40
    assert "missing delta" in proc.stdout and "an index the writer left, ignored" in proc.stdout
    # the README's check: the yaw rate follows the kinematic v tan(delta)/L (L = 0.32 m) about 0.15 s later
    h = float(np.median(np.diff(log["t"])))
    lag = int(round(0.15 / h))
    fast = (log["v"] > 0.3).to_numpy()[:-lag]
    kin = (log["v"] * np.tan(log["delta_cmd"]) / 0.32).to_numpy()[:-lag]
    r = log["yaw_rate"].to_numpy()[lag:]
    assert np.corrcoef(kin[fast], r[fast])[0, 1] > 0.85
    assert np.abs(log["yaw_rate"]).max() < 3.5                       # rad/s, not 180 "deg/s"
    refused(cli("convert", F1 / "DS1", "--signal", "yaw_rate=imuData.wz", "--out", tmp_path / "b.csv"),
            "imuData.wz", "is a rate; declare it", "yaw_rate=imuData.wz[rad/s]")
    refused(cli("convert", F1 / "DS1", "--signal", "yaw_rate=imuData.wzz[deg/s]", "--out", tmp_path / "c.csv"),
            "no column 'imuData.wzz'", "near names: imuData.wz")
    refused(cli("convert", F1 / "DS1", "--signal", "v=vx[m/s]", "--out", tmp_path / "d.csv"),
            "column 'vx' is in several tables", "odomData.vx", "pfOdomData.vx")
    assert not (tmp_path / "b.csv").exists() and not (tmp_path / "c.csv").exists()


@pytest.mark.slow
def test_gyro_spikes_are_named_masked_or_kept(tmp_path):
    run = tmp_path / "DS1"
    shutil.copytree(F1 / "DS1", run)
    imu = pd.read_csv(run / "imuData.csv")
    rows = [300, 700, 1100]
    imu.loc[rows, "wz"] = 3000.0                                      # glitches, deg/s
    imu.to_csv(run / "imuData.csv", index=False)
    t_spike = (imu["s"] + 1e-9 * imu["ns"]).to_numpy()[rows]
    clean = pd.read_csv(_convert(F1 / "DS1", tmp_path / "clean.csv"))
    proc = cli("convert", run, *F1_SIGNALS, "--out", tmp_path / "masked.csv")
    assert proc.returncode == 0, proc.stderr
    report = json.loads((tmp_path / "masked.import.json").read_text())
    spikes = next(s for s in report["spikes"] if s["column"] == "yaw_rate")
    start = report["used"]["utc_start_s"] - report["used"]["start"]
    assert spikes["count"] == 3 and np.allclose(spikes["times_s"], t_spike - start, atol=2e-3)
    masked = pd.read_csv(tmp_path / "masked.csv")
    assert np.abs(masked["yaw_rate"]).max() < 3.5
    near = np.zeros(len(masked), bool)
    for ts in t_spike - report["used"]["utc_start_s"]:
        near |= np.abs(masked["t"] - ts) < 0.1
    np.testing.assert_allclose(masked["yaw_rate"][~near], clean["yaw_rate"][~near], atol=1e-9)
    kept = cli("convert", run, *F1_SIGNALS, "--out", tmp_path / "kept.csv", "--keep-spikes")
    assert kept.returncode == 0, kept.stderr                          # 3 glitches do not make it 'degrees'
    assert "kept (--keep-spikes)" in kept.stdout and pd.read_csv(tmp_path / "kept.csv")["yaw_rate"].max() > 20


def _convert(source: Path, out: Path) -> Path:
    proc = cli("convert", source, *F1_SIGNALS, "--out", out)
    assert proc.returncode == 0, proc.stderr
    return out


def test_headerless_step_tests_take_their_time_from_another_table(tmp_path):
    m = STEPS / "measurement_17"
    proc = cli("convert", m, "--time", "time.col1[s]", "--signal", "x=trajectory.col1[m]", "--signal",
               "y=trajectory.col2[m]", "--signal", "heading=trajectory.col3[rad]", "--signal", "v=trajectory.col4[m/s]",
               "--signal", "delta_cmd=input.col1[rad]", "--out", tmp_path / "m17.csv")
    assert proc.returncode == 0, proc.stderr
    log = pd.read_csv(tmp_path / "m17.csv")
    time = np.loadtxt(m / "time.csv", delimiter=",")
    traj = np.loadtxt(m / "trajectory.csv", delimiter=",")
    inputs = np.loadtxt(m / "input.csv", delimiter=",")
    assert len(log) == 120 and np.allclose(log["t"], time[:120] - time[0])
    np.testing.assert_allclose(log[["x", "y", "heading", "v"]].to_numpy(), traj[:120], atol=1e-9)
    np.testing.assert_allclose(log["delta_cmd"], inputs[:, 0], atol=1e-12)      # one value per interval, held
    report = json.loads((tmp_path / "m17.import.json").read_text())
    assert "one row fewer: a value per interval" in report["tables"]["input"]["time"]
    refused(cli("convert", m, "--signal", "x=trajectory.col1[m]", "--out", tmp_path / "n.csv"),
            "trajectory.csv: no time column", "--time")


def test_a_tractor_loggers_csv_with_dates_kmh_and_float32_positions(tmp_path):
    from agrobot.measurements.raw_nmea import read_nmea_file

    e = read_nmea_file(NMEA / "haicom-305N.log").epochs
    e = e[e["quality"] > 0].reset_index(drop=True)
    when = pd.to_datetime(e["utc"], unit="s").dt.strftime("%d.%m.%Y %H:%M:%S.%f")
    table = pd.DataFrame({"Zeit": when, "Breite": e["lat"].astype(np.float32), "Laenge": e["lon"].astype(np.float32),
                          "Tempo": e["speed"] * 3.6})
    table.to_csv(tmp_path / "logger.csv", sep=";", index=False)
    proc = cli("convert", tmp_path / "logger.csv", "--time", "Zeit[datetime]", "--signal", "lat=Breite",
               "--signal", "lon=Laenge", "--signal", "v=Tempo[km/h]", "--out", tmp_path / "log.csv", "--rate", 1,
               "--trim-standstill")      # compared from the run's start, where the fixes follow the speed
    assert proc.returncode == 0, proc.stderr
    report = json.loads((tmp_path / "log.import.json").read_text())
    q = report["position_quantisation"]
    lat = float(e["lat"].median())
    expect_n = float(np.spacing(np.float32(e["lat"].abs().max()))) * math.pi / 180 * 6_371_000
    assert q["how"] == "latitude/longitude stored as float32" and q["north_m"] == pytest.approx(expect_n, rel=1e-6)
    assert report["resolution"]["y"] == pytest.approx(expect_n, rel=1e-6) and abs(lat) < 90
    assert "positions are quantised" in proc.stdout
    log = pd.read_csv(tmp_path / "log.csv")
    base = cli("convert", NMEA / "haicom-305N.log", "--out", tmp_path / "nmea.csv", "--trim-standstill")
    nmea = pd.read_csv(tmp_path / "nmea.csv")
    n = min(len(log), len(nmea))
    assert np.abs(log[["x", "y"]].to_numpy()[:n] - nmea[["x", "y"]].to_numpy()[:n]).max() < 2.0 and base.returncode == 0
    np.testing.assert_allclose(log["v"][:n], nmea["gnss_speed"][:n], atol=0.01)
    listing = cli("convert", tmp_path / "logger.csv", "--list", "--time", "Zeit[datetime]")
    assert "logger.Tempo" in listing.stdout and "date strings without a time zone, taken as UTC" in listing.stdout


def test_tables_whose_clocks_do_not_overlap_are_refused_naming_both(tmp_path):
    (tmp_path / "run").mkdir()
    pd.DataFrame({"t": np.arange(0, 20, 0.1), "v": 1.0}).to_csv(tmp_path / "run" / "wheel.csv", index=False)
    pd.DataFrame({"t": 1.7e9 + np.arange(0, 20, 0.1), "yaw": 0.1}).to_csv(tmp_path / "run" / "gyro.csv", index=False)
    refused(cli("convert", tmp_path / "run", "--signal", "v=wheel.v[m/s]", "--signal", "yaw_rate=gyro.yaw[rad/s]",
                "--out", tmp_path / "x.csv"),
            "the tables' clocks do not overlap", "wheel.csv", "gyro.csv", "one counts from its start, another from 1970")
    assert not (tmp_path / "x.csv").exists()


# --- ROS bags with custom topics ----------------------------------------------------------------------
@pytest.mark.slow
def test_a_bag_with_only_rosout_and_a_custom_topic_is_listed_and_read_with_a_declared_unit(tmp_path):
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore, get_types_from_msg

    store = get_typestore(Stores.ROS2_HUMBLE)
    store.register(get_types_from_msg("float64 steer_deg\nfloat64 gyro_dps\nfloat64 speed_kmh\n", "agro_msgs/msg/Drive"))
    Drive, Log = store.types["agro_msgs/msg/Drive"], store.types["rcl_interfaces/msg/Log"]
    Time = store.types["builtin_interfaces/msg/Time"]
    with Writer(tmp_path / "bag", version=8) as w:
        drive = w.add_connection("/tractor/drive", "agro_msgs/msg/Drive", typestore=store)
        log = w.add_connection("/rosout", "rcl_interfaces/msg/Log", typestore=store)
        for k in range(600):
            ns = int((1000 + 0.05 * k) * 1e9)
            w.write(drive, ns, store.serialize_cdr(Drive(steer_deg=5 * math.sin(0.1 * k), gyro_dps=3.0,
                                                         speed_kmh=7.2), "agro_msgs/msg/Drive"))
            if k % 100 == 0:
                w.write(log, ns, store.serialize_cdr(Log(stamp=Time(sec=1000 + k // 20, nanosec=0), level=20, name="n",
                                                         msg="hello", file="f", function="g", line=1),
                                                     "rcl_interfaces/msg/Log"))
    listing = cli("convert", tmp_path / "bag", "--list")
    assert listing.returncode == 0, listing.stderr
    assert "/rosout (rcl_interfaces/msg/Log)" in listing.stdout and "/tractor/drive.gyro_dps" in listing.stdout
    refused(cli("convert", tmp_path / "bag", "--out", tmp_path / "a.csv"), "no topic of a known type", "/rosout",
            "/tractor/drive (agro_msgs/msg/Drive)")
    refused(cli("convert", tmp_path / "bag", "--out", tmp_path / "b.csv", "--signal", "yaw_rate=/tractor/drive.gyro_dps"),
            "is a rate; declare it")
    proc = cli("convert", tmp_path / "bag", "--out", tmp_path / "c.csv", "--signal", "yaw_rate=/tractor/drive.gyro_dps[deg/s]",
               "--signal", "v=/tractor/drive.speed_kmh[km/h]", "--signal", "delta=/tractor/drive.steer_deg[deg]")
    assert proc.returncode == 0, proc.stderr
    log = pd.read_csv(tmp_path / "c.csv")
    assert np.allclose(log["yaw_rate"], math.radians(3.0)) and np.allclose(log["v"], 2.0)
    assert np.abs(log["delta"]).max() == pytest.approx(math.radians(5), rel=0.01)


# --- fields --------------------------------------------------------------------------------------------
def test_kml_kmz_and_isoxml_v3_give_the_same_field_as_the_geojson(tmp_path):
    from agrobot.fields import read_fields

    real = read_fields(REAL / "fields2cover_data" / "test.json")[0]
    lonlat = real.to_geodetic(np.asarray(real.boundary.exterior.coords))
    coords = " ".join(f"{lo:.9f},{la:.9f},0" for lo, la in lonlat)
    kml = (f'<?xml version="1.0" encoding="UTF-8"?><kml xmlns="http://www.opengis.net/kml/2.2"><Document><Placemark>'
           f'<name>north parcel</name><Polygon><outerBoundaryIs><LinearRing><coordinates>{coords}</coordinates>'
           f'</LinearRing></outerBoundaryIs></Polygon></Placemark><Placemark><name>AB 1</name><LineString><coordinates>'
           f'{lonlat[0][0]:.9f},{lonlat[0][1]:.9f} {lonlat[2][0]:.9f},{lonlat[2][1]:.9f}</coordinates></LineString>'
           f'</Placemark></Document></kml>')
    (tmp_path / "parcel.kml").write_text(kml)
    with zipfile.ZipFile(tmp_path / "parcel.kmz", "w") as z:
        z.writestr("doc.kml", kml)
    for name in ("parcel.kml", "parcel.kmz"):
        f = read_fields(tmp_path / name)[0]
        assert f.name == "north parcel" and f.area_ha == pytest.approx(real.area_ha, rel=1e-4)
        assert [g.name for g in f.lines] == ["AB 1"]
    pts = "".join(f'<PNT A="2" C="{la:.9f}" D="{lo:.9f}"/>' for lo, la in lonlat)
    (tmp_path / "TASKDATA.XML").write_text(
        f'<?xml version="1.0" encoding="UTF-8"?><ISO11783_TaskData VersionMajor="3" VersionMinor="3" '
        f'DataTransferOrigin="1"><PFD A="PFD1" C="v3 field" D="1"><PLN A="1"><LSG A="1">{pts}</LSG></PLN></PFD>'
        f'</ISO11783_TaskData>')
    v3 = read_fields(tmp_path / "TASKDATA.XML")[0]
    assert v3.name == "v3 field" and v3.area_ha == pytest.approx(real.area_ha, rel=1e-4)


def test_agopengps_names_in_any_case_and_a_folder_names_the_field_it_cannot_read(tmp_path):
    from agrobot.fields.readers import read_folder
    from tests.test_other_data import write_agopengps

    from agrobot.fields import read_fields

    real = next(f for f in read_fields(ISOXML / "PARTFIELDS_TASKDATA.XML") if f.name == "NM_Oxted_NullMeridian_Hole")
    good = write_agopengps(tmp_path / "farm" / "Oxted", real, [])
    (good / "Boundary.txt").rename(good / "Boundary.Txt")
    (good / "Field.txt").rename(good / "FIELD.TXT")
    empty = write_agopengps(tmp_path / "farm" / "Empty", real, [])
    (empty / "Boundary.txt").write_text("$Boundary\n")
    fields, skipped = read_folder(tmp_path / "farm")
    assert [f.name for f in fields] == ["Oxted"] and fields[0].boundary.area == pytest.approx(real.boundary.area, rel=1e-5)
    assert len(skipped) == 1 and "Empty" in skipped[0] and "no boundary ring" in skipped[0]
    proc = cli("fields", tmp_path / "farm")
    assert proc.returncode == 0 and "not read:" in proc.stdout and "Oxted" in proc.stdout


@pytest.mark.slow
def test_a_harvesters_track_becomes_a_field_the_planner_replans(tmp_path):
    proc = cli("fields", ISOXML / "TLG00002.xml", "--from-track", "--out", tmp_path / "f")
    assert proc.returncode == 0, proc.stderr
    data = json.loads((tmp_path / "f" / "fields.json").read_text())["fields"][0]
    assert data["area_ha"] > 0.5 and len(data["lines"]) >= 10
    from agrobot.fields.track import field_from_track
    from agrobot.measurements.isoxml_log import read_timelog
    from agrobot.measurements.recording import positions

    t, lat, lon, report = positions(ISOXML / "TLG00002.xml")
    table, _ = read_timelog(ISOXML / "TLG00002.xml")
    declared = float(table["ddi0067_actual_working_width"].median())       # the machine's own (DDI 67: mm -> m)
    estimated = field_from_track(t, lat, lon, "x", "TLG00002", None)               # from the passes' spacing
    assert estimated.properties["working_width_m"] == pytest.approx(declared, rel=0.35)
    plan = cli("plan", tmp_path / "f" / "fields.geojson", "--out", tmp_path / "p", "--max-swaths", 4,
               "--width", f"{declared:.2f}")
    assert plan.returncode == 0, plan.stderr
    assert (tmp_path / "p" / "route.csv").stat().st_size > 1000
    refused(cli("fields", NMEA / "nmea-rtk.log", "--from-track"), "nmea-rtk.log", "does not cover a field")


# --- one vocabulary -----------------------------------------------------------------------------------
def test_no_import_circle_in_measurements_and_components_do_not_import_it():
    import ast

    folder = ROOT / "src" / "agrobot" / "measurements"
    names = {p.stem for p in folder.glob("*.py")}
    deps = {}
    for p in folder.glob("*.py"):
        found = set()
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level == 1:
                found |= {node.module.split(".")[0]} if node.module else {a.name for a in node.names}
            elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("measurements."):
                found.add(node.module.split(".")[1])
        deps[p.stem] = found & names

    def reaches(a, b, seen=()):
        return any(d == b or (d not in seen and reaches(d, b, seen + (d,))) for d in deps[a])
    assert [m for m in names if reaches(m, m)] == []
    readers = ("raw_can", "raw_nmea", "nmea_can", "rosbag", "isoxml_log", "tables", "mdf4", "streams",
               "signal_expressions", "dbc", "quirks", "log", "recording_readers")
    assert not any(reaches(r, "recording") for r in readers)
    for p in (ROOT / "components").rglob("*.py"):
        assert "measurements" not in {(n.module or "").split(".")[0] for n in ast.walk(ast.parse(p.read_text()))
                                      if isinstance(n, ast.ImportFrom)} | {a.name.split(".")[0] for n in ast.walk(
                                          ast.parse(p.read_text())) if isinstance(n, ast.Import) for a in n.names}, p
