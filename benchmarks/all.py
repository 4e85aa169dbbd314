"""Every benchmark in one run, one table (ratios measured in the same run: the machine is shared).

    python benchmarks/all.py [--quick]

--quick shortens the sweep points to 40 s simulated and the MPC runs (for a smoke test).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import closed_loop  # noqa: E402
import diagnosis_rate  # noqa: E402
import fmu_step  # noqa: E402
import identify_time  # noqa: E402
import mpc_step  # noqa: E402
import sweep  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    rows: list[tuple[str, str, str, str]] = []      # (item, measurement, value, target: met?)

    mpc = mpc_step.measure(500 if args.quick else 2000, 50 if args.quick else 200)
    med = {name: float(np.median(t)) for name, t in mpc["rows"].items()}
    p99 = {name: float(np.percentile(t, 99)) for name, t in mpc["rows"].items()}
    ours, bare = med["ours: full MPC step (daqp)"], med["bare QP: daqp"]
    for name in mpc["rows"]:
        rows.append(("MPC step", f"{name}: median / p99", f"{med[name] * 1e6:.1f} / {p99[name] * 1e6:.1f} us", ""))
    rows.append(("MPC step", "ours / bare daqp (median)", f"{ours / bare:.2f}x",
                 f"<= 1.5x: {'met' if ours / bare <= 1.5 else 'NOT met'}"))
    rows.append(("MPC step", "ours / bare proxsuite (median)", f"{ours / med['bare QP: proxsuite']:.2f}x", ""))
    if "do-mpc make_step (IPOPT)" in med:
        ratio = med["do-mpc make_step (IPOPT)"] / ours
        rows.append(("MPC step", "do-mpc / ours (median)", f"{ratio:.0f}x",
                     f">= 250x: {'met' if ratio >= 250 else 'NOT met'}"))
    else:
        rows.append(("MPC step", "do-mpc", mpc["do_mpc"], ""))

    fs = fmu_step.measure(20.0 if args.quick else 60.0)
    fmed = {name: float(np.median(t)) for name, t in fs["rows"].items()}
    c_step = fmed["FMU C step alone (C harness)"]
    for name, t in fs["rows"].items():
        rows.append(("controller step", f"{name}: median", f"{fmed[name] * 1e6:.2f} us",
                     f"{fmed[name] / c_step:.0f}x the C step"))
    rows.append(("controller step", "bare daqp QP from Python / whole C controller step",
                 f"{bare / c_step:.0f}x", ""))

    cl = closed_loop.measure()
    speed = cl["sim_time"] / cl["warm"]
    share = cl["orchestrator"] / cl["warm"]
    rows.append(("closed loop", f"figure-8 {cl['sim_time']:.0f} s, cold (first run)", f"{cl['sim_time'] / cl['cold']:.0f}x real time", ""))
    rows.append(("closed loop", f"figure-8, warm (median of {cl['repeat']})", f"{speed:.0f}x real time",
                 f">= 200x: {'met' if speed >= 200 else 'NOT met'}"))
    for name, sec in sorted(cl["spent"].items(), key=lambda kv: -kv[1])[:4]:
        rows.append(("closed loop", f"share: {name}", f"{100 * sec / cl['warm']:.1f}%", ""))
    rows.append(("closed loop", "share: orchestrator", f"{100 * share:.1f}%",
                 f"< 20%: {'met' if share < 0.2 else 'NOT met'}"))

    ident = identify_time.measure(repeat=1 if args.quick else 3)
    rows.append(("identification", "identify studies/identification.toml (fresh process)",
                 f"{ident['median']:.1f} s", f"< 10 s: {'met' if ident['median'] < 10 else 'NOT met'}"))

    cases = ["none", "actuator_delay+steering_offset+antenna_lever_arm"] + ([] if args.quick else ["wheel_slip"])
    for case, seconds in diagnosis_rate.timing(420.0, cases):
        rows.append(("diagnosis", f"diagnose a 420 s log ({case}), plots included", f"{seconds:.1f} s",
                     f"<= 15 s: {'met' if seconds <= 15 else 'NOT met'}"))

    sw = sweep.measure(stop_time=40.0 if args.quick else None)
    (_, n, _, r1), (_, _, _, r2) = sw["rows"]
    rows.append(("sweep", f"{n} points x {sw['stop_time']:.0f} s, 1 worker", f"{r1:.3f} points/s", ""))
    rows.append(("sweep", f"{n} points x {sw['stop_time']:.0f} s, 2 workers", f"{r2:.3f} points/s",
                 f"scaling x{r2 / r1:.2f} on 2 cores"))

    widths = [max(len(r[i]) for r in rows) for i in range(4)]
    header = ("item", "measurement", "value", "target")
    widths = [max(w, len(h)) for w, h in zip(widths, header)]
    line = "  ".join(f"{{:<{w}}}" for w in widths)
    print(line.format(*header))
    print("  ".join("-" * w for w in widths))
    for r in rows:
        print(line.format(*r))


if __name__ == "__main__":
    main()
