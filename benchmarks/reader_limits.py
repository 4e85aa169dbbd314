"""The readers at their limits: large recordings through ``convert``, wall time and peak memory.

    python3 benchmarks/reader_limits.py [--cases nmea_1m,day_10hz,can_1h] [--repo PATH] [--keep DIR]

Each case is generated (harness.generated_recordings: a straight drive at 2 m/s, written from known
values), then converted by ``python -m agrobot convert`` in a child process with the code
tree ``--repo`` (default: this one) on its PYTHONPATH; its peak resident memory is the child's
``ru_maxrss`` (resource.getrusage(RUSAGE_CHILDREN), read in a fresh parent per case, so that
no other child counts). Cases:

- nmea_1m: one million NMEA lines (GGA + RMC, 10 Hz, 500,000 epochs, about 80 MB);
- day_10hz: a day-long 10 Hz NMEA log (864,000 epochs, 1.7 million lines);
- can_1h: an hour of candump at 100 Hz of the used message plus 400 Hz of messages the DBC does
  not know (1.8 million lines), read on the logger's clock.

The table gives the file's size and lines, the seconds, the peak memory and the rows written.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))          # the test harness (harness/), beside the package

from harness.generated_recordings import candump_lines, nmea_lines  # noqa: E402  - the generators the tests use


def _write_nmea(path: Path, seconds: float) -> int:
    n = 0
    with open(path, "w") as f:
        for line in nmea_lines(seconds):
            f.write(line + "\n")
            n += 1
    return n


def _write_can(path: Path, seconds: float) -> int:
    n = 0
    with open(path, "w") as f:
        for k, line in enumerate(candump_lines(seconds, rate=100.0)):
            f.write(line + "\n")
            t = float(line[1:line.index(")")])
            for j in range(4):          # other senders the DBC does not know
                f.write(f"({t + 0.002 * (j + 1):.6f}) can0 {0x300 + j:03X}#0011223344556677\n")
            n += 5
    return n


CASES = {"nmea_1m": ("gps.nmea", lambda p: _write_nmea(p, 50_000.0)),
         "day_10hz": ("gps.nmea", lambda p: _write_nmea(p, 86_400.0)),
         "can_1h": ("bus.log", lambda p: _write_can(p, 3_600.0))}

MEASURE = """
import resource, subprocess, sys, time, json
start = time.perf_counter()
proc = subprocess.run(sys.argv[2:], capture_output=True, text=True, env={**__import__('os').environ, 'PYTHONPATH': sys.argv[1]})
wall = time.perf_counter() - start
peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0
print(json.dumps({"code": proc.returncode, "wall_s": wall, "peak_mb": peak, "stdout": proc.stdout[-2000:],
                  "stderr": proc.stderr[-2000:]}))
"""


def measure(repo: Path, args: list[str]) -> dict:
    out = subprocess.run([sys.executable, "-c", MEASURE, str(repo), sys.executable, "-m", "agrobot", *args],
                         capture_output=True, text=True, cwd=repo)
    return json.loads(out.stdout)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--cases", default=",".join(CASES), help="comma-separated: " + ", ".join(CASES))
    p.add_argument("--repo", type=Path, default=ROOT, help="the code tree to run (its PYTHONPATH)")
    p.add_argument("--keep", type=Path, default=None, help="write the inputs and logs here (default: a temporary folder)")
    args = p.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        work = args.keep or Path(tmp)
        for case in args.cases.split(","):
            name, write = CASES[case]
            folder = work / case
            folder.mkdir(parents=True, exist_ok=True)
            source = folder / name
            start = time.perf_counter()
            lines = write(source)
            made = time.perf_counter() - start
            r = measure(args.repo, ["convert", str(source), "--out", str(folder / "log.csv")])
            rows_out = sum(1 for _ in open(folder / "log.csv")) - 1 if r["code"] == 0 else 0
            why = "" if r["code"] == 0 else r["stderr"].strip().splitlines()[-1][:80]
            rows.append((case, f"{source.stat().st_size / 2**20:.0f} MB", f"{lines:,}", f"{made:.0f}",
                         f"{r['wall_s']:.1f}", f"{r['peak_mb']:.0f}", f"{rows_out:,}" if not why else why))
            print(f"{case}: exit {r['code']}, {r['wall_s']:.1f} s, {r['peak_mb']:.0f} MB", file=sys.stderr)
            if not args.keep:
                source.unlink()
    head = ("case", "file", "lines", "written [s]", "convert [s]", "peak [MB]", "rows written")
    print(f"code tree: {args.repo}")
    print(" | ".join(head))
    print(" | ".join("---" for _ in head))
    for row in rows:
        print(" | ".join(row))
    return 0


if __name__ == "__main__":
    sys.exit(main())
