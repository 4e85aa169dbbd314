"""The import audit (measurements.audit) on generated recordings with a known truth
(tests/import_recordings.py): a channel group made 0.85 s late, dropouts of one channel, two
gyros that disagree, a gyro/accelerometer pair swapped, a "gyro" that is an accelerometer; the
audit must find each with the right number, and the log must come out right."""
from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from agrobot.measurements import LogError, read_log
from agrobot.measurements.audit import require_causal
from agrobot.measurements.recording import ImportOptions, import_recording
from agrobot.measurements.signal_expressions import parse_signal
from tests.import_recordings import DELAY, SIGNALS, write_recording

LATE = 0.85


def options(*extra, **kw) -> ImportOptions:
    return ImportOptions(signals=[parse_signal(s) for s in SIGNALS + extra], wheelbase=0.32, **kw)


def kinds(frame_or_report, kind):
    found = frame_or_report.attrs["audit"] if hasattr(frame_or_report, "attrs") else frame_or_report["audit"]["findings"]
    return [f for f in found if f["kind"] == kind]


@pytest.fixture(scope="module")
def late(tmp_path_factory):
    return write_recording(tmp_path_factory.mktemp("late") / "rec", seconds=75.0, late=LATE)


@pytest.fixture(scope="module")
def late_none(late):
    return import_recording(late, options(align="none"))


def test_a_late_group_is_found_with_its_interval_and_aligned(late):
    frame, report = import_recording(late, options())
    offset = [f for f in kinds(frame, "clock_offset") if f["channels"] == ["gnss_speed", "v"]]
    assert len(offset) == 1 and abs(offset[0]["value"] - LATE) < 0.03, offset
    assert offset[0]["interval"][0] <= LATE <= offset[0]["interval"][1] and offset[0]["resolved"]
    assert report["audit"]["alignment"]["channels_moved"] == ["delta_cmd", "v"]
    # after alignment the steering leads the yaw rate by the truth's delay (independent: the
    # generated drive's own DELAY), and the earlier lead is named as resolved
    lead = kinds(frame, "response_leads_input")
    assert lead and lead[0]["resolved"] and abs(lead[0]["value"] - (LATE - DELAY)) < 0.05
    require_causal(frame, "identify")            # no refusal once aligned
    assert not kinds(frame, "mislabelled_channel") and not kinds(frame, "scale_disagreement")
    # the log itself: delta_cmd on the true clock, so v tan(delta_cmd(t - DELAY)) / L is yaw_rate
    t = frame["t"].to_numpy()
    kin = np.interp(t - DELAY, t, frame["v"] * np.tan(frame["delta_cmd"]) / 0.32)
    ok = t > t[0] + 1
    assert np.sqrt(np.mean((kin[ok] - frame["yaw_rate"].to_numpy()[ok]) ** 2)) < 0.1 * np.std(frame["yaw_rate"])


def test_a_response_that_leads_is_refused_unless_aligned(late_none):
    frame, report = late_none
    lead = kinds(frame, "response_leads_input")
    assert len(lead) == 1 and not lead[0]["resolved"]
    assert abs(lead[0]["value"] - (LATE - DELAY)) < 0.05 and lead[0]["interval"][0] < LATE - DELAY < lead[0]["interval"][1]
    with pytest.raises(LogError, match="BEFORE the steering"):
        require_causal(frame, "identify")
    assert "--align bywire=0.8" in " ".join(f["meaning"] for f in kinds(frame, "clock_offset"))


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_the_audit_is_persisted_with_the_written_log(late, tmp_path, suffix, capsys):
    from agrobot.orchestrator.cli import main

    out = tmp_path / f"log{suffix}"
    args = ["convert", str(late), "--align", "none", "--out", str(out), "--wheelbase", "0.5"]
    for s in SIGNALS:
        args += ["--signal", s]
    assert main(args) == 0
    printed = capsys.readouterr().out
    assert "audit response_leads_input" in printed and "audit clock_offset" in printed
    back = read_log(out, ("t",))
    assert kinds(back, "response_leads_input") and not kinds(back, "response_leads_input")[0]["resolved"]
    side = json.loads(out.with_name("log.import.json").read_text())
    assert side["audit"]["findings"] == back.attrs["audit"]
    from agrobot.identification.from_log import read_uneven

    with pytest.raises(LogError, match="response leads its input"):
        read_uneven(out)


@pytest.mark.slow
def test_identify_recovers_the_truth_after_auto_alignment(tmp_path):
    from agrobot.identification.ordinary_driving import identify_driving
    from agrobot.orchestrator.study import Study
    from tests.vehicle_logs import ROOT_STUDIES

    study = Study.load(ROOT_STUDIES / "f1tenth.toml")
    rec = write_recording(tmp_path / "rec", seconds=50.0, late=LATE, seed=4)
    frame, _ = import_recording(rec, options(rate=25.0))
    rep = identify_driving(frame, "aligned", study, max_fit_seconds=30.0)
    total = rep["delay"]["value"] + rep["parameters"].get("lag", {"value": 0.0})["value"]
    assert abs(total - DELAY) < 0.05, rep["delay"]


def test_one_channels_dropouts_are_bridged_and_counted(tmp_path):
    rng = np.random.default_rng(5)
    starts = np.sort(rng.uniform(5, 55, 12))
    starts = starts[np.concatenate([[True], np.diff(starts) > 1.5])]
    lengths = rng.uniform(0.22, 0.45, len(starts))
    rec = write_recording(tmp_path / "rec", seconds=60.0, drops=list(zip(starts, starts + lengths)))

    def steering_report(**kw):          # the kit's steering report: a measured wheel angle
        return ImportOptions(signals=[parse_signal(s.replace("delta_cmd=", "delta=")) for s in SIGNALS],
                             wheelbase=0.32, **kw)
    frame, report = import_recording(rec, steering_report(max_gap=0.5))
    bridged = [f for f in kinds(frame, "gap_bridged") if f["channels"] == ["delta"]]
    assert len(bridged) == 1 and str(len(starts)) + " gap(s)" in bridged[0]["meaning"] and "linear" in bridged[0]["meaning"]
    # the longest silence between stamps: the dropout plus up to a 30 Hz period on either side
    assert lengths.max() <= bridged[0]["value"] <= lengths.max() + 2 / 30 + 1e-3
    assert len(report["runs"]) == 1 and report["used"]["duration"] > 55.0
    frame0, report0 = import_recording(rec, steering_report(max_gap=0.0))
    assert report0["used"]["duration"] < 30.0 and kinds(frame0, "gap_split")
    assert "--max-gap" in kinds(frame0, "gap_split")[0]["meaning"]


def test_two_gyros_that_disagree_are_named(tmp_path):
    rec = write_recording(tmp_path / "rec", seconds=60.0, second_imu=(1.1, 0.3))
    frame, _ = import_recording(rec, options("yaw_rate_2=imu2.wz[rad/s]"))
    pair = [f for f in frame.attrs["audit"] if f["channels"] == ["yaw_rate", "yaw_rate_2"]]
    offset = [f for f in pair if f["kind"] == "clock_offset"][0]
    scale = [f for f in pair if f["kind"] == "scale_disagreement"][0]
    assert abs(offset["value"] - 0.3) < 0.03 and abs(scale["value"] - 1.1) < 0.02
    ambiguous = [f for f in pair if f["kind"] == "ambiguous_channel"]
    assert ambiguous and "against the GNSS course: yaw_rate x 1, yaw_rate_2 x 1.1" in ambiguous[0]["meaning"]


def test_a_swapped_gyro_and_accelerometer_are_named(tmp_path):
    rec = write_recording(tmp_path / "rec", seconds=60.0, swap=True)
    frame, _ = import_recording(rec, options())
    swapped = kinds(frame, "mislabelled_channel")
    assert swapped and swapped[0]["channels"] == ["yaw_rate", "ay"] and swapped[0]["value"] < 0.1


def test_a_gyro_whose_mean_is_g_is_named(tmp_path):
    rec = write_recording(tmp_path / "rec", seconds=40.0)
    imu = pd.read_csv(rec / "imu.csv", dtype={"t": str})
    imu["wz"] = 9.81 + 0.05 * np.random.default_rng(0).standard_normal(len(imu))
    imu.to_csv(rec / "imu.csv", index=False)
    frame, _ = import_recording(rec, options(align="none"))
    g = kinds(frame, "mislabelled_channel")
    assert g and g[0]["channels"] == ["yaw_rate"] and abs(g[0]["value"] - 9.81) < 0.02


@pytest.mark.parametrize("align, expect", [("nowhere=0.3", "no group or column 'nowhere'"),
                                           ("bywire=500", "larger than the recording"),
                                           ("bywire", "expected auto, none, or GROUP=SECONDS")])
def test_a_bad_alignment_is_refused_by_name(late, align, expect):
    with pytest.raises(LogError, match=expect):
        import_recording(late, options(align=align))


def test_a_given_alignment_is_applied_and_said(late):
    frame, report = import_recording(late, options(align=f"bywire={LATE}"))
    assert report["audit"]["alignment"]["offsets_s"] == {"bywire": LATE}
    assert kinds(frame, "response_leads_input")[0]["resolved"]


# --- SI out of every reader: an ISO 11783-10 time log in its DDI units --------------------------------
def test_ddi_raw_units_become_si_with_the_measured_speed_as_v_and_the_terminal_clock_named(tmp_path):
    from tests.import_recordings import write_ddi_timelog

    rec = write_ddi_timelog(tmp_path / "tlg", speed_mm_s=2500, yaw_mdeg=45000, clock_ahead=2040.0)
    frame, report = import_recording(rec, ImportOptions())
    assert np.allclose(frame["v"], 2.5) and np.allclose(frame["ddi0144_yaw_angle"], np.pi / 4)
    clock = [f for f in frame.attrs["audit"] if f["kind"] == "terminal_clock"]
    assert clock and abs(clock[0]["value"] - 2040.0) < 1e-3
    frame, _ = import_recording(rec, ImportOptions(signals=[parse_signal("heading=DDI144")]))
    assert np.allclose(frame["heading"], np.pi / 4)
    with pytest.raises(LogError, match="near names: ddi0144_yaw_angle"):
        import_recording(rec, ImportOptions(signals=[parse_signal("heading=ddi0144_yaw_angel[rad]")]))


# --- text as it comes ------------------------------------------------------------------------------
def test_headerless_txt_dumps_are_tables_with_the_time_guessed_and_said(tmp_path):
    rec = write_recording(tmp_path / "rec", seconds=40.0)
    dump = tmp_path / "dump"
    dump.mkdir()
    for name in ("imu", "bywire"):
        table = pd.read_csv(rec / f"{name}.csv", dtype={"t": str})
        table.to_csv(dump / f"{name}.txt", sep=" ", header=False, index=False)
    frame, report = import_recording(dump, ImportOptions(signals=[parse_signal(s) for s in (
        "yaw_rate=imu.col2[rad/s]", "v=bywire.col3[m/s]", "delta_cmd=bywire.col2[rad]")]))
    assert "guessed" in report["tables"]["imu"]["time"] and "col1" in report["tables"]["imu"]["time"]
    truth = pd.read_csv(rec / "imu.csv")
    assert abs(frame["yaw_rate"].std() - truth["wz"].std()) < 0.05 * truth["wz"].std()


def test_a_csv_whose_rows_are_quoted_whole_is_unwrapped(tmp_path):
    rec = write_recording(tmp_path / "rec", seconds=40.0)
    quoted = tmp_path / "quoted"
    quoted.mkdir()
    for name in ("imu", "bywire", "gnss"):
        lines = (rec / f"{name}.csv").read_text().splitlines()
        (quoted / f"{name}.csv").write_text("".join(f'"{line}"\n' for line in lines))
    frame, report = import_recording(quoted, options())
    plain, _ = import_recording(rec, options())
    assert np.allclose(frame["yaw_rate"], plain["yaw_rate"]) and np.allclose(frame["x"], plain["x"])
    assert any("wrapped in quotes" in n for n in report["notes"])


# --- the user's word stands ------------------------------------------------------------------------
def test_a_declared_unit_is_kept_with_a_warning_where_the_heuristic_disagrees(tmp_path):
    from agrobot.measurements import load_log

    rec = write_recording(tmp_path / "rec", seconds=40.0)
    signals = [s for s in SIGNALS if not s.startswith("yaw_rate")] + ["yaw_rate=4*imu.wz[rad/s]"]
    frame, report = load_log(rec, ("t",), recording=ImportOptions(signals=[parse_signal(s) for s in signals],
                                                                  wheelbase=0.32))
    truth = pd.read_csv(rec / "imu.csv")
    assert frame["yaw_rate"].abs().max() > 3.0 and abs(frame["yaw_rate"].std() / truth["wz"].std() - 4) < 0.2
    assert any("kept as declared [rad/s]" in n for n in report["notes"])
    # the same values in a table without a declaration: the heuristic refuses, naming the unit
    frame.to_csv(tmp_path / "log.csv", index=False)
    with pytest.raises(LogError, match="looks like degrees"):
        read_log(tmp_path / "log.csv", ("t",))


# --- minimums as guidance ---------------------------------------------------------------------------
def test_a_minimum_is_guidance_down_to_its_floor():
    from agrobot.measurements.audit import minimum

    assert minimum(20.0, 20.0, "driving") is None
    assert "under the nominal 20 s" in minimum(19.0, 20.0, "driving") and "floor 13.3 s" in minimum(14.0, 20.0, "driving")
    with pytest.raises(LogError, match="under the floor 13.3 s .* nominal 20 s"):
        minimum(13.0, 20.0, "driving")


def test_a_run_just_under_the_minimum_is_used_with_a_warning(tmp_path):
    rec = write_recording(tmp_path / "rec", seconds=9.0)
    frame, report = import_recording(rec, options(min_run=10.0))
    assert 7.0 < report["used"]["duration"] < 10.0 and report["used"]["how"].startswith("run 1")
    assert any("under the nominal 10 s" in n for n in report["notes"])
    # under the floor (2/3 of 13 s): not a run; the longest stretch is used, and the note says the
    # vehicle drives (a short drive, not a standstill)
    frame, report = import_recording(rec, options(min_run=13.0))
    assert report["used"]["how"].startswith("the longest stretch") and report["runs"] == []
    assert any("the vehicle drives" in n and "too short" in n for n in report["notes"])


# --- bad input: exit 2, named, nothing written ---------------------------------------------------------
@pytest.mark.parametrize("case, expect", [("impossible", "none of the log's columns"), ("zeros", "empty table"),
                                          ("text", "no column to take"), ("align", "larger than the recording")])
def test_bad_input_exits_2_naming_it_and_writes_nothing(tmp_path, capsys, case, expect):
    from agrobot.orchestrator.cli import main
    from harness.generated_recordings import write_timelog

    extra = []
    if case == "impossible":                        # a time log whose every fix is impossible
        source = write_timelog(tmp_path / "tlg", 30, lat_at={k: 95.0 for k in range(30)})
    elif case == "zeros":
        source = tmp_path / "zeros.csv"
        source.write_bytes(bytes(1000))
    elif case == "text":
        source = tmp_path / "text.csv"
        source.write_text("a,b\nx,y\nz,w\n")
    else:
        source = write_recording(tmp_path / "rec", seconds=30.0)
        extra = ["--align", "bywire=100"] + [a for s in SIGNALS for a in ("--signal", s)]
    out = tmp_path / "out" / "log.csv"
    assert main(["convert", str(source), "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert expect in err and str(source) in err and "Traceback" not in err
    assert not out.exists()


# --- a bag: two IMU topics, header stamps against receive times ---------------------------------------
def test_a_bags_second_gyro_and_its_receive_delays_are_named(tmp_path):
    from rosbags.rosbag2 import StoragePlugin, Writer

    from agrobot.measurements.rosbag import typestore
    from tests.import_recordings import truth
    from tests.test_other_data import _imu, _navsat

    drive = truth(60.0, h=0.01)
    store = typestore()
    rng = np.random.default_rng(7)
    delays = rng.uniform(0.06, 0.56, 10_000)          # the robot's receive delays (truth)
    used = []
    with Writer(tmp_path / "bag", version=8, storage_plugin=StoragePlugin.SQLITE3) as w:
        fix = w.add_connection("/fix", "sensor_msgs/msg/NavSatFix", typestore=store)
        imus = [w.add_connection(name, "sensor_msgs/msg/Imu", typestore=store) for name in ("/imu", "/imu_b")]
        for k, row in enumerate(drive.iloc[::10].itertuples()):
            utc = 1.7e9 + row.t
            d = delays[k]
            used.append(d)
            w.write(fix, int((utc + d) * 1e9), store.serialize_cdr(
                _navsat(store, "sensor_msgs/msg/NavSatFix", utc, row.lat, row.lon, 10.0, 4), "sensor_msgs/msg/NavSatFix"))
            for conn, scale in zip(imus, (1.0, 1.2)):
                w.write(conn, int((utc + 0.01) * 1e9), store.serialize_cdr(_imu(store, utc, scale * row.r),
                                                                             "sensor_msgs/msg/Imu"))
    frame, report = import_recording(tmp_path / "bag", ImportOptions())
    stamps = [f for f in frame.attrs["audit"] if f["kind"] == "stamp_vs_receive" and f["channels"] == ["/fix"]]
    assert stamps and abs(stamps[0]["value"] - np.median(used)) < 0.01
    assert abs(stamps[0]["interval"][0] - min(used)) < 0.01 and abs(stamps[0]["interval"][1] - max(used)) < 0.01
    assert "yaw_rate_2" in frame and any("/imu_b" in n for n in report["notes"])
    pair = [f for f in frame.attrs["audit"] if f["channels"] == ["yaw_rate", "yaw_rate_2"]]
    assert any(f["kind"] == "ambiguous_channel" and abs(f["value"] - 1.2) < 0.02 for f in pair)


def test_a_plain_log_table_is_audited_on_its_own_columns(tmp_path, late_none):
    """A log written without its import report (a table from elsewhere) with the steering 0.7 s
    behind the yaw rate: load_log finds the lead on the table's own columns."""
    from agrobot.measurements import load_log

    frame, _ = late_none
    frame[["t", "delta_cmd", "v", "yaw_rate"]].to_csv(tmp_path / "plain.csv", index=False)
    back, _ = load_log(tmp_path / "plain.csv")
    lead = [f for f in back.attrs["audit"] if f["kind"] == "response_leads_input"]
    assert lead and abs(lead[0]["value"] - (LATE - DELAY)) < 0.05 and not lead[0]["resolved"]


def test_signal_works_for_nmea_and_an_unknown_name_is_refused_with_the_near_names(tmp_path):
    from harness.generated_recordings import write_nmea

    nmea = write_nmea(tmp_path / "gps.nmea", 60.0)
    frame, report = import_recording(nmea, ImportOptions(signals=[parse_signal("v=gnss.speed")]))
    assert np.allclose(frame["v"], frame["gnss_speed"]) and "gnss.speed" in report["columns"]["v"]
    with pytest.raises(LogError, match="near names: gnss.speed"):
        import_recording(nmea, ImportOptions(signals=[parse_signal("v=gnss.sped[m/s]")]))
