"""How often the diagnosis names a hidden effect: ``python3 benchmarks/diagnosis_rate.py [--seeds N]``.

For each catalogue effect (and for none), N logs from tests/field_truth.py with seeds 1000.. are
diagnosed; a log counts as right when the verdict names the hidden effect and (for an effect) its
headline parameter is within the tolerance stated in field_truth.recovered. Prints one table.
"""
from __future__ import annotations

import argparse
import multiprocessing
import os
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))


def one(case):
    from diagnosis.pipeline import diagnose
    from tests.field_truth import make_log, recovered

    effect, seed, folder = case
    frame, truth = make_log(seed, effect)
    log = Path(folder) / f"{effect}_{seed}.parquet"
    frame.to_parquet(log)
    res = diagnose(log, Path(folder) / f"{effect}_{seed}", plots=False)
    named = res["verdict"] == (effect or "none")
    within = True
    if named and effect:
        est, true, tol = recovered(effect, truth, res["findings"][0]["params"])
        within = abs(est - true) <= tol
    gain = res["findings"][0]["gain"] if named and effect else float("nan")
    return effect or "none", named, named and within, gain, res["verdict"]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    args = ap.parse_args()
    from tests.field_truth import EFFECTS

    os.environ.update({k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")})
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        cases = [(e, 1000 + s, folder) for e in (None, *EFFECTS) for s in range(args.seeds)]
        with ProcessPoolExecutor(args.workers, mp_context=multiprocessing.get_context("spawn")) as pool:
            rows = list(pool.map(one, cases))
    print(f"{'hidden effect':28s} {'named':>7s} {'+param ok':>10s} {'median gain':>12s}  wrong verdicts")
    total_named = total_ok = 0
    for eff in ("none", *EFFECTS):
        r = [x for x in rows if x[0] == eff]
        named, ok = sum(x[1] for x in r), sum(x[2] for x in r)
        total_named, total_ok = total_named + named, total_ok + ok
        gains = sorted(x[3] for x in r if x[3] == x[3])
        med = f"{100 * gains[len(gains) // 2]:.0f}%" if gains else "-"
        wrong = ", ".join(x[4] for x in r if not x[1])
        print(f"{eff:28s} {named:>3d}/{len(r):<3d} {ok:>6d}/{len(r):<3d} {med:>12s}  {wrong}")
    n = len(rows)
    print(f"{'all':28s} {total_named:>3d}/{n:<3d} {total_ok:>6d}/{n:<3d}   rate {100 * total_ok / n:.1f}% "
          f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
