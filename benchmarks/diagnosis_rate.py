"""How often the diagnosis finds what is hidden: ``python3 benchmarks/diagnosis_rate.py [--seeds N]``.

Logs from harness/truth_tractor.py with seeds 1000.. (never used while tuning), diagnosed
without being told what is in them. Three groups:

- singles: each catalogue effect alone, and none;
- combinations: two and three catalogue effects at once (``--combinations``);
- unlisted: faults of the truth's unlisted group (truth_tractor.UNLISTED), alone and with a catalogue
  effect; the gyro scale factor and wheel slip are now named (gyro_scale, speed_scale:
  hidden_effects.NAMED), the others must be ``unexplained``;
- later effects: a localisation output at another point on a lagging clock, a steering ratio
  varying with the angle (truth_tractor.LATER);
- healthy: no fault, but a truth that differs from the baseline the way a user would call healthy
  (truth_tractor.HEALTHY: the paper's servo steering on a 1-deg potentiometer, relaxation lengths,
  sensor noise levels, one speed, field driving). Any effect or ``unexplained`` is a false alarm.

A log counts as right when the set of effects found is exactly the hidden set (hidden_effects.expected_ids:
an unlisted fault counts as ``unexplained``, an antenna lever arm with a latency as one position_reference) and every catalogued effect's headline parameter is within the tolerance
of harness.hidden_effects.recovered. Prints one table, then the time per diagnosis of a 420 s log
(the issue's budget is 15 s). ``--scale-truth sigma_f=2`` moves the truth further from the baseline;
``--effects none side_slope a+b`` picks the hidden effects; ``--duration`` sets the log length;
``--identify`` which logs identify the vehicle first, as ``diagnose`` does by default (tyre: those
hiding tyre saturation, the default; all; none).

Vehicle classes (``--classes tractor car small_ackermann``, or ``--quick``: one seed of 120 s logs, a
few minutes on two free cores; ``--quick --classes car --seeds 8``: one class over eight seeds): the paper tractor, a passenger car and a small Ackermann machine
(wheelbase 1.27 m, 0.3-1.5 m/s, a dual-antenna heading and no gyro; harness.diagnosis_classes), each
judged against its own baseline study (the small machine's: harness.vehicle_classes.study),
clean and with each steering-map effect hidden (gain error, left/right asymmetry, offset, nonlinear
map; without --quick also an actuator delay, a GPS latency and an offset with a gyro bias; harness.diagnosis_classes names the ids a right diagnosis gives and the parameters' tolerances).
Per class: detection (the exact set named, each headline parameter within its tolerance) and false
alarms (a clean log with any effect);
a class the code cannot yet judge (a refusal, a failure) is printed as a row with its error.
``--compare-screen`` diagnoses the class table's logs twice in one run, the diagnosis's pair screen
off and on (diagnosis.screen), prints both tables and the logs whose diagnosis the screen changes.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))          # the test harness (harness/), beside the package


COMBINATIONS = ("actuator_delay+gps_latency", "steering_offset+yaw_rate_bias", "steering_offset+side_slope",
                "steering_deadband+steering_rate_limit", "antenna_lever_arm+gps_latency",
                "speed_dependent_cornering+steering_offset", "actuator_delay+steering_offset+antenna_lever_arm",
                "steering_rate_limit+side_slope+yaw_rate_bias", "steering_deadband+gps_latency+side_slope")


def unlisted_cases() -> tuple[str, ...]:
    from harness.truth_tractor import UNLISTED

    return UNLISTED + ("wheel_slip+actuator_delay", "tyre_saturation+gps_latency",
                       "steering_sensor_gain+yaw_rate_bias", "gyro_scale_factor+steering_deadband")


def score(run: dict) -> tuple:
    """(case, exact set found, exact set with every parameter in tolerance, found set)."""
    from harness.hidden_effects import expected_ids, recovered

    res = run["result"]
    if run.get("healthy"):
        run = {**run, "effect": f"healthy:{run['healthy']}"}
    found = {e["id"] for e in res["effects"]}
    exact = found == expected_ids(run["truth"])
    within = exact and all(abs(est - true) <= tol for e in res["effects"] if e["id"] != "unexplained"
                           for est, true, tol in [recovered(e["id"], run["truth"], e["parameters"])])
    return run["effect"], exact, within, "+".join(sorted(found)) or "none"


def timing(duration: float, cases: list[str]) -> list[tuple[str, float]]:
    """Seconds per diagnosis (with plots) of one log of ``duration`` s per case, in this process."""
    from agrobot.diagnosis.pipeline import diagnose
    from harness.truth_tractor import make_log

    out = []
    with tempfile.TemporaryDirectory() as folder:
        for case in cases:
            frame, _ = make_log(1000, case, duration=duration)
            frame.to_parquet(Path(folder) / "log.parquet")
            t0 = time.perf_counter()
            diagnose(Path(folder) / "log.parquet", Path(folder) / "out")
            out.append((case, time.perf_counter() - t0))
    return out


def class_table(vehicles: list[str], seeds: int, duration: float, workers: int, effects: tuple,
                first_seed: int = 1000, screens: tuple[bool, ...] = (True,)) -> None:
    """Detection and false-alarm rates per vehicle class over the steering-map effects and clean logs
    (seeds ``first_seed``, ``first_seed`` + 1, ...); one table per entry of ``screens`` (the
    diagnosis with its pair screen on or off, diagnosis.screen), the logs diagnosed in one run."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    from harness.diagnosis_classes import MAP_EFFECTS, diagnose_class_case

    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        cases = [(e, first_seed + s, folder, v, duration, on) for on in screens for v in vehicles
                 for e in ("none", *MAP_EFFECTS, *effects)
                 for s in range(seeds) if not (v == "small_ackermann" and "yaw_rate_bias" in e)]   # no gyro
        with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn")) as pool:
            rows = list(pool.map(diagnose_class_case, cases))
    wall = time.perf_counter() - t0
    for on in screens:
        mine = [r for r in rows if r["screen"] == on]
        label = "" if screens == (True,) else f"screen {'on' if on else 'off (--no-screen)'}, " \
            f"{sum(r['seconds'] for r in mine):.0f} s of diagnosis; "
        _class_rows(mine, vehicles, seeds, duration, first_seed, wall, label)
    if len(screens) > 1:
        _screen_changes(rows)


def _screen_changes(rows: list[dict]) -> None:
    """The logs whose diagnosis differs with the screen on and off (the effects named, their tolerance)."""
    by_log: dict[tuple, dict] = {}
    for r in rows:
        by_log.setdefault((r["vehicle"], r["effect"], r["seed"]), {})[r["screen"]] = r
    changed = [(k, pair) for k, pair in by_log.items()
               if (pair[True]["found"], pair[True].get("in_tolerance")) != (pair[False]["found"],
                                                                             pair[False].get("in_tolerance"))]
    print(f"\nscreen on against off: {len(changed)} of {len(by_log)} logs diagnosed differently")
    for (vehicle, effect, seed), pair in changed:
        print(f"  {vehicle} {effect} {seed}: off {pair[False]['found']} on {pair[True]['found']}")


def _class_rows(rows: list[dict], vehicles: list[str], seeds: int, duration: float, first_seed: int, wall: float,
                label: str) -> None:
    print(f"\nvehicle classes ({label}{seeds} seed(s) from {first_seed}, {duration:.0f} s logs, {wall:.0f} s): "
          f"right: the exact set named (harness.diagnosis_classes.MAP_IDS), its parameters within tolerance; clean: any "
          f"effect named is a false alarm")
    print("| vehicle | hidden | right | found instead (or the error) |\n|---|---|---|---|")
    for r in rows:
        right = r["found"] is not None and set(r["found"]) == set(r["expected"]) and r["in_tolerance"]
        r["right"] = right
        what = r["error"] if r["found"] is None else ("+".join(r["found"]) or "none") + (
            f" (not judged: {', '.join(r['not_judged'])})" if r.get("not_judged") else "")
        print(f"| {r['vehicle']} | {r['effect']} | {'yes' if right else 'no'} | {'' if right else what} |")
    print("\n| vehicle | detection | false alarms | failed to run | logs with a stage not judged |\n|---|---|---|---|---|")
    for v in vehicles:
        mine = [r for r in rows if r["vehicle"] == v]
        faulty = [r for r in mine if r["effect"] != "none"]
        clean = [r for r in mine if r["effect"] == "none"]
        alarms = sum(not r["right"] for r in clean)
        print(f"| {v} | {sum(r['right'] for r in faulty)}/{len(faulty)} "
              f"({100 * sum(r['right'] for r in faulty) / max(len(faulty), 1):.0f} %) | {alarms}/{len(clean)} "
              f"({100 * alarms / max(len(clean), 1):.0f} %) | {sum(r['found'] is None for r in mine)} | "
              f"{sum(bool(r.get('not_judged')) for r in mine)} {_skipped(mine)}|")


def _skipped(rows: list[dict]) -> str:
    """The stages not judged and why, as the first log that skipped them says."""
    first = next((r["not_judged"] for r in rows if r.get("not_judged")), [])
    return f"({'; '.join(first)}) " if first else ""


def _rate_table(groups: dict[str, list[str]], rows: list[tuple], duration: float, t0: float) -> None:
    """Each group's cases found exactly and with their parameters, then the false alarms and the detection."""
    print(f"{'hidden':48s} {'exact set':>10s} {'+params ok':>11s}  found instead")
    for group, cases in groups.items():
        print(f"-- {group}")
        g_ok = g_n = 0
        for case in cases:
            r = [x for x in rows if x[0] == case]
            exact, ok = sum(x[1] for x in r), sum(x[2] for x in r)
            g_ok, g_n = g_ok + ok, g_n + len(r)
            wrong = ", ".join(x[3] for x in r if not x[1])
            print(f"{case:48s} {exact:>4d}/{len(r):<5d} {ok:>5d}/{len(r):<5d}  {wrong}")
        print(f"{group + ' total':48s} {'':10s} {g_ok:>5d}/{g_n:<5d}  {100 * g_ok / max(g_n, 1):.0f}%")
    n_ok = sum(x[2] for x in rows)
    print(f"{'all':48s} {'':10s} {n_ok:>5d}/{len(rows):<5d}  {100 * n_ok / len(rows):.1f}% "
          f"({time.perf_counter() - t0:.0f} s, {duration:.0f} s logs)")
    clean = [x for x in rows if x[0] == "none" or x[0].startswith("healthy:")]
    faulty = [x for x in rows if x not in clean]
    if clean:
        alarms = sum(not x[1] for x in clean)
        print(f"{'false alarms (no fault hidden, verdict not none)':48s} {'':10s} {alarms:>5d}/{len(clean):<5d}  "
              f"{100 * alarms / len(clean):.1f}%")
    if faulty:
        found = sum(x[2] for x in faulty)
        print(f"{'detection (a fault hidden, found exactly)':48s} {'':10s} {found:>5d}/{len(faulty):<5d}  "
              f"{100 * found / len(faulty):.1f}%")


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=None, help="seeds per case (3; --quick: 1)")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--duration", type=float, default=240.0, help="log length [s] of the rate table")
    ap.add_argument("--scale-truth", action="append", default=[], metavar="PARAM=FACTOR",
                    help="stress: multiply a truth-model parameter (m, I, l_f, l_r, C_f, C_r, sigma_f)")
    ap.add_argument("--effects", nargs="+", default=None,
                    help="only these hidden cases ('none', an effect, or effects joined by '+')")
    ap.add_argument("--identify", default="tyre", choices=("tyre", "all", "none"),
                    help="which logs are diagnosed as a user's diagnose does, identifying the vehicle on the same log "
                         "first (tyre: those hiding tyre saturation, which identify's fit finds for the diagnosis; "
                         "all: every log, five times slower; none)")
    ap.add_argument("--no-timing", action="store_true", help="skip the 420 s timing table")
    ap.add_argument("--vehicle", default="tractor", choices=("tractor", "car"),
                    help="the truth and its baseline: the paper's tractor (figure8.toml) or a passenger car at "
                         "10-30 m/s (passenger_car.toml)")
    ap.add_argument("--classes", nargs="+", default=None, choices=("tractor", "car", "small_ackermann"),
                    help="the vehicle-class table over the steering-map effects (harness.diagnosis_classes) only")
    ap.add_argument("--first-seed", type=int, default=1000,
                    help="the vehicle-class table's first seed (another than 1000 checks a change on unseen logs)")
    ap.add_argument("--quick", action="store_true",
                    help="the vehicle-class table (of the three classes unless --classes), one seed unless "
                         "--seeds, 120 s logs (a few minutes)")
    ap.add_argument("--compare-screen", action="store_true",
                    help="the vehicle-class table twice in one run, the diagnosis's pair screen off and on "
                         "(diagnosis.screen), and the logs it changes")
    return ap


def main() -> None:
    args = _parser().parse_args()
    if args.quick or args.classes:
        class_table(args.classes or ["tractor", "car", "small_ackermann"], args.seeds or (1 if args.quick else 3),
                    120.0 if args.quick else args.duration, args.workers,
                    () if args.quick else ("actuator_delay", "gps_latency", "steering_offset", "steering_offset+yaw_rate_bias"),
                    args.first_seed, (False, True) if args.compare_screen else (True,))
        return
    from harness.hidden_effects import EFFECTS, diagnose_many

    from harness.truth_tractor import HEALTHY, LATER

    groups = {"healthy": [f"healthy:{h}" for h in HEALTHY], "singles": ["none", *EFFECTS], "later effects": list(LATER),
              "combinations": list(COMBINATIONS), "unlisted": list(unlisted_cases())}
    if args.vehicle == "car":
        # what a car's test drive at 10-30 m/s can show: its steering effects are a twentieth of the
        # tractor's angles (below the catalogue's materiality), and a drive that never turns round
        # cannot tell a steering offset from a side slope
        groups = {"car": ["none", "actuator_delay", "yaw_rate_bias", "gps_latency", "speed_dependent_cornering",
                          "side_slope", "antenna_lever_arm", "actuator_delay+gps_latency",
                          "antenna_lever_arm+gps_latency", "yaw_rate_bias+speed_dependent_cornering"]}
    if args.effects:
        groups = {"selected": args.effects}
    scale = {k: float(v) for k, v in (item.split("=") for item in args.scale_truth)}
    t0 = time.perf_counter()

    def case(name: str, seed: int, folder: str) -> tuple:
        healthy = name.removeprefix("healthy:") if name.startswith("healthy:") else None
        effect = None if healthy or name == "none" else name
        identify = args.identify == "all" or (args.identify == "tyre" and "tyre_saturation" in name)
        return effect, 1000 + seed, folder, scale, args.duration, healthy, args.vehicle, None, identify

    print(f"identify first (as diagnose does by default): {args.identify} (--identify tyre|all|none)")
    with tempfile.TemporaryDirectory() as folder:
        cases = [case(c, s, folder) for cases in groups.values() for c in cases for s in range(args.seeds or 3)]
        rows = [score(run) for run in diagnose_many(cases, args.workers)]
    _rate_table(groups, rows, args.duration, t0)
    if not args.no_timing:
        print("\nseconds per diagnosis of a 420 s log (plots included, one process; budget 15 s)")
        for case, seconds in timing(420.0, ["none", "steering_offset+yaw_rate_bias",
                                            "actuator_delay+steering_offset+antenna_lever_arm", "wheel_slip"]):
            print(f"{case:48s} {seconds:6.1f} s")


if __name__ == "__main__":
    main()
