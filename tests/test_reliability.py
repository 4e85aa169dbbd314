"""Runs that lose nothing when interrupted or misused (real processes, real signals)."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tests.commands import cli

ROOT = Path(__file__).resolve().parent.parent
CMD = [sys.executable, "-m", "agrobot"]

FAILING = """
[study]
name = "fails"
seed = 1
stop_time = 1.0
base_step = 0.05
signals_format = "csv"

[components.f]
type = "tests.toy_components:FailAt"
parameters = { fail_time = FAIL }
"""


def _start(args: list[str]) -> subprocess.Popen:
    return subprocess.Popen(CMD + args, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _wait_for_rows(out: Path, timeout: float = 60.0) -> None:
    """Until the run's temporary folder beside ``out`` holds a signal file with data."""
    end = time.time() + timeout
    while time.time() < end:
        for tmp in out.parent.glob(f".{out.name}.*"):
            sig = tmp / "signals.parquet"
            if sig.exists() and sig.stat().st_size > 100_000:
                return
        time.sleep(0.2)
    raise AssertionError("the run wrote no signals")


@pytest.mark.slow
@pytest.mark.parametrize("signum, status", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_a_long_run_stopped_by_a_signal_keeps_every_row_and_says_interrupted(tmp_path, signum, status):
    out = tmp_path / "long"
    proc = _start(["run", "studies/figure8.toml", "--set", "study.stop_time=1e5", "--out", str(out), "--no-plots"])
    _wait_for_rows(out)
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == status, err
    assert "Traceback" not in err and "interrupted" in err
    run = json.loads((out / "run.json").read_text())
    metrics = json.loads((out / "metrics.json").read_text())
    assert run["status"] == metrics["status"] == "interrupted"
    frame = pd.read_parquet(out / "signals.parquet")
    dt = frame["t"].diff().dropna()
    assert len(frame) >= 10_000 and dt.max() == pytest.approx(0.01) and dt.min() == pytest.approx(0.01)
    assert frame["t"].iloc[-1] == pytest.approx(run["t_reached_s"])
    assert not list(tmp_path.glob(".long.*"))            # no staging folder left, no lock file


@pytest.mark.slow
def test_a_real_time_composite_run_interrupted_keeps_its_signals(tmp_path):
    out = tmp_path / "rt"
    proc = _start(["run", "studies/figure8_hardware_layout.toml", "--set", "study.realtime=true", "--out", str(out),
                   "--no-plots"])
    end = time.time() + 120.0                   # start-up (imports, the study) takes seconds on a loaded machine
    while not list(out.parent.glob(f".{out.name}.*")) and time.time() < end and proc.poll() is None:
        time.sleep(0.1)
    time.sleep(3.0)                             # then three seconds of real time: 300 instants at 10 ms
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143 and "Traceback" not in err, err
    frame = pd.read_parquet(out / "signals.parquet")
    assert len(frame) > 50 and json.loads((out / "run.json").read_text())["status"] == "interrupted"


@pytest.mark.slow
def test_a_failed_run_never_replaces_a_complete_result(tmp_path):
    study = tmp_path / "fails.toml"
    out = tmp_path / "out"
    study.write_text(FAILING.replace("FAIL", "5.0"))                       # does not fail: completes
    first = subprocess.run(CMD + ["run", str(study), "--out", str(out)], cwd=ROOT, capture_output=True, text=True)
    assert first.returncode == 0, first.stderr
    good = (out / "signals.csv").read_text()
    study.write_text(FAILING.replace("FAIL", "0.5"))
    second = subprocess.run(CMD + ["run", str(study), "--out", str(out), "--overwrite"], cwd=ROOT, capture_output=True,
                            text=True)
    assert second.returncode == 1 and "deliberate failure" in second.stderr and "Traceback" not in second.stderr
    assert (out / "signals.csv").read_text() == good
    assert json.loads((out / "metrics.json").read_text())["status"] == "completed"
    failed = out.with_name("out.failed")
    assert str(failed) in second.stderr
    assert json.loads((failed / "metrics.json").read_text())["status"] == "failed"
    assert len(pd.read_csv(failed / "signals.csv")) == 10          # t = 0 .. 0.45, it fails at 0.5


@pytest.mark.slow
def test_out_is_checked_before_any_computation(tmp_path):
    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "thesis.tex").write_text("precious")
    proc = cli("run", "studies/figure8.toml", "--out", foreign)
    assert proc.returncode == 2 and "--out" in proc.stderr and "thesis.tex" in proc.stderr
    assert "euclid" not in proc.stdout + proc.stderr            # refused before the simulation, not after it
    assert (foreign / "thesis.tex").read_text() == "precious"
    a_file = tmp_path / "file.txt"
    a_file.write_text("x")
    proc = cli("run", "studies/figure8.toml", "--out", a_file)
    assert proc.returncode == 2 and "is a file" in proc.stderr and "Traceback" not in proc.stderr
    assert "euclid" not in proc.stdout + proc.stderr
    proc = cli("run", "studies/figure8.toml", "--set", "study.stop_time=20", "--no-plots", "--out", foreign,
               "--overwrite")
    assert proc.returncode == 2 and "thesis.tex" in proc.stderr, proc.stderr     # not a run's: never replaced
    assert (foreign / "thesis.tex").read_text() == "precious" and not (foreign / "metrics.json").exists()


@pytest.mark.slow
def test_a_second_run_into_the_same_folder_is_refused_while_the_first_runs(tmp_path):
    out = tmp_path / "busy"
    first = _start(["run", "studies/figure8.toml", "--set", "study.stop_time=1e5", "--out", str(out), "--no-plots"])
    try:
        _wait_for_rows(out)
        second = subprocess.run(CMD + ["run", "studies/figure8.toml", "--out", str(out)], cwd=ROOT,
                                capture_output=True, text=True)
        assert second.returncode == 2 and "another run" in second.stderr
    finally:
        first.send_signal(signal.SIGTERM)
        first.communicate(timeout=60)
    assert first.returncode == 143


@pytest.mark.slow
def test_result_files_follow_the_users_umask(tmp_path):
    out = tmp_path / "u"
    proc = subprocess.run(CMD + ["run", "studies/figure8.toml", "--set", "study.stop_time=20", "--out", str(out)],
                          cwd=ROOT, capture_output=True, text=True, preexec_fn=lambda: os.umask(0o027))
    assert proc.returncode == 0, proc.stderr
    assert (out.stat().st_mode & 0o777) == 0o750
    for f in ("signals.parquet", "metrics.json", "run.json"):
        assert ((out / f).stat().st_mode & 0o777) == 0o640, f


def _children(parent: int) -> list[int]:
    """Process ids whose parent is ``parent`` (from /proc)."""
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == parent:
            out.append(int(stat.parent.name))
    return out


def _cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_text()
    except OSError:
        return ""


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def _sweep(out: Path, stop: str) -> subprocess.Popen:
    return _start(["sweep", "studies/speed_sweep.toml", "--out", str(out), "--workers", "2", "--no-plots",
                   "--no-progress", "--set", f"study.stop_time={stop}", "--engine", "python"])   # its workers


@pytest.mark.slow
def test_sweep_workers_end_with_their_parent_even_on_sigkill(tmp_path):
    proc = _sweep(tmp_path / "sw", "300")
    end = time.time() + 60
    workers: list[int] = []
    while time.time() < end and len(workers) < 2:
        workers = [c for c in _children(proc.pid) if "resource_tracker" not in _cmdline(c)]
        time.sleep(0.3)
    assert workers, "no worker started"
    time.sleep(2.0)
    proc.kill()
    proc.communicate(timeout=30)
    end = time.time() + 10
    while time.time() < end and any(_alive(w) for w in workers):
        time.sleep(0.2)
    assert not any(_alive(w) for w in workers)


@pytest.mark.slow
def test_a_sweep_stopped_by_sigterm_keeps_finished_points_and_resumes(tmp_path):
    out = tmp_path / "sw"
    proc = _sweep(out, "150")
    end = time.time() + 120
    while time.time() < end and len(list(out.glob("points/*/metrics.json"))) < 3:
        time.sleep(0.2)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143 and "resume" in err and "Traceback" not in err, err
    kept = pd.read_parquet(out / "results.parquet")
    assert 3 <= len(kept) < 11 and set(kept["status"]) == {"completed"}
    again = subprocess.run(CMD + ["sweep", "studies/speed_sweep.toml", "--out", str(out), "--workers", "2",
                                  "--no-plots", "--no-progress", "--set", "study.stop_time=150", "--engine", "python"],
                           cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stderr
    table = pd.read_parquet(out / "results.parquet")
    assert len(table) == 11
    merged = table.set_index("point").loc[kept["point"]]
    np.testing.assert_array_equal(merged["speed_rms_error"].to_numpy(), kept.set_index("point")["speed_rms_error"].to_numpy())


@pytest.mark.slow
def test_a_wrong_scheduler_address_fails_fast_and_names_it(tmp_path):
    """Exit 2 naming the address, not a hang: the subprocess timeout is the guard (how fast it gives
    up, CONNECT_TIMEOUT, is a figure for a benchmark, not a test on a shared machine)."""
    proc = subprocess.run(CMD + ["sweep", "studies/speed_sweep.toml", "--out", str(tmp_path / "sw"),
                                 "--scheduler", "tcp://127.0.0.1:9", "--no-progress"],
                          cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and "tcp://127.0.0.1:9" in proc.stderr and "Traceback" not in proc.stderr


@pytest.fixture(scope="module")
def clean_log():
    """A 120 s generated log (harness.truth_tractor), made once: each test writes its own edit of it."""
    from harness.truth_tractor import make_log

    return make_log(5, None, duration=120.0)[0]


@pytest.mark.parametrize("edit, words", [
    (lambda f: f.assign(t=f["t"] * 1000), ["'t'", "milliseconds", "divide t by 1000"]),
    (lambda f: f.assign(t=f["t"] * 1e6), ["'t'", "microseconds"]),
    (lambda f: f.assign(v=f["v"].where(f.index != 700, np.inf)), ["'v'", "infinite", "row 700"]),
    (lambda f: f.assign(v=f["v"] * 3.6), ["'v'", "km/h"]),
    (lambda f: f.assign(t=f["t"] + np.random.default_rng(0).uniform(-0.002, 0.002, len(f))), ["unevenly", "--resample"]),
])
def test_measured_logs_are_checked_against_physics(tmp_path, clean_log, edit, words):
    from agrobot.measurements import LogError, read_log

    frame = clean_log
    path = tmp_path / "log.csv"
    edit(frame).to_csv(path, index=False)
    with pytest.raises(LogError) as err:
        read_log(path)
    for w in words:
        assert w in str(err.value), str(err.value)
    assert str(path) in str(err.value)


@pytest.mark.slow
def test_a_jittered_log_is_diagnosed_with_resample(tmp_path, clean_log):
    from agrobot.measurements import read_log

    frame = clean_log.copy()
    frame["t"] += np.random.default_rng(1).uniform(-0.002, 0.002, len(frame))
    path = tmp_path / "jitter.csv"
    frame.to_csv(path, index=False)
    even = read_log(path, resample_jitter=True)
    assert np.allclose(np.diff(even["t"]), np.median(np.diff(frame["t"])))
    proc = subprocess.run(CMD + ["diagnose", str(path), "--out", str(tmp_path / "d"), "--no-plots", "--resample",
                                 "--no-identify"],
                          cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0 and "verdict: none" in proc.stdout, proc.stderr


BAD = [  # (arguments, exit code, words the message must hold); {tmp} is a fresh folder
    (["run", "nope.toml", "--out", "{tmp}/o"], 2, ["nope.toml", "not found"]),
    (["run", "studies/figure8.toml", "--out", "{tmp}/o", "--set", "x=fast"], 2, ["'x=fast'", "component.parameter"]),
    (["run", "studies/figure8.toml", "--out", "{tmp}/o", "--set", "steering.kp=fast"], 2,
     ["components.steering.parameters.kp", "'fast'", "expected a number"]),
    (["run", "studies/figure8.toml", "--out", "{tmp}/o", "--set", "steering.kp=3 m"], 2, ["kp", "'m'"]),
    (["run", "studies/figure8.toml", "--out", "{tmp}/o", "--set", "steering.nosuch=1"], 2, ["nosuch", "unknown parameter"]),
    (["run", "studies/figure8.toml", "--out", "{tmp}/o", "--set", "nosuch.kp=1"], 2, ["no component 'nosuch'"]),
    (["run", "studies/figure8.toml", "--out", "{tmp}/o", "--set", "study.stop_time=inf"], 2, ["stop_time"]),
    (["run", "studies/figure8.toml", "--out", "{tmp}/o", "--set", "study.base_step=0"], 2, ["base_step"]),
    (["sweep", "studies/figure8.toml", "--out", "{tmp}/s"], 2, ["no [sweep] section"]),
    (["sweep", "studies/speed_sweep.toml", "--out", "{tmp}/s", "--workers", "0"], 2, ["--workers"]),
    (["diagnose", "nope.csv", "--out", "{tmp}/d"], 2, ["nope.csv", "not found"]),
    (["diagnose", "{tmp}/header.csv", "--out", "{tmp}/d"], 2, ["0 rows"]),
    (["diagnose", "{tmp}/header.csv", "--out", "{tmp}/d", "--fit-fraction", "0.95"], 2, ["--fit-fraction"]),
    (["identify", "nope.csv", "--out", "{tmp}/i"], 2, ["nope.csv", "not found"]),
    (["identify", "{tmp}/header.csv", "--out", "{tmp}/i"], 2, ["header.csv", "0 rows"]),
    (["identify", "{tmp}/header.csv", "--out", "{tmp}/i", "--band", "2", "1"], 2, ["--band", "F_MIN < F_MAX"]),
    (["identify", "{tmp}/header.csv", "--out", "{tmp}/i", "--speed", "0"], 2, ["--speed", "positive"]),
    (["identify", "{tmp}/header.csv", "--out", "{tmp}/i", "--period", "0"], 2, ["--period", "positive"]),
    (["export-controller", "studies/figure8.toml", "--out", "{tmp}/x.txt"], 2, [".fmu"]),
    (["export-controller", "studies/figure8.toml", "--out", "{tmp}"], 2, [".fmu"]),
    (["export-controller", "studies/figure8.toml", "--out", "{tmp}/header.csv/c.fmu"], 2, ["cannot write there"]),
    (["margins", "nope.toml"], 2, ["nope.toml"]),
    (["run", "studies/figure8.toml", "--out", "{tmp}/header.csv"], 2, ["is a file"]),
    (["emulate", "nope.toml", "--nmea-port", "10999"], 2, ["nope.toml", "not found"]),
    (["run", "studies/figure8.toml", "--out", "{tmp}/o", "--set", "study.seed=abc"], 2, ["study.seed"]),
    (["run", "studies/figure8.toml", "--out", "{tmp}/o", "--set", "study.signals_format=xlsx"], 2, ["signals_format"]),
    (["run", "studies/figure8.toml", "--out", "{tmp}/o", "--set", "steering.quantization_guard=2"], 2,
     ["components.steering", "quantization_guard must be 0 or 1"]),
    (["run", "{tmp}/broken.toml", "--out", "{tmp}/o"], 2, ["broken.toml"]),
    (["run", "{tmp}/unknown_type.toml", "--out", "{tmp}/o"], 2, ["unknown_type.toml", "no_such_component"]),
    (["run", "studies/figure8.toml"], 2, ["--out"]),
    (["no-such-command"], 2, ["invalid choice"]),
    (["sweep", "studies/speed_sweep.toml", "--out", "{tmp}/s", "--scheduler", "foo"], 2, ["--scheduler foo"]),
    (["sweep", "studies/speed_sweep.toml", "--out", "{tmp}/s", "--set", "study.stop_time=-1"], 2, ["stop_time"]),
    (["diagnose", "{tmp}/header.csv", "--out", "{tmp}/d", "--study", "nope.toml"], 2, ["nope.toml"]),
    (["diagnose", "{tmp}/degrees.csv", "--out", "{tmp}/d"], 2, ["'delta'", "degrees"]),
    (["diagnose", "{tmp}/ms.csv", "--out", "{tmp}/d"], 2, ["'t'", "milliseconds"]),
    (["identify", "{tmp}/ms.csv", "--out", "{tmp}/i"], 2, ["'t'", "milliseconds"]),
    (["identify", "{tmp}/degrees.csv", "--out", "{tmp}/i"], 2, ["'delta'", "degrees"]),
    (["identify", "{tmp}/missing.csv", "--out", "{tmp}/i"], 2, ["identification from driving not possible", "no yaw_rate"]),
    (["identify", "studies/identification.toml", "--out", "{tmp}/i", "--set", "gyro.noise_std=loud"], 2,
     ["noise_std", "'loud'"]),
    (["export-controller", "nope.toml", "--out", "{tmp}/c.fmu"], 2, ["nope.toml"]),
    (["margins", "studies/figure8.toml", "--set", "x=1"], 2, ["'x=1'"]),
    (["emulate", "studies/tractor_emulator.toml", "--nmea-port", "70000"], 2, ["--nmea-port"]),
    (["run", "studies/figure8.toml", "--out", "{tmp}/o", "--set", "study.base_step=0.003"], 2, ["step"]),
    # an --out whose parent cannot be created; a study's edit of connections it does not have
    (["run", "studies/figure8.toml", "--out", "/proc/x/y"], 2, ["--out /proc/x/y", "cannot create"]),
    (["sweep", "studies/speed_sweep.toml", "--out", "/proc/x/y"], 2, ["--out /proc/x/y", "cannot create"]),
    (["diagnose", "{tmp}/degrees.csv", "--out", "/proc/x/y"], 2, ["--out /proc/x/y", "cannot create"]),
    (["identify", "studies/identification.toml", "--out", "/proc/x/y"], 2, ["--out /proc/x/y", "cannot create"]),
    (["run", "{tmp}/bad_edit.toml", "--out", "{tmp}/o"], 2, ["bad_edit.toml", "connections_remove",
                                                              "'gps.x -> nowhere.x'", "not a connection"]),
]


@pytest.mark.slow
@pytest.mark.parametrize("args, code, words", BAD, ids=[" ".join(a[:2]) + f" #{i}" for i, (a, _, _) in enumerate(BAD)])
def test_bad_invocations_get_a_message_and_an_exit_code_never_a_traceback(tmp_path, clean_log, args, code, words):
    (tmp_path / "header.csv").write_text("t,delta_cmd,delta,v,yaw_rate,x,y\n")
    (tmp_path / "broken.toml").write_text("[study\nname = 1\n")
    (tmp_path / "unknown_type.toml").write_text(f'extends = "{ROOT / "studies" / "figure8.toml"}"\n'
                                                f'[components.gps]\ntype = "no_such_component"\n')
    (tmp_path / "bad_edit.toml").write_text(f'extends = "{ROOT / "studies" / "figure8.toml"}"\n'
                                            f'connections_remove = ["gps.x -> nowhere.x"]\n')
    frame = clean_log
    frame.assign(delta=np.degrees(frame["delta"])).to_csv(tmp_path / "degrees.csv", index=False)
    frame.assign(t=frame["t"] * 1000).to_csv(tmp_path / "ms.csv", index=False)
    # no gyro, no heading and no positions: nothing measures the yaw (a GNSS course would)
    frame.drop(columns=["yaw_rate", "x", "y"]).to_csv(tmp_path / "missing.csv", index=False)
    proc = cli(*[a.format(tmp=tmp_path) for a in args], timeout=120)
    assert proc.returncode == code, proc.stderr
    assert "Traceback" not in proc.stderr + proc.stdout
    for w in words:
        assert w in proc.stderr, proc.stderr


def test_sweep_plots_label_every_axis_with_its_unit(tmp_path, monkeypatch):
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from agrobot.orchestrator.study import Study
    from agrobot.orchestrator.sweep import sweep_plots

    captured = []
    monkeypatch.setattr(Figure, "savefig", lambda self, *a, **k: captured.append(self))
    study = Study.load(ROOT / "studies" / "speed_sweep.toml")
    table = pd.DataFrame({"point": ["p0", "p1"], "seed": [1, 1], "reference.speed": [1.0, 2.0],
                          "status": ["completed"] * 2, "euclid_max_curved": [0.3, 0.2], "steer_rate_rms": [0.1, 0.2]})
    sweep_plots(study, table, tmp_path)
    axes = [ax for ax in captured[0].axes if ax.get_title()]
    labels = {ax.get_title(): (ax.get_xlabel(), ax.get_ylabel()) for ax in axes}
    assert labels["euclid_max_curved"] == ("reference.speed [m/s]", "[m]")
    assert labels["steer_rate_rms"] == ("reference.speed [m/s]", "[rad/s]")


def test_the_documented_metric_table_uses_the_printed_names():
    import re

    from agrobot.analysis.figure8 import METRICS

    text = (ROOT / "docs" / "guidance-loop.md").read_text()
    table = text.split("## What the shipped study gives", 1)[1].split("\n\n", 3)[2]
    names = []
    for row in table.splitlines()[2:]:
        cell = row.split("|")[1].replace("`", "").strip()
        first = re.sub(r"\(.*?\)", "", cell).split("/")[0].strip()
        if first and first != "wall time":
            names.append(first)
    assert len(names) >= 6
    assert set(names) <= set(METRICS), set(names) - set(METRICS)


@pytest.mark.slow
def test_identification_works_on_logs_at_10_20_50_and_100_hz(tmp_path):
    """The same experiment logged at four rates (the command held at 20 Hz in the 50 and 100 Hz
    logs, decimated to 10 Hz): the RLF model identified from each log has the same steady-state
    gain and the same slowest pole as from the 20 Hz log."""
    from agrobot.identification.pipeline import identify_log, identify_study
    from agrobot.orchestrator.study import Study

    logs = {}
    for rate in (20, 50, 100):
        study = tmp_path / f"id{rate}.toml"
        study.write_text(f'extends = "{ROOT / "studies" / "identification.toml"}"\n[components.gyro]\nstep = {1 / rate}\n'
                         f'[identification]\nsample_rate = {float(rate)}\nspeeds = [2.0]\n')
        identify_study(Study.load(study), tmp_path / f"r{rate}", plots=False)
        logs[rate] = tmp_path / f"r{rate}" / "experiment_log.csv"
    ten = pd.read_csv(logs[20]).iloc[::2]
    logs[10] = tmp_path / "r10.csv"
    ten.to_csv(logs[10], index=False)

    def summary(path):
        """|G| at 0.5 and 1 Hz (inside the identification band) and the oscillatory pole pair's magnitude."""
        model = identify_log(path, None, plots=False)["models"]["rlf"]
        s = 2j * np.pi * np.array([0.5, 1.0])
        gains = np.abs(np.polyval(model["num"], s) / np.polyval(model["den"], s))
        pair = max(abs(complex(*p)) for p in model["poles"] if abs(p[1]) > 1e-9)
        return gains, pair

    ref_gains, ref_pair = summary(logs[20])
    for rate in (10, 50, 100):
        gains, pair = summary(logs[rate])
        np.testing.assert_allclose(gains, ref_gains, rtol=0.05, err_msg=f"{rate} Hz")
        assert pair == pytest.approx(ref_pair, rel=0.10), rate


def test_sigterm_landing_inside_a_subsystem_still_ends_the_run_as_terminated(tmp_path, monkeypatch):
    """The interrupt raised while a composite steps its inner system keeps its kind (SIGTERM: exit 143)."""
    from agrobot.orchestrator.errors import Interrupted, Terminated
    from agrobot.orchestrator.runner import run_study
    from agrobot.orchestrator.study import parse_study
    from tests import toy_components

    class TerminatedAt(toy_components.FailAt):
        def step(self, t, dt):
            if t >= self.p["fail_time"] - 1e-12:
                raise Terminated()
            self.y["value"] = t

    monkeypatch.setattr(toy_components, "TerminatedAt", TerminatedAt, raising=False)
    study = parse_study({"study": {"name": "s", "stop_time": 1.0, "base_step": 0.1, "seed": 1},
                         "subsystems": {"inner": {"components": {"f": {"type": "tests.toy_components:TerminatedAt",
                                                                       "parameters": {"fail_time": 0.5}}},
                                                  "exports": {"outputs": {"value": "f.value"}}}}},
                        tmp_path / "s.toml")
    with pytest.raises(Interrupted) as err:
        run_study(study, tmp_path / "out", plots=False)
    assert err.value.exit_status == 143
    assert json.loads((tmp_path / "out" / "metrics.json").read_text())["status"] == "interrupted"
