"""The hostile cases of the third reliability pass on written files, the compiled cache, crashing FMUs,
study values, flooded ports and damaged binary recordings, run again as a careless user or neighbour
would: each case is a command (its own process) and what must hold; the script prints one line per case
and the count.

    python benchmarks/reliability_cases.py                 # this checkout's code
    python benchmarks/reliability_cases.py --tree /work/main   # another checkout's code, for comparison

Everything is written below a temporary folder; only loopback is used.
"""
from __future__ import annotations

import argparse
import os
import re
import struct
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))          # the tests' generators (tests/test_fuzz_binary_readers.py, tests/fmu_build.py)
F8 = str(ROOT / "studies" / "figure8.toml")
TOY = '[study]\nname = "toy"\nstop_time = 1.0\nbase_step = 0.01\nseed = 1\n[components.clock]\ntype = "tests.toy_components:Clock"\n'


def command(tree: Path, args: list[str], cache: Path, **kw) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": f"{tree / 'src'}:{ROOT}", "AGROBOT_CACHE": str(cache),
           "OPENBLAS_NUM_THREADS": "1"}
    try:
        return subprocess.run(args, cwd=ROOT, env=env, capture_output=True, text=True, timeout=120, **kw)
    except subprocess.TimeoutExpired as exc:       # a case that hangs fails; the next ones still run
        return subprocess.CompletedProcess(args, None, exc.stdout or "", f"timed out after {exc.timeout} s")


def agrobot(tree, cache, *args, **kw):
    return command(tree, [sys.executable, "-m", "agrobot", *map(str, args)], cache, **kw)


def python(tree, cache, code: str):
    return command(tree, [sys.executable, "-c", textwrap.dedent(code)], cache)


FILE_LIMIT = 600_000        # bytes a file may grow to in the full-disk case: the signals fit, the MCAP does not


def _small_files() -> None:
    """The child's files limited to FILE_LIMIT bytes (RLIMIT_FSIZE; SIGXFSZ ignored, so a write past it fails
    with an OSError as on a full disk)."""
    import resource
    import signal

    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (FILE_LIMIT, FILE_LIMIT))


def cases(tree: Path, work: Path):
    """(name, holds) for every case."""
    cache = work / "cache"
    toy = work / "toy.toml"
    toy.write_text(TOY)
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
                   "--engine", "python", "--mcap", work / "full.mcap", preexec_fn=_small_files)
    yield "--mcap on a disk that fills: a named error (exit 2, no traceback), nothing left behind", \
        full.returncode == 2 and "Traceback" not in full.stderr and \
        not [p for p in work.iterdir() if "full.mcap" in p.name]
    rec = work / "rec"
    rec.mkdir()
    (rec / "gps.nmea").write_text("an earlier drive\n")
    done = agrobot(tree, cache, "run", ROOT / "studies" / "field_test.toml", "--out", work / "o5", "--record", rec,
                   "--set", "study.stop_time=0.5", "--no-plots")
    yield "--record over an earlier recording without --overwrite: exit 2, recording kept", \
        done.returncode == 2 and (rec / "gps.nmea").read_text() == "an earlier drive\n"
    yield from compiled_cases(tree, work, cache)
    yield from reader_cases(tree, work, cache)
    yield from emulator_and_crash_cases(tree, work, cache)
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
    for kind in ("tlg", "ros1", "mcap", "blf"):
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
                                                                       "frame", "stream", "magic", "empty", "no ")):
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
    done = python(tree, cache, FUZZ.format(n=100))
    yield "100 damaged copies each of a TLG.bin, ROS 1 bag, MCAP and BLF: each read or refused naming the file " \
          "and where, in seconds", done.returncode == 0 and done.stdout.split()[:1] == ["0"]


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


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tree", type=Path, default=ROOT, help="the checkout whose code runs (default: this one)")
    args = parser.parse_args()
    held = total = 0
    with tempfile.TemporaryDirectory(prefix="reliability-") as tmp:
        for name, holds in cases(args.tree.resolve(), Path(tmp)):
            total += 1
            held += bool(holds)
            print(f"{'holds' if holds else 'FAILS'}  {name}", flush=True)
    print(f"{held} of {total} cases hold ({args.tree})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
