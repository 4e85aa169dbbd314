"""``identify LOG``: which method a measured log gets, and the driving method's outputs
(identification.json, the figures, the summary on the terminal, progress on stderr).

Imported where used: identification.driving_plots (matplotlib: only a run that draws figures loads it).
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd

from agrobot.diagnosis.plausibility import study_understeer
from agrobot.diagnosis.study_fit import study_check
from agrobot.measurements import LogError, load_log
from agrobot.measurements.audit import require_causal
from agrobot.measurements.log import DEGREE_SUSPECT, check_log, persisted_audit, persisted_report, yaw_rate_in_radians
from agrobot.measurements.recording import ImportOptions, is_recording
from agrobot.orchestrator.atomic_files import atomic_write, write_json
from agrobot.orchestrator.resolver import resolve

from .blas_threads import one_blas_thread
from .experiment import detect_period
from . import skid_steer
from .ordinary_driving import identify_driving, study_plant
from .pipeline import _json_default
from .vehicle import Vehicle


def _read(source: Path, resample: bool, recording, study, causal: bool = True):
    """The log as measurements.load_log reads it; a table with clock gaps or jitter (ordinary
    logging) is checked piece by piece between its gaps, each piece on its own even clock.
    ``causal``: refuse a log whose response leads its input (measurements.audit.require_causal);
    False leaves the unresolved finding on the log for a reader that judges it (the diagnosis)."""
    try:
        loaded = load_log(source, ("t",), resample_jitter=resample,
                          recording=(recording or ImportOptions()).for_vehicle(study))
    except LogError as exc:
        if is_recording(Path(source)) or not ("gap" in str(exc) or "unevenly" in str(exc)):
            raise
    else:
        if causal:
            require_causal(loaded[0], str(source))      # a response leading its input: refused, said why
        return loaded
    frame = pd.read_parquet(source) if Path(source).suffix == ".parquet" else pd.read_csv(source)
    frame.attrs.setdefault("audit", persisted_audit(source) or [])
    if causal:
        require_causal(frame, str(source))
    t = frame["t"].to_numpy(float)
    if np.any(np.diff(t) <= 0):
        i = int(np.argmax(np.diff(t) <= 0))
        raise LogError(f"{source}: column 't' is not increasing at row {i + 1} (t = {t[i]} then {t[i + 1]})")
    # every check of a log but the even clock (identification.driving puts each piece on its own)
    even = frame.iloc[:3].assign(t=[0.0, 0.01, 0.02])
    for c in frame.columns:
        if c != "t" and pd.api.types.is_numeric_dtype(frame[c]):
            bad = ~np.isfinite(frame[c].to_numpy(float))
            if bad.any():
                raise LogError(f"{source}: column {c!r} has {int(bad.sum())} NaN or infinite values (first at row "
                               f"{int(np.argmax(bad))}, t = {t[int(np.argmax(bad))]:.4g} s)")
    peaks = frame.abs().max().to_frame().T
    # a fast yaw rate is judged on the motion of the longest stretch (measurements.log.yaw_rate_in_radians)
    fast = "yaw_rate" in frame and len(frame) > 10 and float(peaks["yaw_rate"].iloc[0]) > DEGREE_SUSPECT["yaw_rate"][0]
    why = yaw_rate_in_radians(longest_stretch(frame)[0]) if fast else None
    if why:
        even, peaks = even.drop(columns="yaw_rate"), peaks.drop(columns="yaw_rate")
        frame.attrs.setdefault("notes", []).append(f"column 'yaw_rate' read as rad/s: {why}")
    check_log(pd.concat([even, peaks.assign(t=0.03)], ignore_index=True), str(source), ("t",))
    return frame, None


def longest_stretch(frame, gap: float | None = None):
    """(the longest stretch of the log without a clock gap, on an even clock of its median step;
    (start, end) of it in the log's time). A gap: a step longer than max(0.5 s, 5 median steps)."""
    t = frame["t"].to_numpy(float)
    step = float(np.median(np.diff(t)))
    cuts = np.flatnonzero(np.diff(t) > (gap or max(0.5, 5 * step))) + 1
    a, b = max(zip(np.r_[0, cuts], np.r_[cuts, len(t)]), key=lambda ab: ab[1] - ab[0])
    step = float(np.median(np.diff(t[a:b])))
    even = on_even_clock(frame, slice(a, b), t[a], t[b - 1], step)
    even["t"] -= t[a]
    even.attrs = dict(frame.attrs)          # the audit's findings, the selection: the stretch's too
    moved(even, frame, t[a], t[b - 1])
    return even, (float(t[a]), float(t[b - 1]))


def moved(even: pd.DataFrame, frame: pd.DataFrame, a: float, b: float) -> None:
    """even.attrs["own_samples"] (measurements.runs.OwnSamples: the signals' own samples) on the
    clock of ``even``, the stretch a..b of ``frame`` starting at 0: those within it and the one
    either side (a held value in force at a, an interpolation's ends)."""
    own = frame.attrs.get("own_samples")
    if not own:
        return
    out = {}
    for c, (tc, vc) in own.items():
        lo, hi = max(int(np.searchsorted(tc, a, side="right")) - 1, 0), int(np.searchsorted(tc, b, side="left")) + 1
        out[c] = (np.asarray(tc[lo:hi], float) - a, np.asarray(vc[lo:hi], float))
    even.attrs["own_samples"] = type(own)(out)


def on_even_clock(frame, rows, a: float, b: float, step: float) -> pd.DataFrame:
    """The numeric columns of ``frame``'s ``rows`` interpolated (linearly) on the even clock
    t = a + k step, a <= t <= b; its t column that clock."""
    t = frame["t"].to_numpy(float)[rows]
    grid = a + step * np.arange(int(math.floor((b - a) / step + 1e-9)) + 1)
    return pd.DataFrame({"t": grid, **{c: np.interp(grid, t, frame[c].to_numpy(float)[rows]) for c in frame.columns
                                       if c != "t" and pd.api.types.is_numeric_dtype(frame[c])}})


def joined_stretches(frame):
    """(the stretches a selection keeps, frame.attrs["stretches"] (measurements.modes.judged),
    each on an even clock of the log's median step, one after the other on one clock; the note
    that says so), or None for fewer than two. frame.attrs["joins"] holds where each later one
    starts: the replays burn in again there (diagnosis.candidates)."""
    spans = frame.attrs.get("stretches") or []
    if len(spans) < 2:
        return None
    t = frame["t"].to_numpy(float)
    step = float(np.median(np.diff(t)))
    pieces, joins, start = [], [], 0.0
    for a, b in spans:
        piece = on_even_clock(frame, (t >= a - 1e-9) & (t <= b + 1e-9), a, b, step)
        piece["t"] = start + step * np.arange(len(piece))
        if pieces:
            joins.append(start)
        pieces.append(piece)
        start += step * len(piece)
    even = pd.concat(pieces, ignore_index=True)
    even.attrs = {k: v for k, v in {**frame.attrs, "joins": joins}.items() if k != "own_samples"}   # re-clocked
    if frame.attrs.get("own_samples"):
        even.attrs["own_samples_dropped"] = ("the stretches judged are joined on one new clock, and the signals' own "
                                             "stamps are on the recording's")
    first, last = frame.attrs.get("log_span", (t[0], t[-1]))
    passed = max(last - first - sum(b - a for a, b in spans), 0.0)
    return even, (f"the {len(spans)} stretches judged are joined on one even {1 / step:.3g} Hz clock, each with its own "
                  f"burn-in: " + ", ".join(f"{a:.1f}-{b:.1f} s" for a, b in spans)
                  + f"; passed over: {passed:.0f} s that the selection left out (--keep-unexplained or --where "
                    f"judge others, --min-stretch sets the shortest stretch judged)")


def read_uneven(source: Path, resample: bool = False, recording=None, study=None, causal: bool = True):
    """(log, import report, note): the log as load_log reads it; a table whose clock has gaps or
    jitter (ordinary logging) gives its longest gap-free stretch on an even clock, and says so
    (``causal``: as _read)."""
    frame, imported = _read(source, resample, recording, study, causal)
    joined = joined_stretches(frame)
    if joined is not None:
        return joined[0], imported, joined[1]
    t = frame["t"].to_numpy(float)
    dt = np.diff(t)
    if len(dt) and (dt.max() > 1.5 * np.median(dt) or np.max(np.abs(dt - np.median(dt))) > 0.01 * np.median(dt)):
        even, (a, b) = longest_stretch(frame)
        passed = max(len(t) * float(np.median(dt)) - (b - a), 0.0)
        why = (" (the stretches the selection left out cut it: --keep-unexplained or --where judge others)"
               if frame.attrs.get("selection") else "")
        return even, imported, (f"the log's clock has gaps or jitter{why}: its longest stretch without a gap, t = "
                                f"{a:.1f}-{b:.1f} s of {t[0]:.1f}-{t[-1]:.1f} s, is judged on an even "
                                f"{1 / float(np.median(np.diff(even['t']))):.3g} Hz clock; passed over: {passed:.0f} s "
                                f"of the log's other stretches")
    return frame, imported, None


def wants_driving(source: Path, resample: bool, recording, study) -> bool:
    """True unless delta_cmd repeats itself with a period (a designed multisine experiment)."""
    frame, _ = _read(source, resample, recording, study)
    if "delta_cmd" not in frame or "delta" not in frame:
        return True
    try:
        detect_period(frame["delta_cmd"].to_numpy(float))
    except LogError:
        return True
    return False


def choose_method(source: Path, method: str = "auto", resample: bool = False, recording=None, study=None) -> str:
    """How ``identify SOURCE`` identifies: ``"study"`` for a study file (its designed experiment,
    simulated), else ``method`` for a log, where ``"auto"`` is ``"multisine"`` when delta_cmd
    repeats with a period (wants_driving) and ``"driving"`` otherwise."""
    if Path(source).suffix in (".toml", ".yaml", ".yml"):
        return "study"
    if method not in ("auto", "multisine", "driving"):
        raise ValueError(f"method {method!r}: expected 'auto', 'multisine' or 'driving'")
    if method != "auto":
        return method
    return "driving" if wants_driving(Path(source), resample, recording, study) else "multisine"


@one_blas_thread
def driving_report(source: Path, study=None, resample: bool = False, recording=None, progress=None,
                   course_speed: float | None = None, fit_seconds: float | None = None, geometry: str = "auto",
                   input_hold: str = "auto"):
    """(report, the figures' data): the ordinary-driving identification of a log
    (identification.ordinary_driving; a skid-steered vehicle's, identification.skid_steer), nothing written; the wheelbase given with ``recording``
    (--wheelbase) is the vehicle's; ``course_speed``: the GNSS course's speed floor, ``fit_seconds``:
    the most of the segments fitted (None: their defaults); ``geometry``: the steering geometry,
    ``input_hold``: how the input is read between its rows (ordinary_driving.identify_driving)."""
    say = progress or (lambda text: None)
    frame, imported = _read(source, resample, recording, study)
    say(f"read {source}: {len(frame)} rows, {frame['t'].iloc[-1] - frame['t'].iloc[0]:.0f} s")
    more = ({} if course_speed is None else {"course_speed": course_speed}) | \
        ({} if fit_seconds is None else {"max_fit_seconds": fit_seconds})
    if skid_steer.applies(frame, Vehicle.of(study)):       # no steering angle: the yaw against a turn rate
        report = skid_steer.identify_skid_steer(frame, str(source), study, say)
        passed = [o for o, given in (("--wheelbase", getattr(recording, "wheelbase", None)),
                                     ("--fit-seconds", fit_seconds), ("--course-speed", course_speed)) if given is not None]
        if passed:
            report["notes"].append(f"passed over: {', '.join(passed)} (the skid-steer model has no wheelbase, fits "
                                   f"every segment and needs a gyro, not a GNSS course)")
    else:
        report = identify_driving(frame, str(source), study, progress=say,
                                  wheelbase=recorded_wheelbase(source, getattr(recording, "wheelbase", None)),
                                  geometry=geometry,
                                  input_hold=input_hold, **more)
        if imported is not None and imported.get("steering_ratio"):      # never applied silently
            report["notes"].insert(0, imported["steering_ratio"]["text"])
        study_mismatch(report, frame, study, say)
    hidden = report.pop("_plot")
    if imported is not None:
        report["recording"] = imported
    return report, hidden


def recorded_wheelbase(source: Path, given: float | None):
    """The wheelbase identify stands on before the study's: the one given (--wheelbase), else the one
    ``convert --wheelbase`` recorded beside a converted log (its <name>.import.json), as (L, where
    from); the recorded one passed over for one given is said; None: neither."""
    saved = None if is_recording(Path(source)) else persisted_report(source).get("wheelbase")
    saved = saved.get("value") if isinstance(saved, dict) else None
    side = f"{Path(source).stem}.import.json"
    if given:
        passed = (f"; the {saved:.3g} m that convert --wheelbase recorded in {side} passed over"
                  if saved and abs(saved - given) > 1e-9 else "")
        return float(given), f"given with the recording (--wheelbase){passed}"
    if saved:
        return float(saved), f"recorded by convert --wheelbase in {side} (--wheelbase gives another)"
    return None


def study_mismatch(report: dict, frame, study, say) -> None:
    """The log's steady turns against the wheelbase identify stood on, by the diagnosis's rule
    (diagnosis.study_fit.study_check: more than 30 % apart, the study's understeer allowed for): when
    they disagree, named first among the report's notes (``study_mismatch``) and on stderr."""
    L = (report.get("vehicle") or {}).get("wheelbase")
    if not L:
        return
    name = Path(study.path).name if getattr(study, "path", None) else "paper tractor (no --study)"
    _, text = study_check(frame, float(L), name, study_understeer(study_plant(study)[1]))
    if text:
        report["study_mismatch"] = text
        report["notes"].insert(0, f"before the results: {text}")
        say(f"warning: {text}")


def write_driving(report: dict, hidden, out_dir: Path, study=None, source=None, plots: bool = True,
                  progress=None) -> list[str]:
    """identification.json, the figures (when ``hidden``, the figures' data, is given) and
    extended_study.toml (with ``study``) in ``out_dir``; returns the figures' names."""
    out_dir = Path(out_dir)
    files = []
    if plots and hidden is not None and report.get("final_model") in ("kinematic", "steady_turn", "skid_steer"):
        report["figures_note"] = f"no figures in the {report['final_model'].replace('_', ' ')} (they show the tyres' model)"
    elif plots and hidden is not None:
        from .driving_plots import write_driving_plots

        if progress is not None:
            progress("figures")
        files = [p.name for p in write_driving_plots(report, hidden, out_dir)]
    report["figures"] = files
    if study is not None and report.get("final_model") != "skid_steer":     # its study has no skid-steer plant
        report["extended_study"] = write_extended_study(report, study, out_dir, source)
    write_json(out_dir / "identification.json", finite_for_json(json.loads(json.dumps(report, default=_json_default))))
    return files


def finite_for_json(v):
    """JSON has no infinity: a non-finite number is written as null."""
    if isinstance(v, float) and not math.isfinite(v):
        return None
    if isinstance(v, dict):
        return {k: finite_for_json(x) for k, x in v.items()}
    if isinstance(v, list):
        return [finite_for_json(x) for x in v]
    return v


def write_extended_study(report: dict, study, out_dir: Path, source) -> str | None:
    """extended_study.toml: the study with what the log identified (cornering stiffnesses, the
    steering's delay, the gyro's bias, and tyre saturation when found: the friction, the shape and,
    where identify fitted one friction per axle, the rear / front ratio, tyre_friction_ratio, with the
    front's friction) -- the study then simulates the vehicle of the log. Parameters not identifiable
    from the log keep the study's values."""
    model = resolve(study)
    plant = model.find(role="yaw_plant")
    if not plant:
        return None
    values, left_out = {}, []
    K = report["understeer_gradient"]
    if K.get("withheld") or not K.get("identifiable", True):
        left_out.append("C_f, C_r (they fix one understeer gradient K, and no single K is concluded: " + (
            "the dynamic fit's and the steady turns' disagree)" if K.get("withheld") else f"{K.get('note', '')})"))
    for key, name in (("front", "C_f"), ("rear", "C_r")):
        s = report["cornering_stiffness"][key]
        if s["identifiable"] and not left_out:
            values[f"{plant[0]}.{name}"] = s["value"]
    params = report["parameters"]
    steering = model.find(role="steering")
    if steering and params["delay"]["identifiable"]:
        values[f"{steering[0]}.command_delay"] = params["delay"]["value"]
    gyro = model.find(role="gyro")
    bias = params.get("gyro_bias", {})
    if gyro and bias.get("identifiable") and bias.get("concluded", True) and (bias["interval"][0] > 0 or bias["interval"][1] < 0):
        values[f"{gyro[0]}.bias"] = params["gyro_bias"]["value"]
    tyre = report["tyre_saturation"]
    if tyre["found"] and tyre["parameters"]["friction"].get("at_least"):
        left_out.append(f"tyre_friction{', tyre_friction_ratio' if 'friction_ratio' in tyre['parameters'] else ''} "
                        f"(identified at least {tyre['parameters']['friction']['bounds'][1]:g}, not a "
                        f"value: the study keeps its own)")
    elif tyre["found"] and tyre["parameters"]["friction"].get("identifiable", True):
        values[f"{plant[0]}.tyre_friction"] = tyre["parameters"]["friction"]["value"]
        if tyre["parameters"]["shape"]["identifiable"]:
            values[f"{plant[0]}.tyre_shape"] = tyre["parameters"]["shape"]["value"]
        if "friction_ratio" in tyre["parameters"]:      # identification.axle_friction: the friction is the front's
            values[f"{plant[0]}.tyre_friction_ratio"] = tyre["parameters"]["friction_ratio"]["value"]
    if left_out:
        report["extended_study_left_out"] = left_out
    if not values:
        return None
    text = study.extension_toml(values, f"identified from {source} by `python -m agrobot identify`")
    atomic_write(Path(out_dir) / "extended_study.toml", lambda p: p.write_text(text))
    return "extended_study.toml"
