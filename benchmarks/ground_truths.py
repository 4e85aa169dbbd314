"""Guidance on real ground: the figures of docs/slopes-and-outages.md, from commands anyone can rerun.

    python3 benchmarks/ground_truths.py [--quick] [--only slope|shapes|outage|bridging|iso] [--figure docs/img/outage_drift.png]

1. Side slope: the tractor's and the implement's cross-track error on the swaths of a real parcel
   across a 10 deg side slope with RTK noise, with and without terrain compensation and the crab
   estimate, for antenna heights of 2 to 4 m and for roll errors beyond the assumed IMU's.
2. GNSS outages: five minutes without RTK on a 1334 m swath of a real partfield at 2 m/s, with no
   GNSS at all (IMU + odometry), RTK float or DGPS: the estimate's drift after 1 and 5 minutes and
   the time its own cross-track uncertainty passes the watchdog's 10 cm, beside the vendor's
   published figures for a correction outage (Trimble xFill).
   With the receiver bridging the lost corrections (gps.outages mode "bridging") too; and the
   receiver's own error after 1, 5 and 20 minutes in each mode (a Monte Carlo over receivers, the
   sensor alone) beside its model and the vendors' figures.
3. ISO 12188-2-style figures: pass-to-pass of adjacent passes driven 15 minutes apart and right
   after each other, line acquisition after each turn, the cross-track error along the whole route by
   interpolation, and the repeatability of the same line driven on two runs (two seeds).

Each figure is the median over seeds (--quick: one seed) with the range in brackets. Real fields
from ../shared/realdata when it is there, else the copies in tests/data.
"""
from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")       # scipy's small expm is slow with threads on a shared machine

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from agrobot.orchestrator.runner import run_study  # noqa: E402
from agrobot.orchestrator.study import Study  # noqa: E402

SHARED = ROOT.parent / "shared" / "realdata"
REAL = SHARED if SHARED.exists() else ROOT / "tests" / "data"
PARCEL = REAL / "fields2cover_data" / "test.json"
PARTFIELDS = REAL / "isoxml_dev4ag_timelogs" / "PARTFIELDS_TASKDATA.XML"
SLOPE = ("tractor.slope_angle=10 deg", "tractor.slope_downhill_heading=-90 deg")
SECTION = (f"field.path={PARCEL}", "field.max_swaths=3", "field.headland_work=0")
LONG_LINE = (f"field.path={PARTFIELDS}", "field.name=NO_Prag_Komplex", "field.max_swaths=1", "field.headland_work=0")
OUTAGE = (120.0, 420.0)                                  # s: five minutes, after two minutes of RTK on the swath
VENDOR = "Trimble xFill (TMX-2050 manual): 1-5 cm after 1-5 min, 5-9 cm after 6-10 min, 10-15 cm after 11-20 min"


def shown(path: Path) -> str:
    """A path as a user at the repository's root types it."""
    return str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else str(path)


def run(study: str, overrides, seed: int):
    return run_study(Study.load(ROOT / "studies" / study, [*overrides, f"study.seed={seed}"]), None, plots=False)


def spread(values, scale: float = 100.0, unit: str = "cm") -> str:
    v = np.asarray(values, float) * scale
    if len(v) == 1:
        return f"{v[0]:.1f} {unit}"
    return f"{np.median(v):.1f} [{v.min():.1f}-{v.max():.1f}] {unit}"


def slope_table(seeds: list[int]) -> None:
    rows = [
        ("compensation and crab estimate (the default)", ()),
        ("  crab estimate off", ("ekf.crab_estimate=0",)),
        ("  terrain compensation off", ("ekf.terrain_compensation=0",)),
        ("  both off", ("ekf.terrain_compensation=0", "ekf.crab_estimate=0")),
        ("  passive implement (no side-shift)", ("implement.side_shift_gain=0", "implement.side_shift_integral=0")),
        ("  antenna 2 m", ("tractor.antenna_height=2.0", "ekf.antenna_height=2.0")),
        ("  antenna 4 m", ("tractor.antenna_height=4.0", "ekf.antenna_height=4.0")),
        ("  antenna 4 m, roll offset 0.3 deg (1 sigma)", ("tractor.antenna_height=4.0", "ekf.antenna_height=4.0",
                                                         "imu.attitude_bias_std=0.3 deg")),
        ("flat ground, the default", None),
    ]
    print("1. Side slope of 10 deg (downhill across the swaths), RTK noise 2 cm, antenna 2.5 m, "
          "3 swaths of the F2C test parcel")
    head = f"{'estimator':<48}{'tractor P95':>22}{'implement P95':>22}{'tractor RMS':>22}"
    print(head + "\n" + "-" * len(head))
    for label, extra in rows:
        over = SECTION + (SLOPE + extra if extra is not None else ())
        ms = [run("field_coverage.toml", over, seed).metrics for seed in seeds]
        print(f"{label:<48}{spread([m['tractor_xte_p95_m'] for m in ms]):>22}"
              f"{spread([m['implement_xte_p95_m'] for m in ms]):>22}{spread([m['tractor_xte_rms_m'] for m in ms]):>22}",
              flush=True)
    print("command: python -m agrobot run studies/field_coverage.toml --out OUT --set field.max_swaths=3 "
          "--set field.headland_work=0 --set \"tractor.slope_angle=10 deg\" --set \"tractor.slope_downhill_heading=-90 deg\""
          " [--set ekf.terrain_compensation=0] [--set ekf.crab_estimate=0] [--set study.seed=N]\n")


def shapes_table(seeds: list[int]) -> None:
    """The slope on other field shapes, the side-shift's integral before (0.5 1/s) and now: a field with
    a bay (ISOXML euDZYo7, 4 swaths) and a generated trapezoid (tests/test_slope_implement.py, 3 swaths)."""
    import tempfile

    from tests.test_slope_implement import trapezoid

    folder = Path(tempfile.mkdtemp())
    bay = (f"field.path={REAL / 'isoxml_dev4ag_timelogs' / 'TASKDATA.XML'}", "field.name=euDZYo7", "field.max_swaths=4")
    trap = (f"field.path={trapezoid(folder / 'trapezoid.geojson')}", "field.max_swaths=3")
    print("1b. Side slope of 10 deg on other field shapes: swath P95 (turns excluded)")
    head = f"{'field, side-shift k_i':<48}{'tractor P95':>22}{'implement P95':>22}"
    print(head + "\n" + "-" * len(head))
    for name, field in (("euDZYo7 (a bay), 4 swaths", bay), ("trapezoid, 3 swaths", trap)):
        for ki in (0.5, 2.0):
            over = (*field, "field.headland_work=0", *SLOPE, f"implement.side_shift_integral={ki}")
            ms = [run("field_coverage.toml", over, seed).metrics for seed in seeds]
            print(f"{name + f', k_i {ki:g} 1/s':<48}{spread([m['tractor_xte_swaths_p95_m'] for m in ms]):>22}"
                  f"{spread([m['implement_xte_swaths_p95_m'] for m in ms]):>22}", flush=True)
    print("command: python -m agrobot run studies/field_coverage.toml --out OUT --set field.path=FIELD [--set field.name=NAME] "
          "--set field.max_swaths=N --set field.headland_work=0 --set \"tractor.slope_angle=10 deg\" "
          "--set \"tractor.slope_downhill_heading=-90 deg\" [--set implement.side_shift_integral=0.5] [--set study.seed=N]\n")


def outage_runs(quality, seeds: list[int]):
    mode = f'"{quality}"' if isinstance(quality, str) else quality
    window = f"gps.outages=[[{OUTAGE[0]}, {OUTAGE[1]}, {mode}]]"
    return [run("field_coverage.toml", (*LONG_LINE, window, "watchdog.max_position_std=inf"), seed) for seed in seeds]


def at_outage(frame, after: float) -> tuple[float, float, float]:
    """(horizontal drift, across drift, the estimator's cross-track std) `after` seconds into the outage."""
    t = frame["t"].to_numpy()
    i = int(np.searchsorted(t, OUTAGE[0] + after - 1e-9))
    dx = frame["ekf.x_cg"].iloc[i] - frame["tractor.x_cg"].iloc[i]
    dy = frame["ekf.y_cg"].iloc[i] - frame["tractor.y_cg"].iloc[i]
    psi = frame["tractor.heading"].iloc[i]
    return math.hypot(dx, dy), abs(-math.sin(psi) * dx + math.cos(psi) * dy), float(frame["ekf.cross_track_std"].iloc[i])


RECEIVER_MODES = ((0, "no GNSS (IMU + odometry)"), (5, "RTK float (0.3 m)"), (2, "DGPS (0.85 m)"),
                  ("bridging", "bridging (xFill-like)"))
VENDORS = {"bridging": ("Trimble xFill (TMX-2050): 1-5 cm (1-5 min), 10-15 cm (11-20 min); NovAtel RTK ASSIST: "
                        "~4 cm RMS for up to 20 min; u-blox F9P: a few cm per minute for up to 60 s (default)"),
           5: "none quoted", 2: "u-blox ZED-F9P: SBAS 1.0 m CEP", 0: "dead reckoning: not a receiver figure"}


def receiver_table(draws: int) -> None:
    """The receiver's own horizontal error after 1, 5 and 20 minutes of each mode: RMS over ``draws``
    receivers (gps_sensor alone, 2 cm white noise, 1 s steps), beside the mode's model."""
    from agrobot.components.gps_sensor import GPSSensor, bridging_error
    from agrobot.components.models.sensor_grades import FIX_ERROR_STD

    ages, white = (60.0, 300.0, 1200.0), 0.02
    print(f"2b. The receiver's horizontal error (RMS over {draws} receivers) after 1, 5 and 20 min of each mode, "
          "beside its model")
    head = f"{'mode':<26}" + "".join(f"{f'{a / 60:.0f} min: sim / model':>24}" for a in ages) + "  vendors"
    print(head + "\n" + "-" * len(head))
    for mode, label in RECEIVER_MODES:
        errors = {a: [] for a in ages}
        for seed in range(draws):
            g = GPSSensor("gps", {"position_noise_std": white, "outages": [[0.0, 1500.0, mode]]},
                          rng=np.random.default_rng(seed))
            g.initialize(0.0, 1.0)
            for k in range(int(max(ages)) + 1):
                g.step(float(k), 1.0)
                if float(k) in errors and g.y["fix_valid"] > 0.5:
                    errors[float(k)].append(math.hypot(g.y["x"], g.y["y"]))
        cells = []
        for a in ages:
            if mode == 0:
                cells.append("no position")
                continue
            model = math.hypot(math.sqrt(2) * white, float(bridging_error(a)) if mode == "bridging"
                               else math.sqrt(2) * FIX_ERROR_STD[mode])
            sim = math.sqrt(np.mean(np.square(errors[a])))
            cells.append(f"{100 * sim:.1f} / {100 * model:.1f} cm")
        print(f"{label:<26}" + "".join(f"{c:>24}" for c in cells) + f"  {VENDORS[mode]}", flush=True)
    print("model: bridging sqrt(2 sw^2 + (s0 + r a)^2), s0 = 0.81 cm, r = 0.758 cm/min (the line through xFill's "
          "table); float, DGPS sqrt(2 sw^2 + 2 sq^2); sw = 2 cm white per axis\n")


def outage_table(seeds: list[int], figure: Path | None, modes=RECEIVER_MODES) -> None:
    print(f"2. GNSS outage of {OUTAGE[1] - OUTAGE[0]:.0f} s at 2 m/s on a 1334 m swath (PARTFIELDS NO_Prag_Komplex), "
          "flat, antenna 2.5 m; drift = estimated CG - true CG")
    head = (f"{'receiver in the outage':<30}{'after 1 min: drift':>24}{'across':>22}{'after 5 min: drift':>24}"
            f"{'across':>22}{'std > 10 cm after':>22}")
    print(head + "\n" + "-" * len(head))
    curves = {}
    for quality, label in modes:
        results = outage_runs(quality, seeds)
        one = [at_outage(r.frame, 60.0) for r in results]
        five = [at_outage(r.frame, OUTAGE[1] - OUTAGE[0] - 0.05) for r in results]
        stop = []
        for r in results:
            f = r.frame
            late = f.loc[(f["t"] >= OUTAGE[0]) & (f["ekf.cross_track_std"] > 0.10), "t"]
            stop.append(float(late.iloc[0]) - OUTAGE[0] if len(late) else math.nan)
        stop_text = spread(stop, 1.0, "s") if np.isfinite(stop).all() else "never"
        print(f"{label:<30}{spread([o[0] for o in one]):>24}{spread([o[1] for o in one]):>22}"
              f"{spread([o[0] for o in five]):>24}{spread([o[1] for o in five]):>22}{stop_text:>22}", flush=True)
        f = results[0].frame
        w = (f["t"] >= OUTAGE[0] - 20) & (f["t"] <= OUTAGE[1] + 20)
        psi = f.loc[w, "tractor.heading"].to_numpy()
        dx = (f.loc[w, "ekf.x_cg"] - f.loc[w, "tractor.x_cg"]).to_numpy()
        dy = (f.loc[w, "ekf.y_cg"] - f.loc[w, "tractor.y_cg"]).to_numpy()
        curves[label] = (f.loc[w, "t"].to_numpy() - OUTAGE[0], -np.sin(psi) * dx + np.cos(psi) * dy,
                         f.loc[w, "ekf.cross_track_std"].to_numpy())
    print(f"vendor: {VENDOR}: satellite-delivered corrections while GNSS is still tracked, not dead reckoning")
    print(f"command: python -m agrobot run studies/field_coverage.toml --out OUT --set field.path={shown(PARTFIELDS)} "
          f"--set field.name=NO_Prag_Komplex --set field.max_swaths=1 --set field.headland_work=0 "
          f"--set \"gps.outages=[[{OUTAGE[0]:.0f}, {OUTAGE[1]:.0f}, Q]]\" --set watchdog.max_position_std=inf\n")
    if figure is not None:
        plot(curves, figure)


def plot(curves, figure: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(14, 4), sharex=True)
    for ax, (label, (t, across, std)) in zip(axes, curves.items()):
        ax.fill_between(t, -300 * std, 300 * std, color="tab:blue", alpha=0.15, label="the estimator's own 3 sigma "
                        "(clipped)")
        ax.plot(t, 100 * across, color="tab:red", lw=1, label="drift across the heading (estimate - truth)")
        ax.axvspan(0, OUTAGE[1] - OUTAGE[0], color="0.9", zorder=0, label="outage")
        ax.axhline(10, color="k", ls=":", lw=1)
        ax.axhline(-10, color="k", ls=":", lw=1, label="10 cm: the watchdog's bound on the 1 sigma")
        ax.set(title=label, xlabel="time since the outage began [s]", ylabel="cross-track [cm]")
        lim = max(15.0, 2.0 * 100 * float(np.max(np.abs(across))))
        ax.set_ylim(-lim, lim)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7, loc="lower left")
    fig.suptitle("5 minutes without RTK at 2 m/s: the estimate's drift and its own uncertainty (one seed)")
    fig.tight_layout()
    figure.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(figure, dpi=110)
    plt.close(fig)
    print(f"figure: {figure}\n")


def iso_table(seeds: list[int]) -> None:
    from agrobot.analysis.field_tracks import repeatability

    print("3. ISO 12188-2-style figures (studies/field_line_test.toml: the F2C test parcel's first two swaths, "
          "both receivers' RTK error 1.5 cm white + 1.3 cm Gauss-Markov over 5 min)")
    head = f"{'figure':<58}{'value':>24}"
    print(head + "\n" + "-" * len(head))
    for label, pause in (("passes 15 min apart", 785.0), ("passes back to back", 0.0)):
        ms = [run("field_line_test.toml", (f"operator.pauses=[[1, {pause}]]",), seed).metrics for seed in seeds]
        interval = f"   (interval {np.median([m['pass_to_pass_interval_s'] for m in ms]):.0f} s)"
        print(f"{'pass-to-pass P95, tractor CG, ' + label:<58}{spread([m['tractor_pass_to_pass_p95_m'] for m in ms]):>24}"
              f"{interval}")
        print(f"{'pass-to-pass P95, implement, ' + label:<58}{spread([m['pass_to_pass_p95_m'] for m in ms]):>24}"
              f"{interval}", flush=True)
    ms = [run("field_coverage.toml", SECTION, seed).metrics for seed in seeds]
    print(f"{'line acquisition P95 after a turn, distance':<58}{spread([m['line_acquisition_p95_m'] for m in ms], 1.0, 'm'):>24}")
    print(f"{'line acquisition P95 after a turn, time':<58}{spread([m['line_acquisition_p95_s'] for m in ms], 1.0, 's'):>24}")
    print(f"{'tractor cross-track P95 along the whole route (turns too)':<58}"
          f"{spread([m['route_xte_p95_m'] for m in ms]):>24}")
    study = Study.load(ROOT / "studies" / "field_line_test.toml", ["operator.pauses=[[1, 0.0]]"])
    pairs = list(zip(seeds, seeds[1:])) or [(seeds[0], seeds[0] + 1)]
    p95 = []
    for a, b in pairs:
        runs = [(run("field_line_test.toml", ("operator.pauses=[[1, 0.0]]",), s).frame, study) for s in (a, b)]
        p95.append(float(np.percentile(np.abs(repeatability(*runs, swath=0)), 95)))
    print(f"{'repeatability P95: the first swath on two runs (seeds)':<58}{spread(p95):>24}")
    print("command: python -m agrobot run studies/field_line_test.toml --out OUT  (metrics.json: "
          "tractor_pass_to_pass_p95_m, pass_to_pass_p95_m, pass_to_pass_interval_s, line_acquisition_p95_m, line_acquisition_p95_s, route_xte_p95_m)\n")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true", help="one seed")
    parser.add_argument("--figure", type=Path, default=None, help="write the outage figure (PNG) there")
    parser.add_argument("--only", choices=("slope", "shapes", "outage", "bridging", "iso"), default=None)
    args = parser.parse_args()
    seeds = [27] if args.quick else [27, 28, 29]
    t0 = time.perf_counter()
    if args.only in (None, "slope"):
        slope_table(seeds)
    if args.only in (None, "shapes"):
        shapes_table(seeds)
    if args.only in (None, "outage"):
        outage_table(seeds, args.figure)
    if args.only in (None, "outage", "bridging"):
        receiver_table(60 if args.quick else 200)
    if args.only == "bridging":
        outage_table(seeds, None, RECEIVER_MODES[-1:])
    if args.only in (None, "iso"):
        iso_table(seeds)
    print(f"(wall time {time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
