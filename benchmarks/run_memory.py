"""Peak memory of ``run`` against the length of the run: the signals are streamed to disk while the
run goes and the analysis reads back only the columns it uses, so the peak should grow far
slower than the signal table (rows x columns x 8 bytes).

    python benchmarks/run_memory.py                        # figure-8 at 160, 1600 and 16000 s
    python benchmarks/run_memory.py --field                # and the field coverage run (whole route)
    python benchmarks/run_memory.py --tree /path/to/checkout   # the same commands with another checkout's code

Each case is one ``python -m agrobot run`` in its own process; its peak resident set size is
the kernel's (``wait4``'s ru_maxrss), the CPU time user + sys. "simulation" is the same run without
its analysis (``--set study.analysis=""``): what the run itself holds; "with analysis" adds the
columns the analysis reads back and its arrays.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def peak_run(tree: Path, study: str, overrides: list[str], out: Path) -> dict:
    env = {**os.environ, "PYTHONPATH": str(tree), "OPENBLAS_NUM_THREADS": "1"}
    args = [sys.executable, "-m", "agrobot", "run", study, "--out", str(out), "--overwrite", "--no-plots"]
    for item in overrides:
        args += ["--set", item]
    start = time.perf_counter()
    proc = subprocess.Popen(args, cwd=tree, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    err = proc.stderr.read()
    proc.stderr.close()
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"{' '.join(args)} failed:\n{err}")
    import pyarrow.parquet as pq

    meta = pq.ParquetFile(out / "signals.parquet").metadata
    metrics = json.loads((out / "metrics.json").read_text())
    return {"rows": meta.num_rows, "columns": meta.num_columns, "table_mb": meta.num_rows * meta.num_columns * 8 / 1e6,
            "peak_mb": usage.ru_maxrss / 1024, "cpu_s": usage.ru_utime + usage.ru_stime, "wall_s": wall,
            "sim_s": (metrics.get("ended_by") or {}).get("t", metrics["sim_time_s"])}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tree", type=Path, default=ROOT, help="the checkout whose code runs (default: this one)")
    parser.add_argument("--field", action="store_true", help="add the field coverage run (about 9400 s simulated)")
    parser.add_argument("--lengths", type=float, nargs="+", default=[160.0, 1600.0, 16000.0],
                        help="figure-8 stop times [s]")
    args = parser.parse_args()
    cases = [("studies/figure8.toml", [f"study.stop_time={t:g}"]) for t in args.lengths]
    if args.field:
        cases.append(("studies/field_coverage.toml", []))
    print(f"code: {args.tree}")
    print(f"{'':<54}{'peak RSS [MB]':^28}")
    print(f"{'study':<16}{'simulated [s]':>14}{'rows':>10}{'table [MB]':>12}{'simulation':>14}{'with analysis':>14}"
          f"{'CPU [s]':>9}{'wall [s]':>10}")
    with tempfile.TemporaryDirectory(prefix="run_memory.") as tmp:
        for i, (study, overrides) in enumerate(cases):
            bare = peak_run(args.tree, study, overrides + ['study.analysis=""'], Path(tmp) / f"bare{i}")
            r = peak_run(args.tree, study, overrides, Path(tmp) / f"out{i}")
            print(f"{Path(study).stem:<16}{r['sim_s']:>14.0f}{r['rows']:>10}{r['table_mb']:>12.0f}{bare['peak_mb']:>14.0f}"
                  f"{r['peak_mb']:>14.0f}{r['cpu_s']:>9.1f}{r['wall_s']:>10.1f}", flush=True)


if __name__ == "__main__":
    main()
