"""``diagnose``: log + baseline study -> DIR/diagnosis.json, DIR/report.md (+ plots) and, when an
extension wins and the study has its component, DIR/extended_study.toml that switches it on."""
from __future__ import annotations

import math
from functools import partial
from pathlib import Path

import numpy as np

from agrobot.estimation import REPORTED_AT_BOUND
from agrobot.identification.blas_threads import one_blas_thread
from agrobot.identification.from_log import finite_for_json, read_uneven, recorded_wheelbase
from agrobot.identification.ordinary_driving import held_out_misfit, identify_driving
from agrobot.identification.skid_steer import why_not_diagnosed
from agrobot.identification.vehicle import Vehicle
from agrobot.identification.yaw_measurement import with_yaw_rate
from agrobot.measurements import LogError
from agrobot.measurements.audit import require_causal
from agrobot.measurements.modes import WhereError
from agrobot.measurements.recording import ImportOptions
from agrobot.orchestrator.atomic_files import atomic_write, write_json
from agrobot.orchestrator.errors import InputError
from agrobot.orchestrator.study import load_study
from agrobot.studies import shipped

from .baseline import (baseline_from_study, fixed_geometry, geometry_choice, identify_note, refit_statement,
                       refit_summary, replay_slip_share, with_geometry)
from .candidates import CannotDecide, FitResult, Replay, uncertain
from .effects.tyre_saturation import friction_text
from .catalogue import DISPLAY, SIGNALS, shown
from .evidence import stage_evidence
from .mcap import write_diagnosis_mcap
from .noise_floor import held_out_noise
from .report import binned_figure, floors_figure, markdown, stage_figure
from .parallel_fits import ParallelSelector, default_workers
from .selection import Finding
from .shared_quantities import diagnosis_side, identify_side, shared_quantities
from .unexplained import RATIO, signature, stage_check
from .plausibility import (VehicleContext, beyond_limits, cannot_do, kinematic, steering_gain_check,
                           study_understeer, understeer, understeer_estimates)
from .study_fit import study_check, suggestion
from .vehicle_limits import StudyLimits, log_extremes, shipped_limits
from .verdict import audit_findings, conclude, on_bounded_baseline, said_before

REFIT = ("steering_time_constant", "cornering_front_scale", "cornering_rear_scale", "relaxation_scale")

DEFAULT_STUDY = shipped("figure8.toml")
CANNOT_DECIDE = "cannot decide"


def _study_options(finding: Finding, baseline) -> list[tuple[str, str, float]]:
    """(component, parameter, SI value) that switch the finding's effect on in the study."""
    out = []
    for role, name, value in finding.effect.options(finding.fit.values, baseline.values, baseline.study):
        comp = baseline.components.get(role)
        if comp is None:
            raise KeyError(role)
        out.append((comp, name, float(value)))
    return out


def finding_json(f: Finding, baseline, inconclusive: list[dict] = ()) -> dict:
    """The one JSON shape of a judged effect, whether it is in the final model (``effects``,
    judged by its drop-one comparison) or tried alone against the baseline (``findings``):
    every fitted parameter with its value, standard deviation, 95 % interval and the bounds it
    was searched in, so that anyone can see how far it is from them."""
    try:
        options = _study_options(f, baseline)
        option_text = ", ".join(f"components.{c}.parameters.{n} = {v:.6g}" for c, n, v in options)
    except KeyError as missing:
        what = missing.args[0]
        options, option_text = None, (f"(no study option carries this: {what})" if " " in what else
                                      f"(the study has no {what} component to carry this option)")
    signals = ", ".join(f"{k} {DISPLAY[s][0] * f.rmse_before[k]:.4g} -> {shown(s, f.rmse_after[k], 4)}"
                        for s in f.stages for k in [SIGNALS[s][0]])
    fitted_text = ", ".join(f"{k} = {v:.4g}" for k, v in f.effect.display(f.fit.values).items())
    fitted = {}
    for p in f.effect.parameters:
        value, sd = f.fit.values[p.name], f.fit.std(p.name)
        fitted[p.name] = {"value": value, "std": sd, "interval": [value - 1.96 * sd, value + 1.96 * sd],
                          "bounds": [p.lower, p.upper], "unit": p.unit, "at_bound": at_bound(value, p),
                          "secondary": p.name in f.effect.secondary}
    return {
        "id": f.effect.id,
        "subsystem": f.effect.subsystem,
        "hypothesis": f.effect.hypothesis_for(f.stages),
        "parameters": {p.name: f.fit.values[p.name] for p in f.effect.parameters},
        "parameters_display": f.effect.display(f.fit.values),
        "fitted": fitted,
        "delta_bic": f.delta_bic,
        "held_out_gain": f.gain,
        "gain_by_signal": f.gain_by_signal,
        "rmse_before": f.rmse_before,
        "rmse_after": f.rmse_after,
        "residual_by_stage": {s: {"rms_without": f.rmse_before[SIGNALS[s][0]], "rms_with": f.rmse_after[SIGNALS[s][0]],
                                  "unit": SIGNALS[s][1]} for s in f.stages},
        "supported": f.supported,
        "reasons": f.reasons,
        "material": f.material,
        "materiality": f.effect.threshold,
        "n_eff": f.fit.n_eff,
        "refit_baseline": {k: f.fit.values[k] for k in REFIT if k in f.fit.values},
        "study_option": option_text,
        "summary": (f"{f.effect.id} in the {f.effect.subsystem}: {f.effect.hypothesis_for(f.stages)}. Fitted {fitted_text}; "
                    f"held-out RMS {signals}; dBIC {f.delta_bic:.0f}."),
        "inconclusive_with": [t["effects"][1] for t in inconclusive if t["effects"][0] == f.effect.id],
        "_options": options,
    }


def at_bound(value: float, p) -> str | None:
    """'lower' or 'upper' when a fitted value ends within 0.5 % of the searched range of a bound."""
    return p.at_bound(value, REPORTED_AT_BOUND)


def _warnings(replay: Replay, base: FitResult, floors: dict) -> list[str]:
    """What makes a verdict on this log fragile."""
    out = [f"the {stage} stage is {why}" for stage, why in replay.not_judged.items()]
    if replay.not_judged:
        out.append(f"the log's columns: {', '.join(map(str, replay.frame.columns))}")
    if replay.speed_source != "v" and set(replay.stages) & {"yaw", "position"}:
        out.append({"gnss_speed": "no wheel speed v: the yaw and position replays run on the receiver's speed over ground",
                    "track": "no speed column: the yaw replay runs on the speed of the GPS track"}[replay.speed_source])
    duration = replay.t[-1] - replay.t[0]
    if duration < 180:
        held = float(replay.masks["steering"]["test"].sum()) * replay.h
        out.append(f"the log lasts {duration:.0f} s: with {held:.0f} s held out, "
                   f"small effects cannot be confirmed (record at least 180 s, better 400 s)")
    asked = replay.commanded_yaw() if "steering" in replay.stages else math.inf
    if asked < 0.05:               # 2 deg of steering at 2 m/s on the paper tractor
        out.append(f"little steering excitation: delta_cmd varies by {math.degrees(float(np.std(replay.cmd))):.2g} deg "
                   f"(std), asking for {math.degrees(asked):.3g} deg/s of yaw rate; steering and yaw effects need turns and steps "
                   f"(several degrees on a tractor)")
    moving = replay.speed[replay.speed > replay.min_speed]
    spread = float(np.percentile(moving, 90) - np.percentile(moving, 10)) if len(moving) else 0.0
    if spread < 0.5:
        out.append(f"the speed hardly varies (10-90% spread {spread:.2f} m/s): speed-dependent effects "
                   f"(cornering stiffness, GPS latency against antenna position) cannot be told apart")
    for stage, column in (("steering", replay.delta), ("yaw", replay.gyro)):
        if stage not in replay.stages:
            continue
        mask = replay.masks[stage]["test"]
        spread = float(np.std(column[mask]))
        if spread < 3 * floors[stage]:
            out.append(f"the {SIGNALS[stage][0]} signal is mostly noise: std {spread:.3g} against a noise floor of "
                       f"{floors[stage]:.3g} {SIGNALS[stage][1]}")
        elif base.rmse_test[stage] > 0.9 * spread:
            out.append(f"the baseline explains almost none of {SIGNALS[stage][0]}: held-out RMS "
                       f"{shown(stage, base.rmse_test[stage])} against a signal std of {shown(stage, spread)}; "
                       f"check the study and the log's columns")
    return out


def _unexplained(checks: dict) -> dict | None:
    misfit = [c for c in checks.values() if c["misfit"]]
    if not misfit:
        return None
    worst = max(misfit, key=lambda c: c["ratio"])
    xc = worst["correlates_with"]
    ext = worst["extension"]
    gain = ext["held_out_gain"]
    outcome = (f"takes {100 * gain:.0f}% off the held-out RMS" if gain >= 0.05 else
               f"does not carry over to the held-out part ({100 * gain:+.0f}% on its RMS): the misfit is not a "
               f"fixed function of one signal; extend the model by physics or record the conditions it happens in")
    sig = signature(ext)
    reading = (f"; its form: {sig['physical']}; the run that would tell: {sig['experiment']}" if gain >= 0.05 else
               f"; the run that would tell: {sig['experiment']}")
    summary = (f"the {worst['stage']} stage stays {worst['ratio']:.1f} x its noise floor after the catalogued effects "
               f"(excess {shown(worst['stage'], worst['excess'])}); its residual correlates with {xc['signal']} "
               f"(rho {xc['rho']:.2f}); a data-driven {ext['kind']} on {ext['signal']}, fitted on the training part, "
               f"{outcome}{reading}")
    return {"id": "unexplained", "stage": worst["stage"], "stages": [c["stage"] for c in misfit], "signature": sig,
            "ratio_to_floor": worst["ratio"], "correlates_with": xc, "extension": ext,
            "held_out_gain": ext["held_out_gain"], "by_stage": {c["stage"]: c for c in misfit}, "summary": summary}


def identified_vehicle(frame, where: str, study, baseline, unseen=None, wheelbase: float | None = None,
                       geometry: str = "auto") -> dict:
    """The vehicle ``identify`` fits on this log (identification.ordinary_driving) beside the
    study's: understeer gradient K = (C_r l_r - C_f l_f) m / (C_f C_r L) (the same as (1/c_f -
    1/c_r)/g per unit load), cornering stiffnesses, delay; the identification's final model, its
    held-out fit and its independent estimates (identification.comparisons); ``unseen(t)``: the
    samples the diagnosis holds out, where both models are scored (held_out_misfit); ``wheelbase``:
    the one given with the recording (--wheelbase), as ``identify`` takes it (wheelbase_of); ``geometry``:
    the steering geometry identify fits under (auto: its choice, in ``steering_geometry``)."""
    p = baseline.tractor
    L = p.l_f + p.l_r
    ours = {"understeer_gradient": study_understeer(p),
            "cornering_stiffness_front": p.C_f, "cornering_stiffness_rear": p.C_r,
            "delay": baseline.values.get("command_delay", 0.0), "wheelbase": L}
    try:
        require_causal(frame, where)              # identify refuses a response leading its input
        rep = identify_driving(frame, where, study, wheelbase=wheelbase, geometry=geometry)
    except (InputError, LogError) as exc:          # NotEnoughDriving is an InputError
        return {"study": ours, "identified": None, "why_not": str(exc)}
    tyre = rep["tyre_saturation"]
    mine = {"understeer_gradient": rep["understeer_gradient"], "delay": rep["delay"],
            "cornering_stiffness_front": rep["cornering_stiffness"]["front"],
            "cornering_stiffness_rear": rep["cornering_stiffness"]["rear"],
            "held_out_fit": rep["held_out_fit"]["value"], "final_model": rep["final_model"],
            "tyre_saturation": ({"friction": tyre["parameters"]["friction"]["value"],
                                 "friction_at_least": bool(tyre["parameters"]["friction"].get("at_least")),
                                 "shape": tyre["parameters"]["shape"]["value"],
                                 "friction_ratio": tyre["parameters"].get("friction_ratio", {"value": 1.0})["value"],
                                 "held_out_gain": tyre["held_out_gain"]} if tyre["found"] else None),
            "tyre_saturation_why_not": tyre["why_not"], "input": rep["input"],
            "parameters": {k: {"value": q["value"], "interval": q.get("interval"), "unit": q["unit"]}
                           for k, q in rep["parameters"].items()},
            "held_out_yaw": held_out_misfit(rep, unseen) if unseen is not None else None,
            "shared": identify_side(rep), "steering_geometry": rep.get("steering_geometry"),
            "steering_geometry_note": identify_note(rep)}
    return {"study": ours, "identified": mine, "comparisons": rep.get("comparisons", []),
            "physical_checks": rep.get("physical_checks", {})}


def same_stretches(identified: dict, replay, values: dict[str, float]) -> None:
    """The diagnosis's final model scored on the stretches where identify's model was scored
    (identify's held-out segments after the diagnosis's split: neither fit saw them): the gyro's RMS
    misfit of each model there, in ``identified["held_out_yaw"]``."""
    held = (identified or {}).get("held_out_yaw")
    if not held or "yaw" not in replay.stages:
        return
    t, r = replay.residual_series("yaw", values)
    inside = np.zeros(len(t), bool)
    for a, b in held["windows"]:
        inside |= (t >= a) & (t <= b)
    held["diagnosis_rms"] = float(np.sqrt(np.mean(r[inside] ** 2))) if inside.sum() >= 10 else float("nan")


def agreement(identified: dict, effects: list[dict], sel, min_gain: float = 0.05, floor: float = 0.0,
              held_part: str = "the log's last part") -> list[str]:
    """Where identify and diagnose, on one log, conclude differently, and why: about an effect both
    model (tyre saturation; identify's held-out segments are spread over the log, the diagnosis
    holds out ``held_part``), and about the vehicle itself: when one model of it leaves materially
    less of the gyro unexplained than the other on the same unseen stretches (and the poorer is a
    misfit, above RATIO x the yaw stage's noise ``floor``), the poorer one's verdict is relative to a
    model that misses what the better one has."""
    if not identified:
        return []
    out = []
    ids = {e["id"] for e in effects}
    sat = identified.get("tyre_saturation")
    if sat and "tyre_saturation" not in ids:
        tried = next((f for f in sel.first_step if f.effect.id == "tyre_saturation"), None)
        why = ("; ".join(tried.reasons) or f"supported on its own (dBIC {tried.delta_bic:.1f}, held-out gain "
               f"{100 * tried.gain:.0f} %) but not kept beside the effects chosen") if tried else "it was not fitted"
        out.append(f"identify keeps tyre saturation (friction {friction_text(sat)}, held-out gain "
                   f"{100 * sat['held_out_gain']:.0f} % on segments spread over the log); the diagnosis, judged on "
                   f"{held_part}, does not: {why}")
    if not sat and "tyre_saturation" in ids:
        out.append("the diagnosis finds tyre saturation where identify does not keep it: "
                   + "; ".join(identified.get("tyre_saturation_why_not") or ["-"]))
    held = identified.get("held_out_yaw") or {}
    mine, theirs = held.get("rms", math.nan), held.get("diagnosis_rms", math.nan)
    if not (math.isfinite(mine) and math.isfinite(theirs)):
        return out
    k = DISPLAY["yaw"][0]
    where = (f"on the {held['seconds']:.0f} s of identify's held-out segments inside the diagnosis's held-out "
             f"part ({held_part}), which neither fit saw")
    if min(mine, theirs) >= (1 - min_gain) * max(mine, theirs) or max(mine, theirs) <= RATIO * floor:
        if out:                     # an effect concluded differently: the two models still fit alike
            out[-1] += (f"; yet the two models of this vehicle fit alike {where} (yaw rate RMS {k * mine:.3g} deg/s "
                        f"identify's, {k * theirs:.3g} deg/s the diagnosis's): the difference is in the stretches "
                        f"each judges on, not in the vehicle")
    else:
        if mine < theirs:
            params = identified.get("parameters") or {}
            def shown_value(q: dict) -> str:          # degrees at the edge, no unit for a ratio
                f, unit = {"rad": (180 / math.pi, " deg"), "rad/s": (180 / math.pi, " deg/s"),
                           "1": (1.0, "")}.get(q["unit"], (1.0, " " + q["unit"]))
                return f"{f * q['value']:.3g}{unit}"
            named = ", ".join(f"{n} {shown_value(q)}" for n, q in params.items()
                              if n in ("steer_gain", "delay", "lag", "steer_offset", "friction", "shape", "gyro_bias"))
            out.append(f"the vehicle model identify fits ({identified['final_model']}; {named}) leaves "
                       f"{k * mine:.3g} deg/s of the yaw rate unexplained {where}, the diagnosis's final model "
                       f"{k * theirs:.3g} deg/s: this vehicle is better described by identify's model, and what the "
                       f"diagnosis names (or leaves unexplained) is relative to a baseline that lacks part of it: put "
                       f"identify's stiffnesses, delay and steering gain into the study's yaw plant and diagnose again")
        else:
            out.append(f"the diagnosis's final model leaves {k * theirs:.3g} deg/s of the yaw rate unexplained {where}, "
                       f"the vehicle model identify fits {k * mine:.3g} deg/s: the effects named here describe this "
                       f"vehicle beyond what identify's single-track model holds")
    return out


def explained_findings(audit: list[dict], effects: list[dict], tolerance: float = 0.05) -> list[dict]:
    """The audit's findings with a response leading its input resolved where the diagnosis names
    the steering channels' clock at least that late (the clock = the lead + the vehicle's own
    delay): the recording explained, what it imitates is judged again."""
    clock = next((e["parameters"]["steering_clock"] for e in effects if e["id"] == "steering_clock"), None)
    for f in audit:
        if f["kind"] == "response_leads_input" and not f["resolved"] and clock is not None \
                and isinstance(f.get("value"), (int, float)) and clock >= f["value"] - tolerance:
            f["resolved"] = True
            f["meaning"] = (f"{f.get('meaning') or ''}; explained by the diagnosis: the steering channels stamped "
                            f"{clock:.3f} s late (steering_clock), {clock - f['value']:+.3f} s of it the vehicle's "
                            f"own delay").lstrip("; ")
    return audit


def held_part(replay) -> str:
    """The diagnosis's held-out part in words."""
    if replay.split == "tail":
        return f"the log's last {100 * (1 - replay.fit_fraction):.0f} %, t >= {replay.t_split:.1f} s"
    return f"every third {replay.window:.0f} s of the log"


LONG_LOG = 600.0          # s: beyond this a log faster than COARSE_RATE is averaged down to it (cost)
COARSE_RATE = 10.0       # Hz: the rate the steering and yaw stages need (MIN_RATE): every replay's cost grows
                         # with the samples, and a long log has the turns and speeds to judge at that rate


def coarser_clock(frame):
    """(frame, note): a long fast log averaged over blocks of k samples to at most COARSE_RATE
    (the cost of every replay grows with the samples; the dynamics judged live below 5 Hz)."""
    t = frame["t"].to_numpy(float)
    if len(t) < 3 or t[-1] - t[0] <= LONG_LOG:
        return frame, None
    rate = 1.0 / float(np.median(np.diff(t)))
    k = int(rate // COARSE_RATE)
    if k < 2:
        return frame, None
    n = len(frame) // k * k
    numeric = frame.select_dtypes("number").iloc[:n]
    out = numeric.groupby(np.arange(n) // k).mean().reset_index(drop=True)
    out.attrs = dict(frame.attrs)
    return out, (f"the log lasts {t[-1] - t[0]:.0f} s at {rate:.3g} Hz: averaged over blocks of {k} samples to "
                 f"{rate / k:.3g} Hz to bound the cost (steering time constants below 0.1 s are not resolved)")


def diagnose(log_path: str | Path, out_dir: str | Path | None, study_path: str | Path | None = None,
             fit_fraction: float = 0.6, min_gain: float = 0.05, plots: bool = True, resample: bool = False,
             recording=None, progress=None, identify: bool = True, mcap: bool = False, split: str = "auto",
             workers: int | None = None, screen: bool = True, steering_geometry: str = "auto") -> dict:
    """``diagnosis`` written into the existing folder ``out_dir`` when given (a caller that has
    already placed its output: the commands go through agrobot.api, which stages it)."""
    result, write = diagnosis(log_path, study_path, fit_fraction, min_gain, plots, resample, recording, progress,
                              identify, mcap, split, workers, screen, steering_geometry)
    if out_dir is not None:
        write(Path(out_dir))
    return result


@one_blas_thread
def diagnosis(log_path: str | Path, study_path: str | Path | None = None, fit_fraction: float = 0.6,
              min_gain: float = 0.05, plots: bool = True, resample: bool = False, recording=None, progress=None,
              identify: bool = True, mcap: bool = False, split: str = "auto", workers: int | None = None,
              screen: bool = True, steering_geometry: str = "auto"):
    """Run the diagnosis; returns (result, write), nothing written: ``write(folder)`` writes
    diagnosis.json and report.md (verdict ``cannot decide`` with the reason when the log cannot be
    used), and the figures and extended_study.toml. Raises nothing for a bad log; a ``--where``
    that does not fit it (measurements.modes.WhereError) is a usage error, raised.
    ``identify``: identify the vehicle on the same log first (the model ``identify`` fits); ``mcap``:
    ``write`` adds diagnosis.mcap; ``split``: what is held out (diagnosis.candidates.SPLITS: the last
    part, every third window, or chosen by the log's conditions); ``workers``: processes for the candidate
    fits (diagnosis.parallel_fits; None: every core), the result the same whatever their number; ``screen``:
    pairs of effects whose linearised gain cannot be supported are not fitted (diagnosis.screen);
    ``steering_geometry``: auto, w or tan (diagnosis.baseline.fixed_geometry)."""
    default_study = not study_path
    study_path = Path(study_path) if study_path else DEFAULT_STUDY
    result: dict = {"log": str(log_path), "study": str(study_path), "verdict": CANNOT_DECIDE, "effects": [],
                    "findings": []}
    try:
        study, baseline, frame, replay, note = _replay_of(log_path, study_path, result, fit_fraction, resample,
                                                          recording, split, default_study)
    except WhereError:                            # a --where that does not fit the log: usage, nothing written
        raise
    except (LogError, CannotDecide) as exc:
        reason = str(exc)                         # a LogError names the file already; a replay's refusal does not
        result["reason"] = reason if str(log_path) in reason else f"{log_path}: {reason}"
        result["split_time"] = float("nan")
        return result, partial(_write, result=result, plots=[])
    say = progress or (lambda text: None)
    fixed = fixed_geometry(steering_geometry, baseline)
    baseline, replay = _under_geometry(baseline, replay, frame, fixed[0], fit_fraction, split)
    wheelbase = recorded_wheelbase(Path(log_path), getattr(recording, "wheelbase", None))
    if wheelbase is not None:
        say(f"wheelbase {wheelbase[0]:.4g} m for the identification on the same log: {wheelbase[1]}")
    mismatch = _vehicle_of_log(result, replay, frame, study, baseline, study_path.name, default_study,
                               identify, log_path, say, wheelbase and wheelbase[0], fixed[0] or "auto")
    identified = result.get("identified_vehicle", {}).get("identified") or {}
    choice = result["steering_geometry"] = geometry_choice(baseline, *fixed, identified.get("steering_geometry"),
                                                           identified.get("steering_geometry_note", ""))
    say(choice["says"])
    baseline, replay = _under_geometry(baseline, replay, frame, choice["value"], fit_fraction, split)
    say(f"replaying {len(replay.t)} samples ({replay.t[-1] - replay.t[0]:.0f} s); stages {', '.join(replay.stages)}; "
        f"held out: {held_part(replay)}")
    if replay.split_note:
        say(replay.split_note)
    if replay.side_slip_note():
        say(replay.side_slip_note())
    workers = default_workers() if workers is None else max(1, int(workers))
    say(f"candidate fits on {workers} worker process{'es' if workers > 1 else ''} (--workers)")
    sel = ParallelSelector(replay, min_gain, seed=study.study.seed, saturation=identified.get("tyre_saturation"),
                           progress=say, workers=workers, screen=screen).run()
    say("effects selected; judging the stages against their noise floors")
    final, floors = sel.final, sel.floors
    checks = {s: stage_check(replay, s, final.values, floors, math.sqrt(final.rss[s] / final.n[s]), final.rmse_test[s])
              for s in replay.stages}
    _describe_selection(result, replay, sel, study.study.seed)
    effects, options, unidentifiable = _judged_effects(sel, baseline)
    unexplained = _unexplained(checks)
    result["effects"] = effects + ([unexplained] if unexplained else [])
    result["not_identifiable"] = [{"id": e["id"], "why": f"not identifiable from this log: {e['not_identifiable']}"}
                                  for e in unidentifiable]
    result["audit"] = explained_findings(audit_findings(replay.frame.attrs), effects)
    _conclude(result, replay, baseline, sel, effects, unexplained, unidentifiable, identified, min_gain)
    result["inconclusive"] = sel.inconclusive
    result["selection_trace"] = sel.trace
    result["warnings"] = _warnings(replay, sel.base, floors) + ([note] if note else []) + (
        [replay.split_note] if replay.split_note else []) + [n["text"] for n in result["held_out_noise"].values()]
    if mismatch:
        result["warnings"].insert(0, mismatch)
    if result.get("study_limits", {}).get("statement"):
        result["warnings"].insert(0, result["study_limits"]["statement"])
    elif result.get("study_limits", {}).get("noted"):
        result["warnings"].insert(0, result["study_limits"]["noted"])
    _stage_results(result, replay, sel, checks, effects, baseline)
    return result, partial(_write_all, result=result, replay=replay, sel=sel, study=study, options=options,
                           log_path=log_path, plots=plots, say=say, mcap=mcap)


def _replay_of(log_path, study_path: Path, result: dict, fit_fraction: float, resample: bool, recording, split: str,
               default_study: bool = False):
    """(study, baseline, frame, replay, note): the study's baseline and the log read for its vehicle
    (a recording with the study's steering ratio and wheelbase; a clock with gaps cut to its longest
    stretch; a long fast log averaged down, coarser_clock), replayed; ``note`` says what was changed.
    Raises LogError or CannotDecide."""
    study = load_study(study_path)
    baseline = baseline_from_study(study)
    recording = (recording or ImportOptions()).for_vehicle(study)     # the study's steering ratio, wheelbase
    # a response leading its input is not refused here: its finding is judged as a candidate (steering_clock)
    frame, imported, stretch = read_uneven(Path(log_path), resample, recording, study, causal=False)
    if imported is not None:
        result["recording"] = imported
    if why_not_diagnosed(frame, Vehicle.of(study)):          # no steering angle: not the catalogue's vehicle
        raise CannotDecide(why_not_diagnosed(frame, Vehicle.of(study)))
    frame, measured = with_yaw_rate(frame, str(log_path))       # no gyro: the yaw rate from a heading or course
    if measured is not None:
        result["yaw_measurement"] = measured.as_dict()
    frame, note = coarser_clock(frame)
    said = measured.text if measured is not None and measured.kind != "gyro" else None
    note = "; ".join(x for x in (stretch, note, said) if x) or None
    try:
        replay = Replay(frame, baseline, fit_fraction=fit_fraction, split=split)
    except CannotDecide:
        _said_before_refusal(result, frame, baseline, study_path.name, default_study)
        raise
    return study, baseline, frame, replay, note


def _under_geometry(baseline, replay, frame, geometry: str | None, fit_fraction: float, split: str):
    """(baseline, replay) with the yaw model driven under ``geometry`` (None: as they are); replayed
    again only when it changes."""
    if geometry is None or geometry == baseline.steering_geometry:
        return baseline, replay
    baseline = with_geometry(baseline, geometry)
    return baseline, Replay(frame, baseline, fit_fraction=fit_fraction, split=split)


def _said_before_refusal(result: dict, frame, baseline, study_name: str, default_study: bool) -> None:
    """A log too short or too still to judge still says what comes before any verdict: the log's turns
    not being the study's vehicle (study_check), the study's limits it exceeds (the default study
    matched on the log alone, as _vehicle_of_log does), the class's default outline (verdict.said_before)."""
    p = baseline.tractor
    result["log_vehicle"], mismatch = study_check(frame, p.l_f + p.l_r, study_name, study_understeer(p),
                                                  None if default_study else baseline.vehicle, p.m)
    if mismatch and default_study:
        mismatch += " (no --study given: the default study was used)"
    beyond = _study_limits(result, frame, baseline, study_name, default_study, lambda text: None)
    result["before_verdict"] = said_before([x for x in (beyond, mismatch) if x],
                                           VehicleContext(baseline.vehicle, p.l_f + p.l_r, p.l_r, 0.0), result["log_vehicle"])


def _vehicle_of_log(result: dict, replay: Replay, frame, study, baseline, study_name: str, default_study: bool,
                    identify: bool, log_path, say, wheelbase: float | None = None, geometry: str = "auto") -> str | None:
    """The log's own vehicle against the study's (``log_vehicle``; the mismatch warning returned, or
    None) and, with ``identify`` and a yaw stage, the vehicle identify fits on the log
    (``identified_vehicle``; on the ``wheelbase`` given with the recording, else the study's)."""
    result["log_vehicle"], mismatch = study_check(replay.frame, baseline.tractor.l_f + baseline.tractor.l_r,
                                                  study_name, study_understeer(baseline.tractor),
                                                  None if default_study else baseline.vehicle, baseline.tractor.m)
    if result["log_vehicle"] is not None:         # the user's word on the wheelbase: a study given, with a [vehicle]
        result["log_vehicle"]["declared"] = not default_study and baseline.vehicle.declared
    if mismatch:
        mismatch += " (no --study given: the default study was used)" if default_study else ""
        say(f"warning: {mismatch}")
    _study_limits(result, replay.frame, baseline, study_name, default_study, say)
    if identify and "yaw" in replay.stages:
        say("identifying the vehicle on the same log (the model identify fits)")
        result["identified_vehicle"] = identified_vehicle(frame, str(log_path), study, baseline, replay.unseen,
                                                            wheelbase, geometry)
    return mismatch


def _study_limits(result: dict, frame, baseline, study_name: str, default_study: bool, say) -> str | None:
    """The log's figures against the study's vehicle's limits (``study_limits``: vehicle_limits,
    plausibility.beyond_limits), what was compared said; returned: the statement that the study's
    vehicle cannot do what the log shows (plausibility.cannot_do, with a shipped study whose limits
    the log keeps within, study_fit.suggestion), None when the log stays within them."""
    extremes = log_extremes(frame)
    if extremes is None:
        return None
    limits, mine = StudyLimits.of(baseline), result.get("log_vehicle") or {}
    checked = beyond_limits(extremes, limits, mine["wheelbase"] / limits.wheelbase if mine.get("wheelbase") else None)
    result["study_limits"] = {"log": extremes, "study": {**vars(limits), "min_radius": limits.min_radius}, **checked}
    say(checked["compared"] + ("" if checked["beyond"] else
                               f": within them (against {study_name}; --study gives another vehicle's)"))
    if checked["noted"] and not checked["beyond"]:
        say(f"note: {checked['noted']}")
    if not checked["beyond"]:
        return None
    hint = suggestion(mine.get("wheelbase") or limits.wheelbase, study_name, None if default_study else baseline.vehicle,
                      baseline.tractor.m, partial(_unable, extremes))
    text = cannot_do(checked["beyond"], hint, not default_study and baseline.vehicle.declared, checked["undecided"]) + (
        " (no --study given: the default study was used)" if default_study else "")
    result["study_limits"]["statement"] = text
    say(f"warning: {text}")
    return text


def _unable(extremes: dict, c) -> str:
    """Why shipped study ``c``'s vehicle cannot do what the log shows ('' when it can)."""
    beyond = beyond_limits(extremes, shipped_limits(c.name))["beyond"]
    return "unable to do what the log shows: " + "; ".join(beyond) if beyond else ""


def _describe_selection(result: dict, replay: Replay, sel, seed: int = 0) -> None:
    """What the selection stood on: the split, the baseline's refitted values, each judged stage's
    noise level and floor, what its held-out gains are net of (the selection's ``seed``), the stages
    judged and those not."""
    judged = replay.stages
    result["split_time"] = replay.t_split if replay.split == "tail" else float("nan")
    result["split"] = {"kind": replay.split, "held_out": held_part(replay), "spans": replay.held_out_spans(),
                       "why": replay.split_note}
    result["baseline_refit"] = {k: sel.base.values[k] for k in REFIT}
    params = list(dict.fromkeys(p for s in judged for p in uncertain(replay, s)))
    result["baseline_refit_summary"] = refit_summary(replay.baseline.values, sel.base.values, params,
                                                     getattr(replay, "held_uncertain", ()))
    result["noise_level"] = {SIGNALS[s][0]: sel.sigma[s] for s in judged}
    result["noise_floor"] = {s: sel.floors[s] for s in judged} | {"sensors": sel.floors["_sensors"]}
    # what the held-out gains were judged net of: the measurement noise under the baseline (noise_floor.stage_floors)
    result["held_out_noise"] = {s: {"rms": math.sqrt(n.power), "band_hz": n.band, "gross_rms": math.sqrt(n.gross),
                                    "low_band_rms": math.sqrt(n.low), "least_explained_rms": math.sqrt(n.least),
                                    "text": n.text()}
                                for s, n in held_out_noise(replay, sel.base.values, seed).items()}
    result["stages_judged"] = list(judged)
    result["not_judged"] = dict(replay.not_judged)


def _judged_effects(sel, baseline) -> tuple[list[dict], list, list[dict]]:
    """(effects, study options, unidentifiable): the final model's effects as JSON (finding_json);
    a parameter that ends on its bound is not an answer: the effect is "not identifiable from this
    log" (unidentifiable), unless the parameter is secondary (then that value alone is noted)."""
    effects = [finding_json(f, baseline, sel.inconclusive) for f in sel.effects]
    options = [o for e in effects for o in (e.pop("_options") or [])]
    unidentifiable = [e for e in effects if any(p["at_bound"] and not p["secondary"] for p in e["fitted"].values())]
    for e in effects:                   # a secondary parameter on its bound: the effect stands, that value does not
        for n, p in e["fitted"].items():
            if p["at_bound"] and p["secondary"]:
                p["note"] = f"not identifiable from this log: ended on its {p['at_bound']} bound"
    for e in unidentifiable:
        bound = {n: p for n, p in e["fitted"].items() if p["at_bound"] and not p["secondary"]}
        e["not_identifiable"] = "; ".join(
            f"{n} ended on its {p['at_bound']} bound {p['bounds'][0 if p['at_bound'] == 'lower' else 1]:g} {p['unit']}"
            for n, p in bound.items())
    return effects, options, unidentifiable


def _conclude(result: dict, replay: Replay, baseline, sel, effects: list[dict], unexplained: dict | None,
              unidentifiable: list[dict], identified: dict, min_gain: float) -> None:
    """The verdict (diagnosis.verdict.conclude at the log's median moving speed), with the bullets
    of its agreement with identify's model and of every independent estimate that disagrees."""
    p = baseline.tractor
    moving = replay.speed[replay.speed > replay.min_speed]
    mine = result.get("log_vehicle") or {}
    mismatch, share = mine.get("mismatch"), replay_slip_share(replay)
    beyond = result.get("study_limits", {}).get("statement")
    mine = {**mine, "beyond_limits": beyond} if beyond else mine
    K = identified.get("understeer_gradient") if identified else None
    result["understeer_note"] = understeer(K, baseline.vehicle, share, mine or None) if K else kinematic(share)
    verdict = conclude(effects, unexplained, unidentifiable, sel.inconclusive, result["audit"], baseline.vehicle,
                       p.l_f + p.l_r, p.l_r, float(np.median(moving)) if len(moving) else 0.0,
                       antenna=(baseline.values["antenna_forward"], baseline.values["antenna_left"]),
                       before=[x for x in (beyond, mismatch, kinematic(share)) if x], turns=mine or None)
    verdict = on_bounded_baseline(verdict, result["baseline_refit_summary"])
    verdict["bullets"].append(refit_statement(result["baseline_refit_summary"]))
    if (gain := steering_gain_check(effects, mine)) is not None:
        verdict["bullets"].append(gain[0])
        if not gain[1] and verdict["id"] == "steering_gain" and verdict["status"] == "conclusive":
            verdict["status"], verdict["statement"] = "inconclusive", verdict["statement"] + "; but " + gain[0]
    same_stretches(identified, replay, sel.final.values)
    verdict["bullets"] += agreement(identified, effects, sel, min_gain, sel.floors.get("yaw", 0.0), held_part(replay))
    result["shared_quantities"] = shared_quantities((identified or {}).get("shared"),
                                                    diagnosis_side(effects, sel, replay, p))
    off_class(result, baseline.vehicle, mine or None)
    verdict["bullets"] += [q["line"] for q in result["shared_quantities"]]
    for c in result.get("identified_vehicle", {}).get("comparisons", []):
        if c.get("implausible") and not kinematic(share):
            verdict["bullets"].append(f"{c['quantity']}: implausible for the vehicle: {c['implausible']}")
        if not c["agree"] and c.get("concluded", True) and not (kinematic(share) and "understeer" in c["quantity"]):
            verdict["bullets"].append(f"{c['quantity']}: " + " against ".join(
                f"{m} {e['value']:.3g} [{e['interval'][0]:.3g}, {e['interval'][1]:.3g}]" for m, e in c["estimates"].items())
                + f" {c['unit']}: they disagree; {c['suggests']}")
    result["verdict"] = verdict["id"]
    result["verdict_status"] = verdict["status"]
    result["verdict_statement"] = verdict["statement"]
    result["verdict_bullets"] = verdict["bullets"]
    result["before_verdict"] = verdict["before"]


def off_class(result: dict, vehicle, turns: dict | None) -> None:
    """Every understeer gradient the result prints beside another (the shared quantities, identify's
    comparisons) flagged where it is not of the vehicle's class (plausibility.understeer_estimates):
    ``implausible`` with why, and the shared quantity's line says so."""
    for q in result.get("shared_quantities") or []:
        if "understeer" in q["quantity"] and (why := understeer_estimates(q["estimates"], vehicle, turns)):
            q["implausible"] = why
            q["line"] += "; implausible for the vehicle, not concluded: " + why
    for c in (result.get("identified_vehicle") or {}).get("comparisons") or []:
        if "understeer" in c["quantity"] and (why := understeer_estimates(c["estimates"], vehicle, turns)):
            c["implausible"] = why


def _stage_results(result: dict, replay: Replay, sel, checks: dict, effects: list[dict], baseline) -> None:
    """Each stage's judgement (stage_check, the baseline's held-out RMS, the RMS without each found
    effect; the stages not judged with why), its residual evidence under the baseline and the final
    model, and the findings of the selection's first step (each effect alone against the baseline)."""
    judged, base, final = replay.stages, sel.base, sel.final
    result["stages"] = {s: {**{k: v for k, v in checks[s].items() if k not in ("correlates_with", "extension", "whiteness")},
                            "rms_baseline_test": base.rmse_test[s],
                            "rms_without": {f.effect.id: f.rmse_before[SIGNALS[s][0]] for f in sel.effects if s in f.stages}}
                        for s in judged}
    result["stages"].update({s: {"stage": s, "judged": False, "reason": why} for s, why in replay.not_judged.items()})
    result["residuals"] = {s: stage_evidence(replay, s, base.values) for s in judged}
    if effects:
        result["extended_residuals"] = {s: stage_evidence(replay, s, final.values) for s in judged}
    items = [finding_json(f, baseline) for f in sel.first_step]
    for item in items:
        item.pop("_options", None)
    result["findings"] = items


def _write_all(out: Path, result: dict, replay: Replay, sel, study, options, log_path, plots: bool, say,
               mcap: bool = False) -> None:
    """The figures (each judged stage, the binned residuals, the noise floors), extended_study.toml
    when every effect found has a study option, then diagnosis.json and report.md (and
    diagnosis.mcap with ``mcap``)."""
    base, final, effects = sel.base, sel.final, result["effects"]
    found = [e for e in effects if e["id"] != "unexplained"]
    files = []
    if plots:
        say("figures")
        touched = {s for f in sel.effects for s in f.stages}
        for s in replay.stages:
            files.append(stage_figure(replay, s, base.values, final.values if s in touched else None,
                                      out / f"{s}.png", result["stages"][s]).name)
        files.append(binned_figure(replay, base.values, final.values if found else None, out / "binned.png").name)
        files.append(floors_figure(result, out / "noise_floors.png").name)
    if found and None not in [e["study_option"] for e in found] and options:
        result["extended_study"] = "extended_study.toml"
        text = study.extension_toml({f"{c}.{name}": value for c, name, value in options},
                                    f"{' + '.join(e['id'] for e in found)} found by "
                                    f"`python -m agrobot diagnose {log_path}`")
        atomic_write(out / "extended_study.toml", lambda p: p.write_text(text))
    _write(out, result, files)
    if mcap:
        say("diagnosis.mcap")
        write_diagnosis_mcap(replay, sel.base.values, sel.final.values, out / "diagnosis.mcap", str(log_path))


def _write(out: Path, result: dict, plots: list[str]) -> None:
    write_json(out / "diagnosis.json", finite_for_json(result))
    atomic_write(out / "report.md", lambda p: p.write_text(markdown(result, plots)))
