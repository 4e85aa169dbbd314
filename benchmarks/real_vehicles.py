"""Identify and diagnose every real vehicle log in ../shared/realdata:
``python3 benchmarks/real_vehicles.py [--out DIR] [--only NAME]``.

F1TENTH FrictionMaps DS1..DS5 (a 1:10 car driven by hand) and the AutoKoopman step runs (the same
kind of car, 41 designed 3 s runs laid end to end), read by the recording importer (as ``convert``
reads them: the longest run without a clock gap) through tests/vehicle_logs.py, against
studies/f1tenth.toml.
Prints one table: vehicle, seconds, the identified vehicle diagnose shares with identify (delay,
held-out fit, tyre saturation), the independent estimates side by side (K from the dynamic fit and
from steady states, the delay from the fit and from a cross-correlation, the gyro bias from the fit
and from the GNSS course), the physical checks (beta, vy, a_y when the log has them), the verdict
with its status and statement, whether it is plausible for the vehicle (a value its class has, an
understeer gradient concluded, the study's wheelbase, nothing on a bound), what was not judged, and
the time taken; the second method's steady linear turns (steady_turn_gains: the yaw rate on
v tan(delta) / L per speed band, numpy only) beside the wheelbase diagnose reads from them; and the yaw-rate misfit of
identify's model and of the diagnosis's on the same unseen stretches (identify's held-out segments
inside the diagnosis's held-out part), and what the diagnosis held out (the last 40 %, or every third
10 s when the last part is driven beyond the first's conditions).
"""
from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
REAL = ROOT.parent / "shared" / "realdata"
if not REAL.is_dir():
    REAL = Path("/work/shared/realdata")


def logs():
    from agrobot.measurements.f1tenth import autokoopman_log, frictionmaps_log

    folder = REAL / "f1tenth_frictionmaps" / "DataSets"
    for run in sorted(p.name for p in folder.iterdir() if p.is_dir()):
        yield f"F1TENTH FrictionMaps {run}", frictionmaps_log(folder / run)
    yield "F1TENTH AutoKoopman steps (41 x 3 s)", autokoopman_log(REAL / "f1tenth_autokoopman_steps" / "F1tenthCar")


def fmt(q: dict, f: str = "{:.3g}") -> str:
    if not q.get("identifiable", True):
        return "not identifiable"
    return f.format(q["value"]) + " [" + ", ".join(f.format(x) for x in q["interval"]) + "]"


def both(comparisons: list[dict], quantity: str, f: str = "{:.3g}") -> str:
    """The two estimates of a quantity, 'DISAGREE' when their intervals do not overlap."""
    c = next((c for c in comparisons if c["quantity"].startswith(quantity)), None)
    if c is None:
        return "-"
    text = "; ".join(f"{m.split(' ')[0]} " + f.format(e["value"]) + " [" + ", ".join(f.format(x) for x in e["interval"]) + "]"
                     for m, e in c["estimates"].items())
    return text + ("" if c["agree"] else " DISAGREE")


def plausible(res: dict) -> str:
    """Whether what the diagnosis concluded fits the declared vehicle (diagnosis.plausibility): 'yes',
    or each objection: a judged effect's value no vehicle of its class has, the log's turns not the
    study's vehicle, a baseline value on its bound; what it withheld and why (an understeer gradient
    not identifiable, or beyond the class and undecided) follows 'yes' as 'withheld'."""
    if res["verdict"] == "cannot decide":
        return "nothing concluded"
    said = [f"{e['id']}: {e['judgement'][0]}" for e in res.get("effects", []) if e.get("judgement")]
    if (res.get("log_vehicle") or {}).get("mismatch"):
        said.append("wheelbase: " + res["log_vehicle"]["mismatch"].split(": either")[0])
    said += [f"{r['name']} on its {r['at_bound']} bound" for r in res.get("baseline_refit_summary") or [] if r["at_bound"]]
    withheld = f"; withheld: understeer gradient, {res['understeer_note']}" if res.get("understeer_note") else ""
    return ("yes" + withheld) if not said else "no: " + "; ".join(said) + withheld


STEADY, LINEAR = 0.5, 2.0       # s the input is held; m/s2 of kinematic lateral acceleration


def steady_turn_gains(log, L: float) -> str:
    """The second method (numpy only): in each third of the moving speeds, the yaw rate regressed on
    v tan(delta) / L through the origin over steady turns (the input held within 0.02 rad + 10 % for
    STEADY s, |delta| > 0.03 rad, v^2 tan|delta| / L under LINEAR): the steering map's gain times
    L over the log's wheelbase, at low speed; its fall with speed is understeer."""
    import numpy as np

    t, v, d, r = (log[c].to_numpy(float) for c in ("t", "v", "delta_cmd", "yaw_rate"))
    n = max(2, int(round(STEADY / float(np.median(np.diff(t))))))
    held = np.array([np.ptp(d[k - n + 1:k + 1]) if k >= n - 1 else np.inf for k in range(len(d))])
    ok = np.isfinite(v) & np.isfinite(d) & np.isfinite(r) & (v > 0.2)
    sel = ok & (held <= 0.02 + 0.1 * np.abs(d)) & (np.abs(d) > 0.03) & (v ** 2 * np.tan(np.abs(d)) / L < LINEAR)
    if sel.sum() < 15:
        return f"{sel.sum()} steady linear samples: none to read"
    out = []
    for lo, hi in zip(*(lambda e: (e[:-1], e[1:]))(np.percentile(v[sel], [0, 33, 67, 100]))):
        m = sel & (v >= lo) & (v <= hi)
        x = v[m] * np.tan(d[m]) / L
        if m.sum() >= 5:
            out.append(f"{np.median(v[m]):.2g} m/s: {float(x @ r[m] / (x @ x)):.2f} ({m.sum()})")
    return "; ".join(out)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", type=Path, default=None, help="keep each log's outputs here")
    ap.add_argument("--only", default="", help="the logs whose name contains this (DS3, AutoKoopman)")
    args = ap.parse_args()
    from agrobot.diagnosis.pipeline import diagnose
    from agrobot.identification.from_log import longest_stretch
    from agrobot.identification.ordinary_driving import identify_driving
    from agrobot.identification.vehicle import Vehicle
    from agrobot.orchestrator.errors import InputError
    from agrobot.orchestrator.study import Study

    study_path = ROOT / "studies" / "f1tenth.toml"
    study = Study.load(study_path)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        base = args.out or Path(tmp)
        names = []
        for k, (name, log) in enumerate(logs()):
            names.append(name)
            if args.only not in name:
                continue
            start = time.perf_counter()
            seconds = float(log["t"].iloc[-1] - log["t"].iloc[0])
            piece, _ = longest_stretch(log)         # what diagnose judges of a log with clock gaps
            path = base / f"log{k}.parquet"
            path.parent.mkdir(parents=True, exist_ok=True)
            log.drop(columns=[c for c in ("run",) if c in log]).to_parquet(path)
            res = diagnose(path, base / f"diagnosis{k}", study_path, plots=args.out is not None)
            rep = (res.get("identified_vehicle") or {}).get("identified")
            if rep is not None:         # the model diagnose shares with identify, on the stretch it judged
                comparisons = res["identified_vehicle"].get("comparisons", [])
                ident = {"identified on": f"the diagnosed {piece['t'].iloc[-1] - piece['t'].iloc[0]:.0f} s",
                         "delay [s]": fmt(rep["delay"]), "held-out fit [%]": f"{rep['held_out_fit']:.0f}",
                         "tyre saturation": (f"mu {rep['tyre_saturation']['friction']:.2f}" if rep["tyre_saturation"]
                                             else "not found")}
                held = rep.get("held_out_yaw") or {}
                if "diagnosis_rms" in held:    # both models on identify's held-out segments inside the diagnosis's
                    ident["yaw RMS, same unseen stretches: identify; diagnose [deg/s]"] = (
                        f"{math.degrees(held['rms']):.3g}; {math.degrees(held['diagnosis_rms']):.3g} "
                        f"({held['seconds']:.0f} s)")
            else:
                try:
                    full = identify_driving(log, name, study)
                    comparisons = full.get("comparisons", [])
                    ident = {"identified on": f"all {seconds:.0f} s (diagnose: cannot decide)",
                             "delay [s]": fmt(full["delay"]), "held-out fit [%]": fmt(full["held_out_fit"], "{:.0f}"),
                             "tyre saturation": (f"mu {full['tyre_saturation']['parameters']['friction']['value']:.2f}"
                                                 if full["tyre_saturation"]["found"] else "not found")}
                except InputError as exc:
                    comparisons, ident = [], {"delay [s]": f"cannot judge: {exc}"}
            ident["K: dynamic; steady [rad/(m/s2)]"] = both(comparisons, "understeer")
            ident["delay: fit; xcorr [s]"] = both(comparisons, "command-to-yaw")
            ident["gyro bias: fit; course [rad/s]"] = both(comparisons, "gyro bias", "{:.2g}")
            checks = (res.get("identified_vehicle") or {}).get("physical_checks") or {}
            ident["physical checks"] = "; ".join(f"{c} {v['fit_percent']:.0f} %" for c, v in checks.items()) or "no beta/vy/a_y"
            split = res.get("split") or {}
            ident["held out"] = split.get("held_out", "-")
            verdict = f"{res['verdict']} ({res.get('verdict_status', '')})"
            if res["verdict"] == "cannot decide":
                verdict += f": {res['reason'].split(': ', 1)[-1]}"
            else:
                verdict += ": " + res.get("verdict_statement", "")
            not_judged = "; ".join(f"{s}: {w.removeprefix('not judged: ')}" for s, w in res.get("not_judged", {}).items())
            mine = res.get("log_vehicle") or {}
            ident["steady linear turns: gain per speed (samples); log's wheelbase [m]"] = (
                steady_turn_gains(piece, Vehicle.of(study).wheelbase) + "; L "
                + (f"{mine['wheelbase']:.3g}" if mine.get("wheelbase") else f"none ({mine.get('why', '-')})"))
            rows.append({"vehicle": name, "seconds": f"{seconds:.0f} (diagnosed {piece['t'].iloc[-1]:.0f})", **ident,
                         "verdict": verdict, "plausible for the vehicle": plausible(res), "not judged": not_judged or "-",
                         "time [s]": f"{time.perf_counter() - start:.0f}"})
            print(f"{name}: done in {time.perf_counter() - start:.0f} s", file=sys.stderr, flush=True)
    if not rows:
        ap.error(f"--only {args.only!r}: no log's name contains it; the logs: {'; '.join(names)}")
    cols = list(dict.fromkeys(k for r in rows for k in r))
    print("| " + " | ".join(cols) + " |")
    print("|" + "---|" * len(cols))
    for r in rows:
        print("| " + " | ".join(str(r.get(c, "")).replace("|", "/") for c in cols) + " |")


if __name__ == "__main__":
    main()
