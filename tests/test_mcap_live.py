"""Runs where robotics engineers look at them: the MCAP of a run (read back with the ``mcap`` reader, its
typed Foxglove messages decoded as protobuf) holds the documented topics and schemas with the values of
signals.parquet; the live view serves the same topics over the Foxglove WebSocket protocol to a real
client; a bad MCAP path or a port in use is exit 2 before anything runs."""
from __future__ import annotations

import json
import socket
import struct
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from agrobot.orchestrator.mcap_out import write_study_mcap
from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.study import Study
from tests.figure_checks import apart_in_greyscale, has_unit
from tests.commands import cli

pytest.importorskip("foxglove")
mcap_reader = pytest.importorskip("mcap.reader")
ROOT = Path(__file__).resolve().parent.parent
STUDIES = ROOT / "studies"
SCHEMAS = {"/tf": "foxglove.FrameTransforms", "/vehicle/pose": "foxglove.PoseInFrame",
           "/estimate/pose": "foxglove.PoseInFrame", "/reference/pose": "foxglove.PoseInFrame",
           "/gnss/fix": "foxglove.LocationFix", "/reference/path": "foxglove.SceneUpdate"}


def _read(path: Path):
    """(topic -> schema name, topic -> [(log time ns, decoded message)]) of an MCAP file."""
    from mcap_protobuf.decoder import DecoderFactory

    with open(path, "rb") as f:
        reader = mcap_reader.make_reader(f, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        schemas = {c.topic: summary.schemas[c.schema_id].name for c in summary.channels.values()}
        typed = [c.topic for c in summary.channels.values() if c.message_encoding != "json"]
        messages: dict[str, list] = {}
        for schema, channel, message in reader.iter_messages():
            if channel.message_encoding == "json":
                messages.setdefault(channel.topic, []).append((message.log_time, json.loads(message.data)))
        f.seek(0)
        reader = mcap_reader.make_reader(f, decoder_factories=[DecoderFactory()])
        for schema, channel, message, decoded in reader.iter_decoded_messages(
                topics=typed):
            messages.setdefault(channel.topic, []).append((message.log_time, decoded))
    return schemas, messages


def _at(frame: pd.DataFrame, t_ns: int) -> pd.Series:
    k = int(np.argmin(np.abs(frame["t"].to_numpy() - frame["t"].iloc[0] - t_ns * 1e-9)))
    return frame.iloc[k]


@pytest.fixture(scope="module")
def figure8_mcap(tmp_path_factory):
    where = tmp_path_factory.mktemp("mcap")
    study = Study.load(STUDIES / "figure8.toml", ["study.stop_time=16"])
    run_study(study, where / "run", plots=False, progress=False)
    frame = pd.read_parquet(where / "run" / "signals.parquet")
    _, note = write_study_mcap(study, frame, where / "run.mcap")
    assert "nominal origin" in note and "[output] origin" in note          # the choice is said, with its option
    return frame, _read(where / "run.mcap")


def test_a_figure8_mcap_holds_the_documented_topics_with_the_signals_values(figure8_mcap):
    frame, (schemas, messages) = figure8_mcap
    for topic, name in SCHEMAS.items():
        assert schemas.get(topic) == name, (topic, schemas.get(topic))
    components = {c.split(".")[0] for c in frame.columns if c != "t"}
    assert {f"/signals/{c}" for c in components} <= set(schemas)
    # every output of the plant at every base step (its own rate: the base step), equal to signals.parquet
    tractor = messages["/signals/tractor"]
    assert len(tractor) == len(frame)
    got = np.array([m["x_cg"] for _, m in tractor])
    np.testing.assert_array_equal(got, frame["tractor.x_cg"].to_numpy())
    # the GPS at its own 20 Hz, one message per step of the component
    assert len(messages["/signals/gps"]) == pytest.approx(len(frame) / 5, abs=1)
    # the pose: position and heading (from the quaternion about z) of the plant's CG
    for t_ns, pose in messages["/vehicle/pose"][::17]:
        row = _at(frame, t_ns)
        q = pose.pose.orientation
        assert pose.frame_id == "world"
        assert pose.pose.position.x == pytest.approx(row["tractor.x_cg"], abs=1e-12)
        assert pose.pose.position.y == pytest.approx(row["tractor.y_cg"], abs=1e-12)
        assert 2 * np.arctan2(q.z, q.w) == pytest.approx(row["tractor.heading"], abs=1e-9)
    # the fix on the map: back to east/north about the stated origin with pymap3d, the GPS's measured x, y
    import pymap3d

    from agrobot.analysis.mcap_scene import NOMINAL_ORIGIN

    for t_ns, fix in messages["/gnss/fix"][::23]:
        row = _at(frame, t_ns)
        e, n, _ = pymap3d.geodetic2enu(fix.latitude, fix.longitude, 0.0, *NOMINAL_ORIGIN, 0.0, deg=True)
        assert (e, n) == (pytest.approx(row["gps.x"], abs=1e-6), pytest.approx(row["gps.y"], abs=1e-6))
    # the reference path, once, through the reference points
    (_, update), = messages["/reference/path"]
    points = np.array([[p.x, p.y] for p in update.entities[0].lines[0].points])
    ref = frame[["reference.x_ref", "reference.y_ref"]].to_numpy()
    assert np.min(np.hypot(*(points[:, None, :] - ref[None, ::50, :]).transpose(2, 0, 1)), axis=0).max() < 0.06


FIELD_SECTION = ["field.max_swaths=1", "field.headland_work=0"]


@pytest.fixture(scope="module")
def field_run(tmp_path_factory):
    """(study, signals, metrics.json) of a field mission planned as one swath of a 0.15 ha plot, driven whole."""
    where = tmp_path_factory.mktemp("field")
    study = Study.load(STUDIES / "field_plot_mounted.toml", FIELD_SECTION)
    run_study(study, where / "run", plots=False, progress=False)
    return study, pd.read_parquet(where / "run" / "signals.parquet"), json.loads((where / "run" / "metrics.json").read_text())


def test_a_field_mission_mcap_shows_the_field_and_the_implement_on_the_map(field_run, tmp_path):
    from shapely.geometry import Point, shape

    study, frame, _ = field_run
    write_study_mcap(study, frame, tmp_path / "field.mcap")
    schemas, messages = _read(tmp_path / "field.mcap")
    assert schemas["/field"] == "foxglove.GeoJSON" and schemas["/implement/pose"] == "foxglove.PoseInFrame"
    (_, geo), = messages["/field"]
    features = json.loads(geo.geojson)["features"]
    boundary = shape(next(f["geometry"] for f in features if f["properties"]["kind"] == "boundary"))
    # every fix the tractor's receiver gave lies in the field's boundary (longitude, latitude): the mission frame
    # was carried back to the field's geodetic origin
    fixes = [(m.longitude, m.latitude) for _, m in messages["/gnss/fix"]]
    assert len(fixes) > 100 and all(boundary.contains(Point(p)) for p in fixes[::10])
    implement = messages["/implement/pose"]
    row = _at(frame, implement[-1][0])
    name = next(c.split(".")[0] for c in frame.columns if c.endswith(".hitch_angle"))
    assert implement[-1][1].pose.position.x == pytest.approx(row[f"{name}.x"], abs=1e-12)


def test_a_bad_mcap_path_is_refused_before_the_run(tmp_path):
    out = tmp_path / "run"
    proc = cli("run", str(STUDIES / "figure8.toml"), "--out", str(out), "--mcap",
               str(tmp_path / "no_such_folder" / "x.mcap"), timeout=120)
    assert proc.returncode == 2 and "no_such_folder" in proc.stderr and "does not exist" in proc.stderr
    assert not out.exists()


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _watch_live(study: Path, out: Path, sets: list[str], topics: tuple[str, ...]):
    """Run ``study`` with --live (waiting for a viewer), connect a Foxglove WebSocket client, subscribe to
    ``topics`` when they are advertised and keep every message until the server closes at the run's end:
    (the process, its stdout and stderr, advertised channels by topic, topic -> [(log time ns, payload)])."""
    from websockets.sync.client import connect

    port = _free_port()
    run = subprocess.Popen([sys.executable, "-m", "agrobot", "run", str(study), "--out", str(out), "--no-plots",
                            *[a for x in sets for a in ("--set", x)], "--live", f"127.0.0.1:{port}", "--live-wait", "60"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT)
    try:
        deadline, ws = time.time() + 90, None
        while ws is None:
            try:
                ws = connect(f"ws://127.0.0.1:{port}", subprotocols=["foxglove.sdk.v1"], open_timeout=2)
            except OSError:
                assert run.poll() is None and time.time() < deadline, "the live view never listened"
                time.sleep(0.2)
        channels, subscriptions, got = {}, {}, {}
        with ws:
            while True:
                try:
                    message = ws.recv(timeout=120)
                except Exception:          # noqa: BLE001 - the server closes the connection when the run ends
                    break
                if isinstance(message, str):
                    op = json.loads(message)
                    if op["op"] == "advertise":
                        channels.update({c["topic"]: c for c in op["channels"]})
                        wanted = [channels[t] for t in topics if t in channels]
                        subscriptions = {10 + k: c for k, c in enumerate(wanted)}
                        ws.send(json.dumps({"op": "subscribe", "subscriptions": [
                            {"id": k, "channelId": c["id"]} for k, c in subscriptions.items()]}))
                else:
                    opcode, sid, t_ns = struct.unpack_from("<BIQ", message)
                    assert opcode == 1
                    got.setdefault(subscriptions[sid]["topic"], []).append((t_ns, message[13:]))
        stdout, stderr = run.communicate(timeout=120)
    finally:
        if run.poll() is None:
            run.kill()
    return run, stdout, stderr, channels, got


def test_the_live_view_serves_the_running_study_to_a_websocket_client(tmp_path):
    out = tmp_path / "run"
    # the whole 160 s: the view sends at most 20 instants a second of wall time, and a quiet machine runs
    # 40 s of the study in 0.12-0.25 s (3-4 instants)
    run, stdout, stderr, channels, got = _watch_live(STUDIES / "figure8.toml", out, ["study.stop_time=160"],
                                                     ("/signals/tractor", "/vehicle/pose"))
    assert run.returncode == 0, stderr
    assert channels["/vehicle/pose"]["schemaName"] == "foxglove.PoseInFrame"
    assert channels["/signals/tractor"]["encoding"] == "json"
    frame = pd.read_parquet(out / "signals.parquet")
    tractor = [(t, json.loads(p)) for t, p in got["/signals/tractor"]]
    # the two subscriptions reach the server one after the other: the pose may miss the first instant
    assert len(tractor) >= 5 and 0 <= len(tractor) - len(got["/vehicle/pose"]) <= 2
    assert f"{len(tractor)} instants sent" in stdout or "instants sent" in stdout
    for t_ns, values in tractor:                 # the values of the run at the instant sent
        row = frame.iloc[int(round(values["t"] / 0.01))]
        assert t_ns == round(values["t"] * 1e9)
        assert values["x_cg"] == row["tractor.x_cg"] and values["heading"] == row["tractor.heading"]


@pytest.mark.slow
def test_the_live_view_follows_a_real_time_run_of_the_hardware_layout(tmp_path):
    """figure8_hil.toml without its hardware tractor (which needs the emulator or a tractor): its layout,
    figure8_hardware_layout.toml, paced in real time as figure8_hil.toml is (study.realtime). The run is paced
    and the live view sends its instants as they happen, from the start to the end of the run, at up to 20 a
    second of wall time (here one per 50 ms base step at most), with the estimate's pose on the map (the truth of
    a hardware tractor is unknown) and the values of the run."""
    out, stop = tmp_path / "run", 7.0        # the analysis judges from 5 s after the reference's 1 s ramp
    run, stdout, stderr, channels, got = _watch_live(
        STUDIES / "figure8_hardware_layout.toml", out,
        ["study.realtime=true", f"study.stop_time={stop:g}", "reference.ramp_time=1"],
        ("/signals/ekf", "/estimate/pose"))
    assert run.returncode == 0, stderr
    realtime = json.loads((out / "metrics.json").read_text())["realtime"]
    assert realtime["steps"] == round(stop / 0.05) + 1 and "steps of 50 ms" in stdout           # paced
    assert channels["/estimate/pose"]["schemaName"] == "foxglove.PoseInFrame" and "/vehicle/pose" not in channels
    frame = pd.read_parquet(out / "signals.parquet")
    ekf = [(t, json.loads(p)) for t, p in got["/signals/ekf"]]
    times = np.array([values["t"] for _, values in ekf])
    # paced at the wall clock, the view sees the run as it goes: from its first second to its last, at most one
    # instant per base step, and not fewer than half the 20 a second it may send
    assert times[0] <= 1.0 and times[-1] >= stop - 1.0 and np.all(np.diff(times) >= 0.05 - 1e-9)
    assert 0.5 * 20 * stop <= len(ekf) <= stop / 0.05 + 1
    assert abs(len(got["/estimate/pose"]) - len(ekf)) <= 2
    for t_ns, values in ekf:
        row = frame.iloc[int(round(values["t"] / 0.05))]
        assert t_ns == round(values["t"] * 1e9)
        assert values["x_cg"] == row["ekf.x_cg"] and values["heading"] == row["ekf.heading"]


def test_a_port_in_use_is_refused_with_its_number(tmp_path):
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        port = busy.getsockname()[1]
        proc = cli("run", str(STUDIES / "figure8.toml"), "--out", str(tmp_path / "run"), "--live",
                   f"127.0.0.1:{port}", timeout=120)
    assert proc.returncode == 2 and f"127.0.0.1:{port}" in proc.stderr and "Traceback" not in proc.stderr
    assert not (tmp_path / "run").exists()


def test_convert_writes_the_log_as_mcap_beside_it(tmp_path):
    from harness.truth_tractor import make_log
    from agrobot.orchestrator.cli import main

    frame, _ = make_log(3, None, duration=40.0)
    frame.to_csv(tmp_path / "drive.csv", index=False)
    assert main(["convert", str(tmp_path / "drive.csv"), "--out", str(tmp_path / "log.parquet"), "--mcap"]) == 0
    log = pd.read_parquet(tmp_path / "log.parquet")
    schemas, messages = _read(tmp_path / "log.mcap")
    assert schemas["/log/position"] == "foxglove.Point3InFrame"
    rows = messages["/signals/log"]
    assert len(rows) == len(log)
    for column in ("v", "yaw_rate", "delta"):
        np.testing.assert_allclose([m[column] for _, m in rows], log[column], rtol=1e-12, atol=0)
    positions = messages["/log/position"]
    np.testing.assert_allclose([p.point.x for _, p in positions], log["x"], rtol=1e-12, atol=0)
    assert [t for t, _ in positions] == [round((t - log["t"].iloc[0]) * 1e9) for t in log["t"]]


def test_the_trajectory_figure_says_its_conclusion_labels_units_and_reads_in_grey(figure8_mcap):
    import matplotlib

    matplotlib.use("Agg")
    from agrobot.analysis.figure8 import PAPER_BOUNDS, metrics, trajectory_figure

    frame, _ = figure8_mcap
    study = Study.load(STUDIES / "figure8.toml", ["study.stop_time=16"])
    fig = trajectory_figure(frame, study)
    title = fig._suptitle.get_text()
    m = metrics(frame, study)
    for key, where in (("euclid_max_curved", "curves"), ("euclid_max_straight", "straights")):
        if np.isfinite(m[key]):
            verdict = "within" if m[key] < PAPER_BOUNDS[key] else "BEYOND"
            assert f"{where} max {m[key]:.2f} m ({verdict} the paper's {PAPER_BOUNDS[key]:.2f} m)" in title
        else:
            assert f"no {where} judged" in title
    for ax in fig.axes:
        assert "[m]" in ax.get_xlabel() and "[m]" in ax.get_ylabel()
        assert apart_in_greyscale(ax) == []


def test_the_coverage_figure_says_its_conclusion_labels_units_and_reads_in_grey(field_run, tmp_path):
    """The title carries the coverage, overlap and skipped area of metrics.json and the judgement of the goal
    (the analysis's bounds); on a one-swath section the coverage bounds are said not judged, on the same figures
    taken as a whole route's they are judged and missed."""
    import matplotlib

    matplotlib.use("Agg")
    from agrobot.analysis.field_coverage import COVERAGE_TARGET, OVERLAP_TARGET, coverage_figure, coverage_verdict

    study, frame, m = field_run
    fig = coverage_figure(frame, study)
    fig.savefig(tmp_path / "coverage.png", dpi=60)
    map_ax, bar = fig.axes
    title = map_ax.get_title()
    head = (f"Coverage {100 * m['coverage_share']:.1f} %, overlap {100 * m['overlap_share']:.1f} %, "
            f"{m['skipped_area_m2']:.0f} m² skipped")
    assert head in title
    assert m["overlap_share"] <= OVERLAP_TARGET and "overlap within the goal" in title
    assert "coverage not judged: bounds for the whole field; this run plans 1 swath (max_swaths = 1)" in title
    whole = Study.load(STUDIES / "field_plot_mounted.toml")      # the same figures judged as a whole route's
    assert m["coverage_share"] < COVERAGE_TARGET
    judged = coverage_verdict({**m, "route_done_share": 1.0}, whole).split("\n")[1]
    assert judged.startswith("MISSES the goal: ") and "overlap" not in judged
    for name, key in (("coverage", "coverage_share"), ("whole-field coverage", "field_coverage_share")):
        assert f"{name} {100 * m[key]:.1f} % (goal >= {100 * COVERAGE_TARGET:g} %)" in judged
    assert has_unit(map_ax.get_xlabel()) and has_unit(map_ax.get_ylabel()) and has_unit(bar.get_ylabel())
    assert apart_in_greyscale(map_ax) == []


def test_a_sweep_writes_each_points_mcap_on_request(tmp_path):
    from agrobot.orchestrator.cli import main

    study = tmp_path / "sweep.toml"
    study.write_text(f'extends = "{STUDIES / "figure8.toml"}"\n[study]\nstop_time = 14.0\n'
                     '[sweep]\nmode = "grid"\n[sweep.parameters]\n"reference.speed" = [1.5, 2.5]\n')
    assert main(["sweep", str(study), "--out", str(tmp_path / "out"), "--workers", "1", "--no-plots", "--mcap"]) == 0
    files = sorted((tmp_path / "out" / "points").glob("*/run.mcap"))
    assert len(files) == 2
    speeds = set()
    for path in files:
        _, messages = _read(path)
        speeds.add(round(max(m["speed_ref"] for _, m in messages["/signals/reference"]), 6))
    assert speeds == {1.5, 2.5}


def test_a_diagnosis_mcap_holds_measured_replays_and_residuals_on_the_logs_time(tmp_path):
    from agrobot.diagnosis.baseline import baseline_from_study
    from agrobot.diagnosis.candidates import Replay
    from agrobot.diagnosis.mcap import write_diagnosis_mcap
    from harness.truth_tractor import make_log
    from agrobot.orchestrator.study import load_study

    frame, _ = make_log(5, "steering_offset", duration=60.0)
    replay = Replay(frame, baseline_from_study(load_study(STUDIES / "figure8.toml")))
    base = dict(replay.baseline.values)
    final = {**base, "steer_angle_offset": base["steer_angle_offset"] + 0.02}
    write_diagnosis_mcap(replay, base, final, tmp_path / "d.mcap", "log.csv")
    schemas, messages = _read(tmp_path / "d.mcap")
    assert {f"/diagnosis/{s}" for s in replay.stages} | {"/diagnosis/log"} <= set(schemas)
    steering = messages["/diagnosis/steering"]
    assert len(steering) == len(replay.t)
    # the measured wheel angle is the log's own delta at the same time (the original table, not the replay's)
    log_delta = np.interp([m["t"] for _, m in steering], frame["t"], frame["delta"])
    np.testing.assert_allclose([m["measured"] for _, m in steering], log_delta, atol=1e-9)
    for _, m in steering[::97]:
        assert m["residual_baseline"] == pytest.approx(m["measured"] - m["baseline"], abs=1e-12)
        assert m["residual_final"] == pytest.approx(m["measured"] - m["final"], abs=1e-12)
    # the final model (an offset of the wheel angle the plant sees) is another replay of the yaw rate
    yaw = messages["/diagnosis/yaw"]
    assert max(abs(m["final"] - m["baseline"]) for _, m in yaw if m["final"] is not None) > 1e-3
