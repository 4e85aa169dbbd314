"""The hostile cases of the third reliability pass, every one the pass lists (plugins, the live view,
written files, flooded ports, crashing and hanging FMUs, damaged binary recordings, unbounded and
impossible values, the compiled cache, the three left from the second pass), run again as a careless
user or neighbour would: each case is a command (its own process) and what must hold; the script prints
one line per case and the count. Sizes are scaled down where the property is the same (fewer viewers, a
shorter run, a file size limit for a full disk), each case's line says how; each takes seconds.

    python benchmarks/reliability_cases.py                 # this checkout's code
    python benchmarks/reliability_cases.py --tree /work/main   # another checkout's code, for comparison
    python benchmarks/reliability_cases.py --group live --group fmu   # only these groups of cases

Everything is written below a temporary folder; only loopback is used.
"""
from __future__ import annotations

import argparse
import asyncio
import collections
import functools
import json
import os
import re
import resource
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import textwrap
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))          # the tests' generators (tests/test_fuzz_binary_readers.py, tests/fmu_build.py)
from harness.interrupts import ctrl_c_twice_in_flight  # noqa: E402  (after the path above)

F8 = str(ROOT / "studies" / "figure8.toml")
TOY = '[study]\nname = "toy"\nstop_time = 1.0\nbase_step = 0.01\nseed = 1\n[components.clock]\ntype = "tests.toy_components:Clock"\n'


def environment(tree: Path, cache: Path, **extra: str) -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": f"{tree / 'src'}:{ROOT}", "AGROBOT_CACHE": str(cache),
            "OPENBLAS_NUM_THREADS": "1", **extra}


def command(tree: Path, args: list[str], cache: Path, env: dict | None = None, **kw) -> subprocess.CompletedProcess:
    try:
        return subprocess.run(list(map(str, args)), cwd=ROOT, env=env or environment(tree, cache), capture_output=True,
                              text=True, timeout=120, **kw)
    except subprocess.TimeoutExpired as exc:       # a case that hangs fails; the next ones still run
        return subprocess.CompletedProcess(args, None, exc.stdout or "", f"timed out after {exc.timeout} s")


def agrobot(tree, cache, *args, **kw):
    return command(tree, [sys.executable, "-m", "agrobot", *map(str, args)], cache, **kw)


def python(tree, cache, code: str):
    return command(tree, [sys.executable, "-c", textwrap.dedent(code)], cache)


FILE_LIMIT = 600_000        # bytes a file may grow to in the full-disk case: the signals fit, the MCAP does not


def _files_limited(limit: int) -> None:
    """The child's files limited to ``limit`` bytes (RLIMIT_FSIZE; SIGXFSZ ignored, so a write past it fails
    with an OSError as on a full disk)."""
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))


def written_cases(tree: Path, work: Path, cache: Path):
    """--mcap and --record under the rule of written files."""
    toy = work / "toy.toml"
    mcap = work / "kept.mcap"
    mcap.write_bytes(b"someone's file")
    done = agrobot(tree, cache, "run", toy, "--out", work / "o1", "--mcap", mcap)
    yield "--mcap over an existing file without --overwrite: exit 2, file kept", \
        done.returncode == 2 and mcap.read_bytes() == b"someone's file"
    first = subprocess.Popen([sys.executable, "-m", "agrobot", "run", F8, "--out", work / "o2", "--no-plots",
                              "--mcap", work / "both.mcap", "--engine", "python"], cwd=ROOT,
                             env={**os.environ, "PYTHONPATH": f"{tree / 'src'}:{ROOT}"}, stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL)
    second = agrobot(tree, cache, "run", F8, "--out", work / "o3", "--no-plots", "--mcap", work / "both.mcap",
                     "--engine", "python")
    first.wait()
    readable = python(tree, cache, f"""
        import mcap.reader
        with open({str(work / 'both.mcap')!r}, 'rb') as f:
            print(sum(1 for _ in mcap.reader.make_reader(f).iter_messages()))""")
    yield "two runs into one --mcap: the file whole (every message readable), no temporary left", \
        second.returncode in (0, 2) and readable.returncode == 0 and \
        not [p for p in work.iterdir() if p.name.startswith(".both.mcap")]
    full = agrobot(tree, cache, "run", F8, "--set", "study.stop_time=20", "--out", work / "o4", "--no-plots",
                   "--engine", "python", "--mcap", work / "full.mcap", preexec_fn=functools.partial(_files_limited, FILE_LIMIT))
    yield "--mcap on a disk that fills (a file size limit): a named error (exit 2, no traceback), nothing left " \
          "behind", full.returncode == 2 and "Traceback" not in full.stderr and \
        not [p for p in work.iterdir() if "full.mcap" in p.name]
    yield from _mcap_memory(tree, work, cache)
    rec = work / "rec"
    rec.mkdir()
    (rec / "gps.nmea").write_text("an earlier drive\n")
    done = agrobot(tree, cache, "run", ROOT / "studies" / "field_test.toml", "--out", work / "o5", "--record", rec,
                   "--set", "study.stop_time=0.5", "--no-plots")
    yield "--record over an earlier recording without --overwrite: exit 2, recording kept", \
        done.returncode == 2 and (rec / "gps.nmea").read_text() == "an earlier drive\n"


PEAK = """
    import resource, subprocess, sys
    subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss // 1024)"""
MCAP_RUN_S = 2000           # s of the figure-8 (the 8,000 s held 2.35 GB with --mcap, 393 MB without)


def _mcap_memory(tree: Path, work: Path, cache: Path):
    peaks = []
    for k, extra in enumerate(([], ["--mcap", work / "long.mcap"])):
        done = command(tree, [sys.executable, "-c", textwrap.dedent(PEAK), sys.executable, "-m", "agrobot", "run", F8,
                              "--out", work / f"long{k}", "--no-plots", "--no-progress", "--engine", "compiled",
                              "--set", f"study.stop_time={MCAP_RUN_S}", *map(str, extra)], cache)
        peaks.append(int(done.stdout.split()[-1]) if done.returncode == 0 else None)
    yield f"--mcap on a {MCAP_RUN_S} s run (the issue's 8,000 s scaled down): peak memory within 25 % of the " \
          f"same run without it (MB: {peaks[0]} without, {peaks[1]} with)", \
        None not in peaks and peaks[1] <= 1.25 * peaks[0]


PLUGINS = {"entry_points.txt": "[agrobot.plugins]\nbroken = brokenplug_missing:register\n"
                               "raiser = brokenplug:register\n",
           "METADATA": "Metadata-Version: 2.1\nName: brokenplug\nVersion: 1.0\n"}


def plugin_cases(tree: Path, work: Path, cache: Path):
    """A distribution with two plugins: one whose module is missing, one whose register raises."""
    site = work / "site"
    (site / "brokenplug-1.0.dist-info").mkdir(parents=True)
    for name, text in PLUGINS.items():
        (site / "brokenplug-1.0.dist-info" / name).write_text(text)
    (site / "brokenplug.py").write_text("def register(reg):\n    raise RuntimeError('boom in register')\n")
    env = environment(tree, cache, PYTHONPATH=f"{tree / 'src'}:{ROOT}:{site}")
    done = [agrobot(tree, cache, *args, env=env)
            for args in (["--version"], ["run", "--help"], ["run", work / "toy.toml", "--out", work / "p1"])]
    lines = [[x for x in d.stderr.splitlines() if x.startswith("warning: plugin")] for d in done]
    worked = all(d.returncode == 0 and "Traceback" not in d.stderr for d in done)
    yield "a plugin whose module cannot be imported: --version, run --help and a run work, the plugin named in one " \
          "warning line", worked and all(sum("'broken' of brokenplug" in x for x in w) == 1 for w in lines)
    yield "a plugin whose register() raises: the same, its name and error in one line", \
        worked and all(sum("'raiser' of brokenplug" in x and "boom in register" in x for x in w) == 1 for w in lines)


def _free_port(kind: int = socket.SOCK_STREAM) -> int:
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


async def _crowd(port: int, run: subprocess.Popen, slow: int, refused: int) -> list:
    """``slow`` viewers that subscribe to every channel and never read (receive buffers of 4 kB), then
    ``refused`` more connecting at once while the run goes; the close codes of the latter."""
    from websockets.asyncio.client import connect
    from websockets.exceptions import ConnectionClosed, InvalidHandshake

    async def viewer():
        s = socket.socket()
        s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        s.connect(("127.0.0.1", port))
        ws = await connect(f"ws://127.0.0.1:{port}", sock=s, proxy=None, max_queue=1, subprotocols=["foxglove.sdk.v1"])
        channels = {}
        while True:
            try:
                op = json.loads(await asyncio.wait_for(ws.recv(), 1.0 if channels else 60.0))
            except asyncio.TimeoutError:
                break
            channels.update({c["id"]: c for c in op.get("channels", [])} if op.get("op") == "advertise" else {})
        await ws.send(json.dumps({"op": "subscribe", "subscriptions": [{"id": i, "channelId": i} for i in channels]}))
        return ws

    async def one_more():
        """1013 (refused with the reason), the name of what ended the attempt, or 'served'."""
        try:
            ws = await connect(f"ws://127.0.0.1:{port}", subprotocols=["foxglove.websocket.v1"], proxy=None,
                               open_timeout=30)
            await ws.recv()
            await ws.close()
            return "served"
        except ConnectionClosed as exc:
            return exc.rcvd.code if exc.rcvd is not None else "closed"
        except (OSError, asyncio.TimeoutError, InvalidHandshake) as exc:
            return type(exc).__name__
    deadline = time.monotonic() + 60
    while run.poll() is None and time.monotonic() < deadline:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1).close()
            break
        except OSError:
            await asyncio.sleep(0.2)
    viewers = [await viewer() for _ in range(slow)]
    codes = await asyncio.gather(*(one_more() for _ in range(refused)))
    while run.poll() is None:
        await asyncio.sleep(0.2)
    for ws in viewers:
        ws.transport.abort()
    return codes


LIVE_S = 6.0                # s of figure8_hardware_layout paced at 50 ms


def _paced(tree: Path, cache: Path, out: Path, port: int | None) -> tuple[dict, list]:
    """figure8_hardware_layout.toml paced in real time for LIVE_S: with the live view on ``port`` and its
    crowd (``_crowd``: 6 slow viewers, 200 more), or without it (None): (its realtime metrics, the codes)."""
    live = [] if port is None else ["--live", f"127.0.0.1:{port}", "--live-wait", "60", "--live-viewers", "8"]
    run = subprocess.Popen([sys.executable, "-m", "agrobot", "run", ROOT / "studies" / "figure8_hardware_layout.toml",
                            "--out", out, "--no-plots", "--no-progress", *live, "--set", "study.realtime=true", "--set",
                            f"study.stop_time={LIVE_S:g}", "--set", "reference.ramp_time=1"], cwd=ROOT,
                           env=environment(tree, cache), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    codes: list = []
    try:
        if port is not None:
            codes = asyncio.run(asyncio.wait_for(_crowd(port, run, 6, 200), 180))
        run.wait(timeout=180)
    except (OSError, asyncio.TimeoutError, subprocess.TimeoutExpired) as exc:
        codes = [repr(exc)]
    finally:
        if run.poll() is None:
            run.kill()
        run.wait()
    try:
        return json.loads((out / "metrics.json").read_text())["realtime"], codes
    except (OSError, ValueError, KeyError):
        return {"steps": 0, "deadline_misses": -1, "jitter_ms": {"max": float("nan")}}, codes


def live_cases(tree: Path, work: Path, cache: Path):
    """The live view: many viewers and slow ones during a real-time run; its numbers bounded."""
    alone, _ = _paced(tree, cache, work / "alone", None)
    rt, codes = _paced(tree, cache, work / "live", _free_port())
    steps = round(LIVE_S / 0.05) + 1
    ended = collections.Counter(codes)
    yield f"206 viewers (the issue's 1,000 scaled down; 6 subscribed that never read, then 200 more at once: the 2 " \
          f"the limit of 8 leaves served, 198 refused) during a real-time run: {rt['deadline_misses']} of " \
          f"{rt['steps']} steps more than 2 ms late ({alone['deadline_misses']} without the live view; at most 10 % " \
          f"of the steps more), worst {rt['jitter_ms']['max']:.0f} ms (under 500, the tests' real-time tolerance); " \
          f"the 200: {', '.join(f'{n} {c}' for c, n in ended.most_common())}", \
        rt["steps"] == alone["steps"] == steps and 0 <= rt["deadline_misses"] <= alone["deadline_misses"] + 0.1 * steps \
        and rt["jitter_ms"]["max"] < 500 and ended == {1013: 198, "served": 2}
    done = agrobot(tree, cache, "run", F8, "--out", work / "l1", "--live", "127.0.0.1:99999")
    yield "--live 127.0.0.1:99999: exit 2 naming the port", done.returncode == 2 and "99999" in done.stderr and \
        "Traceback" not in done.stderr and not (work / "l1").exists()
    done = agrobot(tree, cache, "run", F8, "--out", work / "l2", "--live", "127.0.0.1:0", "--live-wait", "inf")
    yield "--live-wait inf: exit 2 naming it", done.returncode == 2 and "--live-wait" in done.stderr and \
        "Traceback" not in done.stderr and not (work / "l2").exists()


FLOOD = 200                 # junk datagrams every 10 ms (one base step): three times a step's max_frames (64)


def _flood(port: int, stop: threading.Event) -> None:
    """FLOOD junk datagrams (no frame) on the CAN port every 10 ms, until ``stop`` (the sender takes little CPU:
    the emulator's cost is its own)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as out:
        k = 0
        while not stop.is_set():
            out.sendto(b"\xc1junk%d" % k, ("127.0.0.1", port))
            k += 1
            if k % FLOOD == 0:
                time.sleep(0.01)


def _emulated(tree: Path, cache: Path, out: Path, flood: bool) -> tuple[int, dict, str]:
    """The emulator for 5.5 s (the issue's 22 s; its analysis needs 5 s), its CAN port flooded with junk or not: (its exit status, its
    realtime metrics, its events)."""
    port, stop = _free_port(socket.SOCK_DGRAM), threading.Event()
    sender = threading.Thread(target=_flood, args=(port, stop), daemon=True)
    if flood:
        sender.start()
    try:
        done = agrobot(tree, cache, "emulate", ROOT / "studies" / "tractor_emulator.toml", "--nmea-port", "0",
                       "--duration", "5.5", "--out", out, "--no-progress", "--set", f"can.port={port}")
    finally:
        stop.set()
        if flood:
            sender.join()
    try:
        return done.returncode, json.loads((out / "metrics.json").read_text())["realtime"], \
            (out / "events.log").read_text()
    except (OSError, ValueError, KeyError):
        return done.returncode, {"steps": 0, "deadline_misses": -1, "jitter_ms": {"max": float("nan")}}, ""


def flood_cases(tree: Path, work: Path, cache: Path):
    """A flood of junk datagrams on the emulator's CAN port for its whole run."""
    _, alone, _ = _emulated(tree, cache, work / "quiet", False)
    code, rt, events = _emulated(tree, cache, work / "flooded", True)
    yield f"a flood of junk datagrams on the emulator's CAN port (5.5 s, 20,000 a second): counted as flooded and " \
          f"reported; no stall: the latest step {rt['jitter_ms']['max']:.0f} ms late (under 50; the issue's 234), " \
          f"{rt['deadline_misses']} of {rt['steps']} more than 2 ms late ({alone['deadline_misses']} without the " \
          f"flood on this machine: each step reads its 64 datagrams)", \
        code == 0 and "CAN commands flooded" in events and "refused" in events and rt["steps"] > 0 and \
        0 <= rt["jitter_ms"]["max"] < 50


FAILING = """[study]
name = "failing"
stop_time = 2.0
base_step = 0.1
seed = 1
signals_format = "csv"
[components.m]
type = "misbehaving.fmu"
parameters = {{ fail_time = 0.5, fail_mode = {mode} }}
"""


def _hung(tree: Path, work: Path, cache: Path, sig: int) -> tuple[float, subprocess.Popen, str]:
    """A run of the FMU that hangs in doStep at 0.5 s (default isolation), sent ``sig`` 4 s after its FMU's
    process started: (seconds until it ended, the process, its stderr)."""
    study = work / "hang.toml"
    study.write_text(FAILING.format(mode=3))
    run = subprocess.Popen([sys.executable, "-m", "agrobot", "run", study, "--out", work / f"hung{sig}", "--no-plots",
                            "--no-progress"], cwd=ROOT, env=environment(tree, cache), stdout=subprocess.DEVNULL,
                           stderr=subprocess.PIPE, text=True)
    children, end = Path(f"/proc/{run.pid}/task/{run.pid}/children"), time.time() + 60
    while time.time() < end and run.poll() is None and not children.read_text().split():
        time.sleep(0.2)
    time.sleep(4.0)
    run.send_signal(sig)
    sent = time.monotonic()
    try:
        _, err = run.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        run.kill()
        _, err = run.communicate()
    return time.monotonic() - sent, run, err


def fmu_cases(tree: Path, work: Path, cache: Path):
    """A foreign FMU that segfaults or hangs, run as a study that says nothing about isolation."""
    from tests.fmu_build import build_test_fmu

    build_test_fmu("misbehaving", work)
    (work / "segv.toml").write_text(FAILING.format(mode=1))
    done = agrobot(tree, cache, "run", work / "segv.toml", "--out", work / "segv", "--no-plots", "--no-progress")
    hidden = [p for p in work.iterdir() if p.name.startswith(".segv")]
    yield "a foreign FMU segfaulting at 0.5 s, by default: a named error (the component, the call, the signal), " \
          "the signals until then kept, no hidden staging folder left", \
        done.returncode not in (0, 139, -11, None) and "SIGSEGV" in done.stderr and "doStep" in done.stderr and \
        "Traceback" not in done.stderr and not hidden and \
        any(len(p.read_text().splitlines()) > 5 for p in work.glob("segv*/signals.csv"))
    for sig, name in ((signal.SIGTERM, "SIGTERM"), (signal.SIGINT, "Ctrl-C")):
        took, run, err = _hung(tree, work, cache, sig)
        yield f"a foreign FMU hanging in doStep, by default: {name} ends the run in {took:.1f} s (under 5), no " \
              f"traceback", run.returncode not in (0, None, -9) and took < 5.0 and "Traceback" not in err


CHANNEL = """
    import csv, sys
    from pathlib import Path
    from harness.quirk_recordings import compose
    folder = Path(sys.argv[1])
    compose(3, folder, classes=[], layout="table", machine="tractor")
    rows = list(csv.reader((folder / "log.csv").open()))
    v = rows[0].index("v")
    for k in (100, 400, 900) if sys.argv[2] == "samples" else range(1, len(rows)):
        rows[k][v] = "9.2e18"
    with (folder / "log.csv").open("w") as f:
        csv.writer(f, lineterminator="\\n").writerows(rows)"""
EXPORTED = """
    import math
    from pathlib import Path
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    from agrobot.fmu_export.component_fmus import export_component
    from agrobot.orchestrator.build import build_system
    from agrobot.orchestrator.resolver import resolve
    from agrobot.orchestrator.study import Study
    system = build_system(resolve(Study.load({f8!r}, ["study.stop_time=5"])))
    fmu = Path({where!r})
    fmu.write_bytes(export_component(system, "tractor"))
    md = read_model_description(str(fmu))
    inputs = [v.valueReference for v in md.modelVariables if v.causality == "input"]
    outputs = [v.valueReference for v in md.modelVariables if v.causality == "output"]
    s = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu)), modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName="x")
    s.instantiate(); s.setupExperiment(startTime=0.0); s.enterInitializationMode(); s.exitInitializationMode()
    h, t, refused = float(md.defaultExperiment.stepSize), 0.0, False
    try:
        s.setReal(inputs[:1], [1e308])
    except Exception:
        refused = True
    for _ in range(50):
        s.setReal(inputs, [0.1] * len(inputs))
        s.doStep(t, h)
        t += h
    print(refused, sum(not math.isfinite(y) for y in s.getReal(outputs)), len(outputs))"""


def number_cases(tree: Path, work: Path, cache: Path):
    """Values without the bound they need, and impossible values taken as data."""
    for setting in ("tractor.m=inf", "steering.command_delay=nan"):
        done = agrobot(tree, cache, "run", F8, "--out", work / "o6", "--set", setting, "--engine", "compiled")
        yield f"--set {setting} --engine compiled: exit 2 naming it", \
            done.returncode == 2 and setting.split("=")[0].split(".")[1] in done.stderr and "Traceback" not in done.stderr
    sweep = work / "sweep.toml"
    sweep.write_text(TOY + '[sweep]\nmode = "monte_carlo"\nsamples = 1000000000000\n'
                           'parameters = { "study.stop_time" = { uniform = [1.0, 2.0] } }\n')
    done = agrobot(tree, cache, "sweep", sweep, "--out", work / "o7", "--workers", "1")
    yield "sweep.samples = 10^12: exit 2 with the numbers", done.returncode == 2 and "1e+12" in done.stderr
    empty = work / "empty"
    empty.mkdir()
    done = python(tree, cache, f"""
        import os; os.chdir({str(empty)!r})
        import agrobot
        from agrobot.orchestrator.output import OutputError
        try:
            agrobot.run({F8!r}, out='')
        except OutputError as exc:
            print('refused:', exc)""")
    yield "agrobot.run(..., out=''): refused by name", "refused:" in done.stdout and "working folder" in done.stdout
    done = agrobot(tree, cache, "run", F8, "--out", work / "o8", "--set", "study.base_step=1e-9")
    yield f"study.base_step = 1e-9 for the figure-8's chain of subsystems: exit 2 in one short line " \
          f"({len(done.stderr)} bytes, at most 1,000)", done.returncode == 2 and len(done.stderr) <= 1000 and \
        "base_step" in done.stderr
    for which, code in (("samples", 0), ("channel", 2)):
        made = command(tree, [sys.executable, "-c", textwrap.dedent(CHANNEL), work / which, which], cache)
        done = agrobot(tree, cache, "convert", work / which, "--out", work / f"{which}.csv")
        yield f"a log whose speed reads 9.2e18 m/s ({'three samples' if code == 0 else 'every sample'}): named in " \
              f"the audit as out of range ({'masked, exit 0' if code == 0 else 'refused, exit 2'})", \
            made.returncode == 0 and done.returncode == code and "out_of_range" in done.stdout + done.stderr and \
            "9.2e+18 m/s" in done.stdout + done.stderr
    done = python(tree, cache, EXPORTED.format(f8=F8, where=str(work / "tractor.fmu")))
    got = done.stdout.split()[-3:] if done.returncode == 0 else ["", "", ""]
    yield f"an input of 1e308 to the exported tractor FMU: refused with an FMI error, then {got[1] or '?'} of " \
          f"{got[2] or '?'} outputs non-finite after 50 finite steps (none)", got[:2] == ["True", "0"]


def leftover_cases(tree: Path, work: Path, cache: Path):
    """The three left from the second pass: a double Ctrl-C on a Dask sweep, a sweep on a full disk, a long name."""
    sleepers = work / "sleepers.toml"
    sleepers.write_text(SLEEPERS)
    out = work / "dask"
    run = subprocess.Popen([sys.executable, "-m", "agrobot", "sweep", sleepers, "--out", out, "--workers", "2",
                            "--scheduler", "local", "--no-progress", "--no-plots"], cwd=ROOT, start_new_session=True,
                           env=environment(tree, cache), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    started = ctrl_c_twice_in_flight(run, out / ".running")         # points in flight when interrupted
    sent = time.monotonic()
    try:
        run.communicate(timeout=15)
    except subprocess.TimeoutExpired:
        os.killpg(run.pid, signal.SIGKILL)
        run.communicate()
    took = time.monotonic() - sent
    yield f"a double Ctrl-C on a Dask sweep: ended in {took:.1f} s (under 10) without SIGKILL, nothing running left", \
        started and took < 10 and run.returncode not in (-9, None) and not (out / ".running").exists()
    grown = work / "grown.toml"
    grown.write_text(TOY + '[sweep]\nparameters = { "study.stop_time" = [1.0, 400.0] }\n')
    done = agrobot(tree, cache, "sweep", grown, "--out", work / "full", "--workers", "1", "--no-progress",
                   "--no-plots", preexec_fn=functools.partial(_files_limited, TINY_FILE))
    yield "a sweep whose second point fills the disk (a file size limit): exit 2 naming it, no traceback, the first " \
          "point kept, no temporary file", done.returncode == 2 and "Traceback" not in done.stderr and \
        "p0001" in done.stderr and (work / "full" / "points" / "p0000" / "metrics.json").is_file() and \
        not list((work / "full").rglob("*.tmp"))
    for verb in ("run", "sweep"):
        done = agrobot(tree, cache, verb, work / ("toy.toml" if verb == "run" else "sleepers.toml"), "--out",
                       work / ("a" * 256), "--no-progress")
        yield f"{verb} --out of a 256-character name: exit 2 naming it", done.returncode == 2 and \
            "choose a shorter name" in done.stderr and "Traceback" not in done.stderr


SLEEPERS = """[study]
name = "sleepers"
stop_time = 20.0
base_step = 0.05
seed = 1
signals_format = "csv"
[components.s]
type = "tests.toy_components:Sleeper"
parameters = { sleep = 0.0, every = 1 }
[sweep]
parameters = { "s.sleep" = [0.05, 0.05, 0.05, 0.05] }
"""
TINY_FILE = 100_000         # bytes: the 1 s point's signals fit, the 400 s point's do not


def cases(tree: Path, work: Path, groups: list[str]):
    """(name, holds) for every case of the chosen groups (all when none is chosen)."""
    cache = work / "cache"
    (work / "toy.toml").write_text(TOY)
    for name, group in GROUPS.items():
        if not groups or name in groups:
            yield from group(tree, work, cache)


def compiled_cases(tree: Path, work: Path, cache: Path):
    build = python(tree, cache, """
        from agrobot.orchestrator.compiled import toolchain
        print(toolchain.library({'loop.c': 'int agc_run(double*p,double*y,double*u,long n,double*o){return 0;}'}, [], [])[1])""")
    key = build.stdout.split()[-1] if build.returncode == 0 else "none"
    folder = cache / "compiled" / key
    marker = work / "constructor-ran"
    planted = work / "planted.c"
    planted.write_text(f'#include <stdio.h>\n__attribute__((constructor)) static void p(void) {{ fclose(fopen("{marker}",'
                       f' "w")); }}\nconst char *agc_token(void) {{ return "{key}"; }}\n'
                       'int agc_run(double*p,double*y,double*u,long n,double*o){return -1;}\n')
    subprocess.run(["cc", "-shared", "-fPIC", "-o", str(folder / "libloop.so"), str(planted)], check=False)
    again = python(tree, cache, """
        from agrobot.orchestrator.compiled import toolchain
        print(toolchain.library({'loop.c': 'int agc_run(double*p,double*y,double*u,long n,double*o){return 0;}'}, [], [])[0].agc_run(None, None, None, 0, None))""")
    yield "a planted library in the cache: its constructor never runs, the shape rebuilt", \
        not marker.exists() and again.returncode == 0 and again.stdout.split()[-1:] == ["0"]
    lib = folder / "libloop.so"
    lib.write_bytes(lib.read_bytes()[:100])
    again = python(tree, cache, """
        from agrobot.orchestrator.compiled import toolchain
        print(toolchain.library({'loop.c': 'int agc_run(double*p,double*y,double*u,long n,double*o){return 0;}'}, [], [])[2])""")
    yield "a truncated cached library: built again", again.returncode == 0 and again.stdout.split()[-1:] == ["True"]
    os.chmod(cache / "compiled", 0o777)
    done = agrobot(tree, cache, "run", F8, "--out", work / "c1", "--engine", "compiled", "--no-plots")
    os.chmod(cache / "compiled", 0o700)
    yield "a cache folder others may write: --engine compiled refused naming it (exit 2)", \
        done.returncode == 2 and str(cache / "compiled") in done.stderr


FUZZ = """
    import random, struct, tempfile, time
    from pathlib import Path
    from agrobot.orchestrator.errors import InputError
    from agrobot.measurements.recording import import_recording
    from tests.test_fuzz_binary_readers import _base, damaged
    rng, bad = random.Random(58), []
    for kind in ("tlg", "ros1", "mcap", "db3", "blf"):
        name, data = _base(kind)
        for trial in range({n}):
            edits = [(rng.choice(["flip", "cut", "truncate", "zero", "huge", "back"]), rng.random(),
                      rng.choice([4, 8]), rng.randrange(256)) for _ in range(rng.randint(1, 3))]
            with tempfile.TemporaryDirectory() as tmp:
                path = Path(tmp) / name
                path.write_bytes(damaged(data, edits))
                if kind == "tlg":
                    (Path(tmp) / "TLG00001.xml").write_bytes(_base("tlg_header")[1])
                began = time.perf_counter()
                try:
                    import_recording(Path(tmp) if kind == "tlg" else path)
                except InputError as exc:
                    text = str(exc)
                    if str(path) not in text or "MemoryError" in text or not any(
                            w in text.replace(str(path), "") for w in ("offset", "byte", "record", "message",
                                                                       "frame", "stream", "magic", "empty", "no ",
                                                                       "page", "table")):
                        bad.append((kind, text[:160]))
                except Exception as exc:
                    bad.append((kind, type(exc).__name__))
                if time.perf_counter() - began > 10:
                    bad.append((kind, "slow"))
    print(len(bad), bad[:3])
"""


def reader_cases(tree: Path, work: Path, cache: Path):
    """Binary recordings with impossible sizes, and many damaged copies of each binary format."""
    from tests.test_fuzz_binary_readers import _base

    for kind, at, value in (("ros1", 13, struct.pack("<I", 0xFFFFFFF0)), ("mcap", 9, struct.pack("<Q", 1 << 62))):
        name, data = _base(kind)
        path = work / name
        path.write_bytes(data[:at] + value + data[at + len(value):])
        done = agrobot(tree, cache, "convert", path, "--out", work / f"{kind}.csv")
        yield f"a {kind} bag declaring a record of {int.from_bytes(value, 'little')} bytes: exit 2 naming the " \
              f"file and the byte offset", done.returncode == 2 and f"(at byte offset {at if kind == 'ros1' else 8})" \
            in done.stderr and str(path) in done.stderr
    yield from _looped_mdf4(tree, work, cache)
    done = python(tree, cache, FUZZ.format(n=100))
    yield "100 damaged copies each of a TLG.bin, ROS 1 bag, MCAP, ROS 2 .db3 and BLF: each read or refused naming " \
          "the file and where, in seconds", done.returncode == 0 and done.stdout.split()[:1] == ["0"]


def _looped_mdf4(tree: Path, work: Path, cache: Path):
    """An MDF4 file whose second data group's next link points back to the first: convert and --list."""
    from tests.test_mdf4_links import two_groups

    path = two_groups(work / "looped.mf4")
    raw = bytearray(path.read_bytes())
    first = raw.find(b"##DG")
    second = raw.find(b"##DG", first + 1)
    raw[second + 24:second + 32] = struct.pack("<Q", first)
    path.write_bytes(bytes(raw))
    for how in (["--out", work / "looped.csv"], ["--list"]):
        began = time.perf_counter()
        done = agrobot(tree, cache, "convert", path, *how)
        took = time.perf_counter() - began
        yield f"an MDF4 file whose links loop, convert {how[0]}: exit 2 in {took:.1f} s (under 10) naming the file " \
              f"and the offset", done.returncode == 2 and took < 10 and str(path) in done.stderr and \
            f"offset {second}" in done.stderr


CRASH = """[study]
name = "crashing"
stop_time = 3.0
base_step = 0.1
seed = 1
realtime = true
isolate_fmus = false
[components.m]
type = "misbehaving.fmu"
parameters = { fail_time = 1.5, fail_mode = 1 }
"""


def emulator_and_crash_cases(tree: Path, work: Path, cache: Path):
    """emulate --record over an earlier recording; a segfault in an FMU kept in this process."""
    rec = work / "emulated"
    rec.mkdir()
    (rec / "gps.nmea").write_text("an earlier drive\n")
    done = agrobot(tree, cache, "emulate", ROOT / "studies" / "tractor_emulator.toml", "--nmea-port", "0",
                   "--duration", "1", "--record", rec, "--set", "can.interface=virtual", "--set", "can.channel=cases")
    yield "emulate --record (no --out) over an earlier recording without --overwrite: exit 2, recording kept", \
        done.returncode == 2 and (rec / "gps.nmea").read_text() == "an earlier drive\n"
    from tests.fmu_build import build_test_fmu

    build_test_fmu("misbehaving", work)
    (work / "crashing.toml").write_text(CRASH)
    done = agrobot(tree, cache, "run", work / "crashing.toml", "--out", work / "crashed", "--no-progress",
                   "--engine", "python", "--no-plots")
    named = re.search(r"the signals recorded until the crash: (\S+) \(", done.stderr)
    read = python(tree, cache, f"""
        from agrobot.orchestrator.atomic_files import read_partial
        t = read_partial({named.group(1) if named else ''!r})["t"]
        print(len(t), abs(t - [0.1 * k for k in range(len(t))]).max())""")
    yield "an FMU kept in this process segfaults at t = 1.5 s: the dump names where the signals until then are, " \
          "and they read back (t = 0 .. 1.2 s or later)", \
        named is not None and read.returncode == 0 and int(read.stdout.split()[0]) >= 12 and \
        float(read.stdout.split()[1]) < 1e-9


GROUPS = {"plugins": plugin_cases, "live": live_cases, "written": written_cases, "flood": flood_cases,
          "fmu": fmu_cases, "readers": reader_cases, "numbers": number_cases, "compiled": compiled_cases,
          "leftovers": leftover_cases, "emulate": emulator_and_crash_cases}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tree", type=Path, default=ROOT, help="the checkout whose code runs (default: this one)")
    parser.add_argument("--group", action="append", choices=sorted(GROUPS), default=[],
                        help="run only this group of cases (repeatable; default: all)")
    args = parser.parse_args()
    held = total = 0
    with tempfile.TemporaryDirectory(prefix="reliability-") as tmp:
        for name, holds in cases(args.tree.resolve(), Path(tmp), args.group):
            total += 1
            held += bool(holds)
            print(f"{'holds' if holds else 'FAILS'}  {name}", flush=True)
    print(f"{held} of {total} cases hold ({args.tree})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
