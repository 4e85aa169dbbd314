"""Raw field recordings in: NMEA files and CAN logs -> the measured log, clocks,
gaps and runs, the round trip run --record -> import -> diagnose, and ISO 11783-7 guidance."""
from __future__ import annotations

import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from agrobot.components.hardware.guidance_messages import ISOBUS_DBC
from agrobot.components.hardware.record import record_study
from agrobot.measurements import LogError
from agrobot.measurements.recording import ImportOptions, import_recording, import_runs
from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.study import Study
from tests.commands import cli

ROOT = Path(__file__).resolve().parents[1]
EPOCH = 1777622400.0          # the recorder's default epoch, 2026-05-01T08:00:00Z
LEVER = {"tractor.tractor.antenna_forward": 0.8, "tractor.tractor.antenna_left": 0.3}


def record(folder: Path, stop: float, values: dict | None = None, overrides: tuple = ()) -> Path:
    study = Study.load(ROOT / "studies" / "field_test.toml", [f"study.stop_time={stop}", *overrides])
    study = record_study(study, folder)
    if values:
        study = study.with_values(values)
    run_study(study, folder.parent / (folder.name + "_run"), plots=False, overwrite=True, named=(folder,))
    return folder


def against_simulation(frame: pd.DataFrame, report: dict, folder: Path) -> pd.DataFrame:
    """The simulation's own log at the imported log's instants (t from the run's start)."""
    ref = pd.read_csv(folder / "simulation_log.csv")
    start = report["used"]["start"]
    ref = ref.assign(key=np.round((ref["t"] - start) / 0.05).astype(int))
    got = frame.assign(key=np.round(frame["t"] / 0.05).astype(int))
    return got.merge(ref, on="key", suffixes=("", "_sim"))


def drive(folder: Path, stop: float) -> Path:
    """A test drive of STOP s recorded on the buses, through ``run --record``, of a tractor whose GPS
    antenna sits 0.8 m ahead and 0.3 m left of R."""
    args = [a for k, v in LEVER.items() for a in ("--set", f"{k}={v}")]
    proc = cli("run", ROOT / "studies" / "field_test.toml", "--out", folder.parent / "run", "--record", folder,
               "--no-plots", "--set", f"study.stop_time={stop}", *args)
    assert proc.returncode == 0, proc.stderr
    return folder


@pytest.fixture(scope="module")
def lever_recording(tmp_path_factory) -> Path:
    """The whole 240 s drive (what the diagnosis of the lever arm needs)."""
    return drive(tmp_path_factory.mktemp("field") / "recording", 240.0)


@pytest.fixture(scope="module")
def short_recording(tmp_path_factory) -> Path:
    """Its first 130 s (six speed changes between 1, 2 and 3 m/s): what the
    readers, the clocks and the runs need."""
    return drive(tmp_path_factory.mktemp("field") / "recording", 130.0)


@pytest.mark.slow
def test_imported_recording_equals_the_simulations_own_log(lever_recording):
    frame, report = import_recording(lever_recording)
    both = against_simulation(frame, report, lever_recording)
    assert len(both) == len(frame) > 4000
    # what the buses quantise: 1e-4 rad and rad/s, 1e-3 m/s (DBC); positions 0.2 mm (NMEA minutes)
    assert np.abs(both["delta_cmd"] - both["delta_cmd_sim"]).max() < 6e-5
    assert np.abs(both["delta"] - both["delta_sim"]).max() < 3e-4
    assert np.abs(both["v"] - both["v_sim"]).max() < 1e-3
    assert np.abs(both["yaw_rate"] - both["yaw_rate_sim"]).max() < 5e-4
    for c in ("x", "y"):
        shifted = both[f"{c}_sim"] - both[f"{c}_sim"].iloc[0]
        assert np.abs(both[c] - shifted).max() < 5e-3
    assert report["gaps"] == [] and len(report["runs"]) == 1 and report["used"]["how"].startswith("run 1")
    assert report["clocks"]["can_clock"]["method"].startswith("same host clock")


@pytest.mark.slow
def test_round_trip_finds_the_hidden_effect_as_from_the_simulation_log(lever_recording, tmp_path):
    from agrobot.diagnosis.pipeline import diagnose

    raw = diagnose(lever_recording, tmp_path / "raw", plots=False, identify=False)
    own = diagnose(lever_recording / "simulation_log.csv", tmp_path / "own", plots=False, identify=False)
    assert raw["verdict"] == own["verdict"] == "antenna_lever_arm"
    found = {}
    for name, result in (("raw", raw), ("own", own)):
        e = next(e for e in result["effects"] if e["id"] == "antenna_lever_arm")
        found[name] = np.array([e["parameters"]["antenna_forward"], e["parameters"]["antenna_left"]])
        assert np.abs(found[name] - [0.8, 0.3]).max() < 0.02, (name, found[name])
    assert np.abs(found["raw"] - found["own"]).max() < 0.01
    assert raw["recording"]["used"]["how"].startswith("run 1")
    assert "imported from a raw recording" in (tmp_path / "raw" / "report.md").read_text()


def test_candump_asc_and_blf_read_the_same(short_recording, tmp_path):
    import can

    base, _ = import_recording(short_recording)
    for suffix in (".asc", ".blf"):
        folder = tmp_path / suffix[1:]
        folder.mkdir()
        shutil.copy(short_recording / "gps.nmea", folder)
        with can.Logger(str(folder / f"bus{suffix}")) as log:
            for msg in can.LogReader(str(short_recording / "can.log")):
                log(msg)
        frame, _ = import_recording(folder)
        assert len(frame) == len(base)
        # ASC writes times to the microsecond, as candump does
        assert np.abs(frame[["delta_cmd", "delta", "v", "yaw_rate"]].to_numpy()
                      - base[["delta_cmd", "delta", "v", "yaw_rate"]].to_numpy()).max() < 1e-9


def test_host_clock_offset_drift_and_nmea_latency_are_estimated(tmp_path):
    # a host clock that keeps UTC: the offset of the envelope is the least NMEA latency (80 ms)
    synced = record(tmp_path / "synced", 120.0, {"bus_recorder.nmea_latency": 0.08,
                                                  "bus_recorder.nmea_latency_jitter": 0.03})
    frame, report = import_recording(synced)
    h = report["clocks"]["nmea_host_clock"]
    assert abs(h["nmea_latency_s"]["least"] - 0.08) < 0.002 and abs(h["drift_ppm"]) < 5
    assert 0.09 < h["nmea_latency_s"]["median"] < 0.10 and h["nmea_latency_s"]["max"] <= 0.1101
    both = against_simulation(frame, report, synced)
    assert np.abs(both["yaw_rate"] - both["yaw_rate_sim"]).max() < 5e-4      # CAN on the GPS time base
    # a free-running host clock, one hour and 0.25 s ahead, 50 ppm fast
    free = record(tmp_path / "free", 120.0, {"bus_recorder.host_clock_offset": 3600.25,
                                              "bus_recorder.host_clock_drift": 50e-6,
                                              "bus_recorder.nmea_latency_jitter": 0.03})
    frame, report = import_recording(free)
    h = report["clocks"]["nmea_host_clock"]
    assert abs(h["offset_s"] - 3600.25) < 0.002 and abs(h["drift_ppm"] - 50) < 2
    both = against_simulation(frame, report, free)
    assert np.abs(both["delta_cmd"] - both["delta_cmd_sim"]).max() < 6e-5


def test_a_can_logger_with_its_own_clock_is_aligned_by_the_speed(short_recording, tmp_path):
    folder = tmp_path / "own_clock"
    folder.mkdir()
    # NMEA without host stamps (the receiver's UTC only); the CAN logger counts from its power-up
    lines = (short_recording / "gps.nmea").read_text().splitlines()
    (folder / "gps.nmea").write_text("\n".join(line.split(" ", 1)[1] for line in lines) + "\n")
    text = []
    for line in (short_recording / "can.log").read_text().splitlines():
        stamp, rest = line.split(")", 1)
        t = float(stamp[1:]) - EPOCH + 12.5
        text.append(f"({t:.6f}){rest}")
    (folder / "logger.log").write_text("\n".join(text) + "\n")
    frame, report = import_recording(folder)
    k = report["clocks"]["can_clock"]
    assert k["method"].startswith("independent clock")
    # the simulated tractor's GPS reaches its host one GPS period (50 ms) late (the diagnosis finds
    # gps_latency 0.05 s in every log of it): aligned on content, the CAN data follow that lag
    # (a true offset of EPOCH - 12.5 s): the estimate lies between the clock offset and that lag
    assert -0.01 < k["offset_s"] - (EPOCH - 12.5) < 0.075, k
    assert "nmea_host_clock" not in report["clocks"]
    both = against_simulation(frame, report, short_recording)
    assert np.sqrt(np.mean((both["v"] - both["v_sim"]) ** 2)) < 0.01


def test_gaps_split_runs_and_a_run_or_time_range_is_chosen(short_recording, tmp_path):
    folder = tmp_path / "gap"
    folder.mkdir()
    shutil.copy(short_recording / "can.log", folder)
    kept = []
    for line in (short_recording / "gps.nmea").read_text().splitlines():
        t = float(line.split(" ", 1)[0]) - EPOCH
        if not 30.0 <= t < 31.5:                   # the receiver lost 1.5 s
            kept.append(line)
    (folder / "gps.nmea").write_text("\n".join(kept) + "\n")
    frame, report = import_recording(folder)
    assert [g["stream"] for g in report["gaps"]] == ["gnss"]
    g = report["gaps"][0]
    assert abs(g["start"] - 29.95) < 0.06 and abs(g["duration"] - 1.55) < 0.06     # s after the first fix
    assert len(report["runs"]) == 2 and report["runs"][0]["end"] < g["start"] + 1e-6 < g["end"] <= report["runs"][1]["start"]
    assert report["used"]["how"] == "run 2 (the longest)"
    first, rep1 = import_recording(folder, ImportOptions(run=1))
    kept = sum(rep1["used"].get("standstill_kept", [0.0, 0.0]))     # the standstill either side, kept
    assert rep1["used"]["how"].startswith("run 1") and abs(first["t"].iloc[-1] - kept
                                                           - (report["runs"][0]["end"] - report["runs"][0]["start"])) < 0.06
    every = import_runs(folder)                            # the files read once, each run assembled
    assert [r["used"]["run"] for _, r in every] == [1, 2] and len(every[0][0]) == len(first)
    assert np.array_equal(every[1][0].to_numpy(), frame.to_numpy())
    part, rep = import_recording(folder, ImportOptions(time_range=(40.0, 80.0)))
    assert abs(part["t"].iloc[-1] - 40.0) < 0.06 and rep["used"]["how"] == "time range"
    with pytest.raises(LogError, match="crosses a gap.*gnss silent from 29.95"):
        import_recording(folder, ImportOptions(time_range=(20.0, 40.0)))
    with pytest.raises(LogError, match="--run 3: the recording has 2 run"):
        import_recording(folder, ImportOptions(run=3))


def test_nmea_variants_are_read(short_recording, tmp_path):
    """GP talker, no RMC/ZDA date (date from the host stamps), junk and corrupted lines counted."""
    from agrobot.measurements.raw_nmea import read_nmea_file

    lines = (short_recording / "gps.nmea").read_text().splitlines()
    out = []
    for i, line in enumerate(lines):
        stamp, sentence = line.split(" ", 1)
        if sentence[3:6] in ("RMC", "ZDA"):
            continue
        if sentence.startswith("$GN"):                 # recompute the checksum for the GP talker
            body = "GP" + sentence[3:sentence.index("*")]
            check = 0
            for ch in body.encode():
                check ^= ch
            sentence = f"${body}*{check:02X}"
        if i == 42:                                    # a GGA
            sentence = sentence[:-2] + "00"            # a bad checksum
        out.append(f"{stamp} {sentence}")
    out.insert(10, "garbage without a sentence")
    out.insert(11, "1777622400.1 $GPGSV,3,1,12,01,40,083,46*7C")
    path = tmp_path / "receiver.nmea"
    path.write_text("\n".join(out) + "\n")
    rec = read_nmea_file(path)
    ref = read_nmea_file(short_recording / "gps.nmea")
    assert rec.counts["bad checksum"] == 1 and rec.counts["not a sentence"] == 1 and rec.counts["unused GSV"] == 1
    assert any("date is taken from the host stamps" in n for n in rec.notes)
    assert lines[42].split(" ", 1)[1][3:6] == "GGA" and len(rec.epochs) == len(ref.epochs) - 1
    merged = rec.epochs.merge(ref.epochs, on="utc", suffixes=("", "_ref"))
    assert len(merged) >= len(rec.epochs) - 1 and np.abs(merged["lat"] - merged["lat_ref"]).max() < 1e-12


def test_isobus_recording_decodes_through_the_wheelbase(tmp_path):
    folder = record(tmp_path / "iso", 60.0, {"bus_recorder.protocol": "isobus"})
    frame, report = import_recording(folder, ImportOptions(dbc=ISOBUS_DBC))
    assert "curvature to wheel angle" in report["columns"]["delta"]
    both = against_simulation(frame, report, folder)
    # 0.25 /km of curvature is 0.35 mrad of wheel angle at L = 1.4 m
    assert np.abs(both["delta_cmd"] - both["delta_cmd_sim"]).max() < 2e-4
    assert np.abs(both["delta"] - both["delta_sim"]).max() < 4e-4
    assert np.abs(both["v"] - both["v_sim"]).max() < 1e-3
    # the project's DBC knows none of these 29-bit frames: it says so
    with pytest.raises(LogError, match="unknown identifiers: 0xCADFF1C"):
        import_recording(folder)


@pytest.mark.slow
def test_bad_recordings_and_options_are_named(lever_recording, tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "notes.md").write_text("nothing recorded here\n")
    cases = [
        (["convert", str(tmp_path / "nowhere"), "--out", str(tmp_path / "a.csv")], "nowhere: no such file or folder"),
        (["convert", str(empty), "--out", str(tmp_path / "a.csv")], "no recording in it: expected ROS bags"),
        (["convert", str(lever_recording), "--out", str(tmp_path / "a.csv"), "--signal", "delta=Foo"],
         "--signal delta=Foo: no signal 'Foo'"),
        (["convert", str(lever_recording), "--out", str(tmp_path / "a.csv"), "--signal", "v=TractorFeedback.Nope"],
         "no signal 'TractorFeedback.Nope'; near names: TractorFeedback."),
        (["convert", str(lever_recording), "--out", str(tmp_path / "a.csv"), "--run", "4"], "--run 4: the recording has 1 run"),
        (["convert", str(lever_recording), "--out", str(tmp_path / "a.txt")], "expected a path ending in .csv or .parquet"),
        (["diagnose", str(lever_recording), "--out", str(tmp_path / "d"), "--dbc", str(tmp_path / "x.dbc")],
         "x.dbc: no such file"),
    ]
    for argv, expected in cases:
        proc = cli(*argv)
        assert proc.returncode == 2 and expected in proc.stderr, (argv, proc.stderr)
    assert not (tmp_path / "a.csv").exists()


def test_convert_writes_the_log_and_its_report(short_recording, tmp_path):
    import json

    from agrobot.measurements import read_log

    out = tmp_path / "converted" / "field.csv"
    proc = cli("convert", str(short_recording), "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    assert "used: run 1 (the longest)" in proc.stdout
    log = read_log(out)                                   # the measured-log type, checks included
    report = json.loads(out.with_name("field.import.json").read_text())
    assert math.isclose(log["t"].iloc[-1], report["used"]["duration"] - 0.05, abs_tol=1e-6)


# --- ISO 11783-7 guidance on a live (virtual) bus ----------------------------------------------

def _iso_pair(**tractor_params):
    import random

    from agrobot.components.can_actuators import CANActuators
    from agrobot.components.can_tractor_link import CANTractorLink

    channel = f"iso{random.getrandbits(32)}"
    common = {"interface": "virtual", "channel": channel, "protocol": "isobus", "wheelbase": 1.4}
    guidance = CANActuators("act", common)
    tractor = CANTractorLink("link", {**common, "command_timeout": 0.5, **tractor_params})
    guidance.initialize(0.0, 0.05)
    tractor.initialize(0.0, 0.05)
    return guidance, tractor


def test_isobus_frames_have_the_iso_11783_7_layout():
    """Bytes written by hand from ISO 11783-7 (curvature 0.25 /km per bit, offset -8032 /km, little
    endian; status in the low two bits of byte 3; readiness bits 3-4, lockout bits 1-2 of byte 3 of
    the machine info), 29-bit identifiers of PGN 44288 and 44032 at priority 3."""
    import can

    guidance, tractor = _iso_pair(lockout_after=0.1)
    spy = can.Bus(interface="virtual", channel=guidance.p["channel"])
    try:
        delta = 0.1                                          # left: ISO curvature is negative (right positive)
        guidance.u.update(steer_angle_cmd=delta, speed_cmd=2.5, safe_state=0.0)
        guidance.actuate(0.0)
        frames = [spy.recv(1.0), spy.recv(1.0)]
        command = next(f for f in frames if (f.arbitration_id >> 8) & 0x3FF00 == 44288)
        assert command.is_extended_id and command.arbitration_id >> 26 == 3
        raw = round((-1000.0 * math.tan(delta) / 1.4 + 8032.0) / 0.25)
        assert command.data[0] | command.data[1] << 8 == raw and command.data[2] & 0x03 == 1
        assert all(b == 0xFF for b in command.data[3:]) and command.data[2] >> 2 == 0x3F     # reserved bits 1
        speed = next(f for f in frames if (f.arbitration_id >> 8) & 0x3FFFF == 64835)
        assert speed.data[0] | speed.data[1] << 8 == 2500
        tractor.u.update(steer_angle_measured=-0.05, yaw_rate=0.2, speed=2.5)
        tractor.step(0.2, 0.05)                              # the lockout is set at 0.1 s
        assert tractor.y["steer_angle_cmd"] == pytest.approx(delta, abs=2e-4)
        assert tractor.y["speed_cmd"] == pytest.approx(2.5) and tractor.y["guidance_safe_state"] == 0.0
        info = None
        while info is None:
            f = spy.recv(1.0)
            if f is not None and (f.arbitration_id >> 8) & 0x3FF00 == 44032:
                info = f
        assert info.data[0] | info.data[1] << 8 == round((1000.0 * math.tan(0.05) / 1.4 + 8032.0) / 0.25)
        assert info.data[2] & 0x03 == 1 and (info.data[2] >> 2) & 0x03 == 1      # lockout active, system ready
        guidance.step(0.25, 0.05)
        assert guidance.y["steer_angle_measured"] == pytest.approx(-0.05, abs=2e-4)
        assert guidance.y["machine_lockout"] == 1.0 and guidance.y["machine_ready"] == 1.0
        assert guidance.y["yaw_rate"] == pytest.approx(0.2, abs=1e-4) and guidance.y["speed_measured"] == pytest.approx(2.5)
        guidance.u.update(safe_state=1.0)                     # disengaged: 'not intended to steer'
        guidance.actuate(0.3)
        tractor.step(0.3, 0.05)
        assert tractor.y["guidance_safe_state"] == 1.0
    finally:
        spy.shutdown()
        guidance.terminate()
        tractor.terminate()


@pytest.mark.parametrize("fault, reason", [("lockout", 4), ("not_ready", 3)])
def test_watchdog_disengages_when_the_machine_is_locked_out_or_not_ready(fault, reason):
    from agrobot.components.safety_watchdog import SafetyWatchdog

    guidance, tractor = _iso_pair(**{f"{fault}_after": 1.0})
    w = SafetyWatchdog("w", {"recovery_time": 1.0})
    w.initialize(0.0, 0.05)
    trip = None
    try:
        for k in range(60):
            t = 0.05 * k
            tractor.u.update(steer_angle_measured=0.02, yaw_rate=0.0, speed=2.0)
            tractor.step(t, 0.05)
            guidance.step(t, 0.05)
            w.u.update(steer_angle_cmd=0.1, speed_cmd=2.0, steer_angle_measured=guidance.y["steer_angle_measured"],
                       fix_age=0.0, fix_quality=4.0, machine_ready=guidance.y["machine_ready"],
                       machine_lockout=guidance.y["machine_lockout"])
            w.step(t, 0.05)
            guidance.u.update(steer_angle_cmd=w.y["steer_angle_cmd_out"], speed_cmd=w.y["speed_cmd_out"],
                              safe_state=w.y["safe_state"])
            guidance.actuate(t)
            if w.y["safe_state"] and trip is None:
                trip = t
        assert trip is not None and 1.0 <= trip <= 1.1 + 1e-9       # the next machine info, one step
        assert w.y["trip_reason"] == reason and w.y["speed_cmd_out"] == 0.0
        assert tractor.y["guidance_safe_state"] == 1.0              # the tractor sees 'not intended to steer'
        assert ("lockout" if fault == "lockout" else "not ready") in w.events[0][1]
    finally:
        guidance.terminate()
        tractor.terminate()


@pytest.mark.slow
def test_identify_from_a_recorded_multisine_experiment_matches_the_simulation_log(tmp_path):
    """The paper's experiment (a 50 s odd-odd multisine on the steering, 2 m/s) driven on the simulated
    tractor and recorded on its buses: the fits from the recording equal those from the simulation's
    own log (the buses quantise to 1e-4 rad), and the CLI takes the folder."""
    import warnings

    from agrobot.identification.multisine import MultisineDesign, realisation
    from agrobot.identification.pipeline import identify_log

    design = MultisineDesign(20.0, 1000, 0.02, 2.0, math.radians(4), "odd_odd")
    study = Study.load(ROOT / "studies" / "field_test.toml", ["study.stop_time=205"])
    study = study.replace_component("plan", "steering_excitation", step=0.05,
                                    parameters={"values": realisation(design, np.random.default_rng(3)).tolist()})
    study = study.with_connections(remove=["plan.speed_cmd -> tractor.speed_cmd"]).with_component(
        "tractor", inputs={"speed_cmd": 2.0})
    folder = tmp_path / "multisine"
    run_study(record_study(study, folder), tmp_path / "run", plots=False, named=(folder,))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        raw = identify_log(folder, None, period=50.0, models=["second_order", "bicycle"])
        own = identify_log(folder / "simulation_log.csv", None, period=50.0, models=["second_order", "bicycle"])
    assert raw["recording"]["used"]["how"].startswith("run 1 (the longest)")
    for name in ("second_order", "bicycle"):
        a, b = raw["models"][name], own["models"][name]
        assert np.allclose(a["num"], b["num"], rtol=0.02) and np.allclose(a["den"], b["den"], rtol=0.02), name
    den = raw["models"]["second_order"]["den"]
    assert 150 < den[2] < 260 and 8 < den[1] < 13          # the paper's 242 and 10.9 at 2 m/s, in range
    proc = subprocess.run([sys.executable, "-m", "agrobot", "identify", str(folder), "--out", str(tmp_path / "id"),
                           "--period", "50", "--models", "second_order", "--no-plots"],
                          capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 0 and "used: run 1" in proc.stdout, proc.stderr


@pytest.mark.slow
def test_a_steering_offset_in_a_recording_is_named_with_its_value(tmp_path):
    """A 0.03 rad (1.7 deg) wheel-angle offset on the project's own plant, through
    the recording path, is named with its value: a free input map that could also carry an offset
    does not displace the named effect. A clean recording of the same drive names no steering
    effect and leaves no stage misfit (its GPS is one 50 ms sample older than the gyro and the wheel
    angle, which the diagnosis may rightly name as gps_latency)."""
    from agrobot.diagnosis.pipeline import diagnose

    results = {}
    for name, values in (("offset", {"tractor.tractor.steer_angle_offset": 0.03}), ("clean", None)):
        folder = record(tmp_path / name / "recording", 240.0, values)
        results[name] = diagnose(folder, tmp_path / name / "diagnosis", plots=False, identify=False)
    res = results["offset"]
    offset = next((e for e in res["effects"] if e["id"] == "steering_offset"), None)
    assert offset is not None, res["selection_trace"]
    assert abs(offset["parameters"]["steer_angle_offset"] - 0.03) < math.radians(0.3)
    assert not any(line.startswith("- steering_offset") for line in res["selection_trace"])
    clean = results["clean"]
    assert clean["verdict"] == "none" and clean["effects"] == [], clean["selection_trace"]
    assert not any(st["misfit"] for st in clean["stages"].values())
    assert clean["recording"]["resolution"]["delta"] == pytest.approx(math.radians(1.0), abs=2e-4)
