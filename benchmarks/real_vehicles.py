"""Identify and diagnose every real vehicle of the corpus (benchmarks/real_corpus.toml) that has a
steering or turn-rate input:
``python3 benchmarks/real_vehicles.py [--out DIR] [--only NAME] [--realdata DIR] [--corpus DIR]``.

Each recording is read as ``convert`` reads it, with its manifest's import options (signals, time,
wheelbase, steering ratio, align, bus, DBC), and judged against the study the manifest names, else
the shipped study of its class (CLASS_STUDY): a small Ackermann robot against studies/f1tenth.toml,
a passenger car against studies/passenger_car.toml, a tractor against studies/figure8.toml; a
skid-steer robot has no shipped study (identify fits its skid-steer model; diagnose runs on the
default study). The F1TENTH FrictionMaps runs the manifest does not list (DS2, DS4, DS5) are read
as its DS1 is, and the AutoKoopman step runs (41 designed 3 s runs laid end to end) through
agrobot.measurements.f1tenth, against studies/f1tenth.toml. A recording without a steering or
turn-rate input (delta, delta_cmd, odom_yaw_rate, turn_rate_cmd) gets one line saying why it is
not judged.

Prints one table: vehicle, its class, the dimensions its publisher declares, the study judged
against, seconds, the identified vehicle diagnose shares with identify (delay, held-out fit; the tyre
saturation's friction as each tool concluded it, labelled), the independent estimates side by side (K from the dynamic fit and from steady
states, the delay from the fit and from a cross-correlation, the gyro bias from the fit and from
the GNSS course), the independent reference (benchmarks/real_corpus.py's second method on the raw
files: the slope of the yaw rate on v tan(delta / N) / L with the declared N and L at its best lag,
and that lag), the physical checks (beta, vy, a_y when the log has them), the verdict with its
status and statement, whether it is plausible for the vehicle (a value its class has, an
understeer gradient concluded, the study's wheelbase, nothing on a bound), what was not judged,
and the time taken; the second method's steady linear turns (steady_turn_gains: the yaw rate on
v tan(delta) / L per speed band, numpy only) beside the wheelbase diagnose reads from them; and
the yaw-rate misfit of identify's model and of the diagnosis's on the same unseen stretches
(identify's held-out segments inside the diagnosis's held-out part), and what the diagnosis held
out (the last 40 %, or every third 10 s when the last part is driven beyond the first's
conditions).
"""
from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
import real_corpus  # noqa: E402  (its import options, study paths and second method)

MANIFEST = ROOT / "benchmarks" / "real_corpus.toml"
CLASS_STUDY = {"small Ackermann robot": "studies/f1tenth.toml", "passenger car": "studies/passenger_car.toml",
               "tractor or implement": "studies/figure8.toml"}
INPUTS = ("delta", "delta_cmd", "odom_yaw_rate", "turn_rate_cmd")    # what identify's models are driven by
EXTRA_FRICTIONMAPS = ("DS2", "DS4", "DS5")


def recordings(roots: dict) -> list[dict]:
    """The manifest's recordings, then the FrictionMaps runs it leaves out (as its DS1) and the
    AutoKoopman step runs laid end to end (``loader``: read without convert)."""
    recs = tomllib.loads(MANIFEST.read_text())["recording"]
    ds1 = next(r for r in recs if r["name"] == "f1tenth_frictionmaps_DS1")
    extra = [{**ds1, "name": f"f1tenth_frictionmaps_{run}", "path": ds1["path"].replace("DS1", run),
              "reference": ds1["reference"] | {"published": "-"}} for run in EXTRA_FRICTIONMAPS]
    koopman = {"name": "f1tenth_autokoopman_steps (41 x 3 s)", "class": "small Ackermann robot", "root": "realdata",
               "path": "f1tenth_autokoopman_steps/F1tenthCar", "loader": "autokoopman",
               "vehicle": {"wheelbase": 0.32, "steering_ratio": 1.0}, "convert": {"study": "studies/f1tenth.toml"}}
    return recs + [r for r in extra if (roots["realdata"] / r["path"]).is_dir()] + [koopman]


def declared(rec: dict) -> str:
    """The dimensions the recording's publisher declares (the manifest's vehicle table)."""
    v = rec.get("vehicle", {})
    dims = [f"{k} {v[k]:g}{'' if k == 'steering_ratio' else ' m'}" for k in
            ("wheelbase", "steering_ratio", "track", "wheel_diameter") if k in v]
    assumed = " (assumed)" if "assumed" in v.get("note", "") or "guessed" in v.get("note", "") else ""
    return ("; ".join(dims) + assumed) if dims else "none declared"


def study_for(rec: dict, roots: dict) -> tuple[str | None, str]:
    """(the study judged against, how it was chosen): the manifest's, else its class's."""
    named = real_corpus.study_path(rec, roots)
    if named:
        return named, "the manifest's"
    if rec["class"] in CLASS_STUDY:
        return str(ROOT / CLASS_STUDY[rec["class"]]), f"its class's ({CLASS_STUDY[rec['class']]})"
    return None, f"none: no shipped study of a {rec['class']} (the default study)"


def read(rec: dict, roots: dict, folder: Path):
    """(the log, the source diagnose reads, its import options): a recording read as convert reads it."""
    from agrobot import api

    if rec.get("loader") == "autokoopman":
        from agrobot.measurements.f1tenth import autokoopman_log

        log = autokoopman_log(roots[rec["root"]] / rec["path"])
        path = folder / "autokoopman.parquet"
        log.drop(columns=[c for c in ("run",) if c in log]).to_parquet(path)
        return log, path, None
    options = real_corpus.import_options(rec, roots)
    source = roots[rec["root"]] / rec["path"]
    return api.convert(source, options=options).log, source, options


def reference(rec: dict, roots: dict) -> str:
    """The second method on the raw files (real_corpus.kinematic): the slope of the yaw rate on
    v tan(delta / N) / L with the declared N and L, at the lag of the best correlation."""
    if "reference" not in rec:
        return "-"
    try:
        kin = real_corpus.reference_numbers(rec, roots)["kinematic"]
    except Exception as exc:          # noqa: BLE001 - a failing reference is a cell of the table
        return f"failed: {type(exc).__name__}: {exc}"
    if kin is None:
        return "no steering, yaw and speed to compare"
    if math.isnan(kin["slope"]):
        return f"constant input: yaw / kinematic ratio {kin['ratio']:.3g} ({kin['seconds']:.0f} s)"
    return (f"slope {kin['slope']:.3g} at lag {kin['delay']:.2f} s (corr {kin['corr']:.2f}; "
            f"{kin['seconds']:.0f} s)")


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
    verdict = " NOT CONCLUDED" if c.get("concluded") is False else "" if c["agree"] else " DISAGREE"
    return text + verdict + (" NOT OF THE CLASS" if c.get("implausible") else "")


SIZE = 1.3          # a suggested study is of the vehicle's size when its wheelbase is within 30 %
WHEELBASE = 1.1     # the log's wheelbase is the declared one within 10 %


def plausible(res: dict, wheelbase: float | None) -> str:
    """Whether what the diagnosis concluded fits the declared vehicle (diagnosis.plausibility): 'yes',
    or each objection: a judged effect's value no vehicle of its class has, the log's turns not the
    study's vehicle, a study suggested that is not of the vehicle's size, the log's wheelbase off the
    declared ``wheelbase`` [m] by more than 10 % and not named, a baseline value on its bound; what
    it withheld and why (an understeer gradient not identifiable, or beyond the class and undecided)
    follows 'yes' as 'withheld'."""
    if res["verdict"] == "cannot decide":
        return "nothing concluded"
    said = [f"{e['id']}: {e['judgement'][0]}" for e in res.get("effects", []) if e.get("judgement")]
    mine = res.get("log_vehicle") or {}
    if mine.get("mismatch"):
        said.append("wheelbase: " + mine["mismatch"].split(": either")[0])
        tail = mine["mismatch"].split("(wheelbase ")
        if len(tail) > 1 and "is of the log's size" in tail[-1] and wheelbase:
            other = float(tail[-1].split(" m)")[0])
            if abs(math.log(other / wheelbase)) > math.log(SIZE):
                said.append(f"suggests a study of wheelbase {other:.3g} m for a vehicle of {wheelbase:.3g} m")
    elif mine.get("wheelbase") and wheelbase and abs(math.log(mine["wheelbase"] / wheelbase)) > math.log(WHEELBASE) \
            and res["verdict"] != "steering_gain" and not any("more than 10 %" in n for n in res.get("before_verdict") or []):
        said.append(f"the log's turns give a wheelbase of {mine['wheelbase']:.3g} m against the declared "
                    f"{wheelbase:.3g} m, and the verdict does not say why")
    said += [f"{r['name']} on its {r['at_bound']} bound" for r in res.get("baseline_refit_summary") or [] if r["at_bound"]]
    said += [f"{q['quantity']} (flagged): {q['implausible']}" for q in res.get("shared_quantities") or []
             + ((res.get("identified_vehicle") or {}).get("comparisons") or []) if q.get("implausible")]
    withheld = f"; withheld: understeer gradient, {res['understeer_note']}" if res.get("understeer_note") else ""
    return ("yes" + withheld) if not said else "no: " + "; ".join(said) + withheld


STEADY, LINEAR = 0.5, 2.0       # s the input is held; m/s2 of kinematic lateral acceleration


def steady_turn_gains(log, L: float) -> str:
    """The second method (numpy only): in each third of the moving speeds, the yaw rate regressed on
    v tan(delta) / L through the origin over steady turns (the input held within 0.02 rad + 10 % for
    STEADY s, |delta| > 0.03 rad, v^2 tan|delta| / L under LINEAR): the steering map's gain times
    L over the log's wheelbase, at low speed; its fall with speed is understeer."""
    import numpy as np

    steer = next((c for c in ("delta_cmd", "delta") if c in log), None)
    if steer is None or "yaw_rate" not in log or "v" not in log:
        return "no steering angle, yaw rate and speed"
    t, v, d, r = (log[c].to_numpy(float) for c in ("t", "v", steer, "yaw_rate"))
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


def identified(res: dict, piece, log, name: str, study) -> tuple[list, dict]:
    """(identify's comparisons, its cells): the model diagnose shares with identify on the stretch it
    judged, else identify on the whole log."""
    from agrobot.identification import skid_steer
    from agrobot.identification.ordinary_driving import identify_driving
    from agrobot.identification.vehicle import Vehicle
    from agrobot.diagnosis.effects.tyre_saturation import friction_text
    from agrobot.orchestrator.errors import InputError

    rep = (res.get("identified_vehicle") or {}).get("identified")
    if rep is not None:
        ident = {"identified on": f"the diagnosed {piece['t'].iloc[-1] - piece['t'].iloc[0]:.0f} s",
                 "delay [s]": fmt(rep["delay"]), "held-out fit [%]": f"{rep['held_out_fit']:.0f}",
                 "tyre saturation: identify; diagnose": tyre_cells(rep["tyre_saturation"], res)}
        held = rep.get("held_out_yaw") or {}
        if "diagnosis_rms" in held:    # both models on identify's held-out segments inside the diagnosis's
            ident["yaw RMS, same unseen stretches: identify; diagnose [deg/s]"] = (
                f"{math.degrees(held['rms']):.3g}; {math.degrees(held['diagnosis_rms']):.3g} ({held['seconds']:.0f} s)")
        return res["identified_vehicle"].get("comparisons", []), ident
    seconds = float(log["t"].iloc[-1] - log["t"].iloc[0])
    if skid_steer.applies(log, Vehicle.of(study)):
        return [], skid_steer_cells(log, name, study, seconds)
    try:
        full = identify_driving(log, name, study)
    except InputError as exc:
        return [], {"delay [s]": f"cannot judge: {exc}"}
    saturation = full.get("tyre_saturation") or {}
    return full.get("comparisons", []), {
        "identified on": f"all {seconds:.0f} s (diagnose: cannot decide)",
        "delay [s]": fmt(full["delay"]) if "delay" in full else "-",
        "held-out fit [%]": fmt(full["held_out_fit"], "{:.0f}") if "held_out_fit" in full else "-",
        "tyre saturation: identify; diagnose": "identify: " + (
            f"mu {friction_text(identify_friction(saturation))}" if saturation.get("found")
            else "not found" if saturation else "-") + "; diagnose: cannot decide"}


def identify_friction(saturation: dict) -> dict:
    """Identify's report's tyre saturation as diagnose's identified vehicle carries it (friction, at least)."""
    mu = saturation["parameters"]["friction"]
    return {"friction": mu["value"], "friction_at_least": bool(mu.get("at_least"))}


def tyre_cells(identified_saturation: dict | None, res: dict) -> str:
    """The friction each tool concluded, labelled: identify's (its "at least" where it ended on the
    class's top), diagnose's effect as its verdict says it ("at least" its bound, not identifiable
    on another bound, or not kept)."""
    from agrobot.diagnosis.effects.tyre_saturation import friction_text

    mine = f"mu {friction_text(identified_saturation)}" if identified_saturation else "not found"
    e = next((e for e in res.get("effects", []) if e["id"] == "tyre_saturation"), None)
    if e is None:
        theirs = "not kept"
    else:
        mu = e["fitted"]["tyre_friction"]
        theirs = ("mu at least {:.3g}" if mu.get("at_bound") == "upper" else
                  "mu not identifiable (on its lower bound {:.3g})" if mu.get("at_bound") else "mu {:.3g}").format(
            mu["value"])
    return f"identify: {mine}; diagnose: {theirs}"


def skid_steer_cells(log, name: str, study, seconds: float) -> dict:
    """identify's skid-steer model (the yaw rate against a turn-rate input): its yaw gain, delay,
    held-out fit and its own plausibility findings."""
    from agrobot.identification.skid_steer import identify_skid_steer

    rep = identify_skid_steer(log, name, study)
    found = rep["plausibility"]["findings"]
    return {"identified on": f"all {seconds:.0f} s, skid-steer model against {rep['input']}",
            "delay [s]": fmt(rep["delay"]), "held-out fit [%]": f"{rep['held_out_fit']['value']:.0f}",
            "tyre saturation: identify; diagnose": "-", "skid-steer yaw gain (B / B_eff)": fmt(rep["parameters"]["yaw_gain"]),
            "skid-steer plausibility": "yes" if not found else "no: " + "; ".join(map(str, found))}


def judged(rec: dict, roots: dict, folder: Path, keep: bool) -> dict:
    """One recording's row: read, diagnosed against its study, identify's and the reference's numbers."""
    from agrobot.diagnosis.pipeline import diagnose
    from agrobot.identification.from_log import longest_stretch
    from agrobot.identification.vehicle import Vehicle
    from agrobot.orchestrator.study import Study

    study_path, how = study_for(rec, roots)
    row = {"vehicle": rec["name"], "class": rec["class"], "declared": declared(rec),
           "study": f"{Path(study_path).name if study_path else '-'} ({how})"}
    log, source, options = read(rec, roots, folder)
    seconds = float(log["t"].iloc[-1] - log["t"].iloc[0])
    if not any(c in log for c in INPUTS):
        return row | {"seconds": f"{seconds:.0f}", "verdict": "not judged: no steering or turn-rate input "
                      f"(the log has {', '.join(c for c in log.columns if c != 't')}; identify and diagnose need "
                      f"one of {', '.join(INPUTS)})"}
    piece, _ = longest_stretch(log)         # what diagnose judges of a log with clock gaps
    res = diagnose(source, folder / "diagnosis", study_path, plots=keep, recording=options)
    study = Study.load(study_path or ROOT / "studies" / "figure8.toml")
    comparisons, ident = identified(res, piece, log, rec["name"], study)
    ident["K: dynamic; steady [rad/(m/s2)]"] = both(comparisons, "understeer")
    ident["delay: fit; xcorr [s]"] = both(comparisons, "command-to-yaw")
    ident["gyro bias: fit; course [rad/s]"] = both(comparisons, "gyro bias", "{:.2g}")
    ident["reference (raw files): yaw on v tan(delta/N)/L"] = reference(rec, roots)
    checks = (res.get("identified_vehicle") or {}).get("physical_checks") or {}
    ident["physical checks"] = "; ".join(f"{c} {v['fit_percent']:.0f} %" for c, v in checks.items()) or "no beta/vy/a_y"
    ident["held out"] = (res.get("split") or {}).get("held_out", "-")
    verdict = f"{res['verdict']} ({res.get('verdict_status', '')})"
    verdict += f": {res['reason'].split(': ', 1)[-1]}" if res["verdict"] == "cannot decide" else ": " + res.get(
        "verdict_statement", "")
    before = "; ".join(res.get("before_verdict") or []) or "-"
    not_judged = "; ".join(f"{s}: {w.removeprefix('not judged: ')}" for s, w in res.get("not_judged", {}).items())
    mine = res.get("log_vehicle") or {}
    L = Vehicle.of(study).wheelbase or 1.4
    ident["steady linear turns: gain per speed (samples); log's wheelbase [m]"] = (
        steady_turn_gains(piece, L) + "; L " + (f"{mine['wheelbase']:.3g}" if mine.get("wheelbase")
                                                else f"none ({mine.get('why', '-')})"))
    wheelbase = rec.get("vehicle", {}).get("wheelbase") or Vehicle.of(study).wheelbase
    return row | {"seconds": f"{seconds:.0f} (diagnosed {piece['t'].iloc[-1] - piece['t'].iloc[0]:.0f})", **ident,
                  "said before the verdict": before, "verdict": verdict,
                  "plausible for the vehicle": plausible(res, wheelbase), "not judged": not_judged or "-"}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", type=Path, default=None, help="keep each recording's outputs here")
    ap.add_argument("--only", default="", help="the recordings whose name contains this (DS3, kora, polaris)")
    ap.add_argument("--realdata", type=Path, default=real_corpus.ROOTS["realdata"])
    ap.add_argument("--corpus", type=Path, default=real_corpus.ROOTS["corpus"])
    args = ap.parse_args()
    roots = {"realdata": args.realdata, "corpus": args.corpus}
    recs = recordings(roots)
    chosen = [r for r in recs if args.only in r["name"]]
    if not chosen:
        ap.error(f"--only {args.only!r}: no recording's name contains it; the recordings: "
                 f"{'; '.join(r['name'] for r in recs)}")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for k, rec in enumerate(chosen):
            start = time.perf_counter()
            folder = (args.out or Path(tmp)) / f"recording{k}"
            folder.mkdir(parents=True, exist_ok=True)
            try:
                row = judged(rec, roots, folder, args.out is not None)
            except Exception as exc:          # noqa: BLE001 - what fails on a real recording is a row
                row = {"vehicle": rec["name"], "class": rec["class"], "declared": declared(rec),
                       "verdict": f"failed: {type(exc).__name__}: {' '.join(str(exc).split())}"}
            rows.append(row | {"time [s]": f"{time.perf_counter() - start:.0f}"})
            print(f"{rec['name']}: done in {time.perf_counter() - start:.0f} s", file=sys.stderr, flush=True)
    cols = list(dict.fromkeys(k for r in rows for k in r))
    print("| " + " | ".join(cols) + " |")
    print("|" + "---|" * len(cols))
    for r in rows:
        print("| " + " | ".join(str(r.get(c, "-")).replace("|", "/").replace("\n", " ") for c in cols) + " |")


if __name__ == "__main__":
    main()
