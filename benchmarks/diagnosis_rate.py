"""How often the diagnosis names a hidden effect: ``python3 benchmarks/diagnosis_rate.py [--seeds N]``.

For each catalogue effect (and for none), N logs from measurements/truth_tractor.py with seeds 1000.. are
diagnosed; a log counts as right when the verdict names the hidden effect and (for an effect) its
headline parameter is within the tolerance stated in diagnosis.hidden_effects.recovered. Prints one table.
Stress: ``--scale-truth sigma_f=2`` moves the truth model further from the baseline;
``--effects none side_slope`` picks the hidden effects.
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def score(run: dict) -> tuple:
    """(effect, named, named with the parameter in tolerance, held-out gain, verdict)."""
    from diagnosis.hidden_effects import recovered

    effect, res = run["effect"], run["result"]
    named = res["verdict"] == effect
    within = True
    if named and effect != "none":
        est, true, tol = recovered(effect, run["truth"], res["findings"][0]["params"])
        within = abs(est - true) <= tol
    gain = res["findings"][0]["gain"] if named and effect != "none" else float("nan")
    return effect, named, named and within, gain, res["verdict"]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--scale-truth", action="append", default=[], metavar="PARAM=FACTOR",
                    help="stress: multiply a truth-model parameter (m, I, l_f, l_r, C_f, C_r, sigma_f)")
    ap.add_argument("--effects", nargs="+", default=None, help="only these hidden effects ('none' for none)")
    args = ap.parse_args()
    from diagnosis.hidden_effects import EFFECTS, diagnose_many

    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        scale = {k: float(v) for k, v in (item.split("=") for item in args.scale_truth)}
        effects = [None if e == "none" else e for e in args.effects] if args.effects else [None, *EFFECTS]
        cases = [(e, 1000 + s, folder, scale) for e in effects for s in range(args.seeds)]
        rows = [score(run) for run in diagnose_many(cases, args.workers)]
    print(f"{'hidden effect':28s} {'named':>7s} {'+param ok':>10s} {'median gain':>12s}  wrong verdicts")
    total_named = total_ok = 0
    for eff in ("none", *EFFECTS):
        r = [x for x in rows if x[0] == eff]
        if not r:
            continue
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
