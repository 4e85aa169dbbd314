"""``diagnose``: log + baseline study -> DIR/diagnosis.json, DIR/report.md (+ plots) and, when an
extension wins and the study has its component, DIR/extended_study.toml that switches it on."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from measurements import LogError, load_log
from orchestrator.results import atomic_write, write_json
from orchestrator.study import load_study

from .baseline import baseline_from_study
from .candidates import STAGES, CannotDecide, Fit, Replay
from .catalogue import DISPLAY, SIGNALS, shown
from .evidence import stage_evidence
from .report import binned_figure, floors_figure, markdown, stage_figure
from .selection import Finding, select
from .unexplained import stage_check

REFIT = ("steering_time_constant", "cornering_front_scale", "cornering_rear_scale", "relaxation_scale")

DEFAULT_STUDY = Path(__file__).resolve().parent.parent / "studies" / "figure8.toml"
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


def _finding_json(f: Finding, baseline) -> dict:
    try:
        options = _study_options(f, baseline)
        option_text = ", ".join(f"components.{c}.parameters.{n} = {v:.6g}" for c, n, v in options)
    except KeyError as missing:
        options, option_text = None, f"(the study has no {missing.args[0]} component to carry this option)"
    signals = ", ".join(f"{k} {DISPLAY[s][0] * f.rmse_before[k]:.4g} -> {shown(s, f.rmse_after[k], 4)}"
                        for s in f.stages for k in [SIGNALS[s][0]])
    params = ", ".join(f"{k} = {v:.4g}" for k, v in f.effect.display(f.fit.values).items())
    summary = (f"{f.effect.id} in the {f.effect.subsystem}: {f.effect.hypothesis}. Fitted {params}; "
               f"held-out RMS {signals}; dBIC {f.delta_bic:.0f}.")
    return {
        "effect": f.effect.id,
        "subsystem": f.effect.subsystem,
        "params": {p.name: f.fit.values[p.name] for p in f.effect.parameters},
        "params_display": f.effect.display(f.fit.values),
        "rmse_before": f.rmse_before,
        "rmse_after": f.rmse_after,
        "gain": f.gain,
        "evidence": {
            "supported": f.supported,
            "reasons": f.reasons,
            "delta_bic": f.delta_bic,
            "gain_by_signal": f.gain_by_signal,
            "n_eff": f.fit.n_eff,
            "param_std": {k: v for k, v in f.fit.std.items() if k in {p.name for p in f.effect.parameters}},
            "materiality": f.effect.threshold,
            "material": f.material,
            "refit_baseline": {k: f.fit.values[k] for k in REFIT},
            "study_option": option_text,
            "summary": summary,
        },
        "_options": options,
    }


def _effect_json(f: Finding, baseline, inconclusive: list[dict]) -> dict:
    """One effect of the final model, judged by its drop-one comparison."""
    item = _finding_json(f, baseline)
    names = {p.name for p in f.effect.parameters}
    return {
        "id": f.effect.id,
        "subsystem": f.effect.subsystem,
        "hypothesis": f.effect.hypothesis,
        "parameters": {k: v for k, v in item["params"].items()},
        "parameters_display": item["params_display"],
        "std": {k: v for k, v in f.fit.std.items() if k in names},
        "delta_bic": f.delta_bic,
        "held_out_gain": f.gain,
        "residual_by_stage": {s: {"rms_without": f.rmse_before[SIGNALS[s][0]], "rms_with": f.rmse_after[SIGNALS[s][0]],
                                  "unit": SIGNALS[s][1]} for s in f.stages},
        "study_option": item["evidence"]["study_option"],
        "summary": item["evidence"]["summary"],
        "inconclusive_with": [t["effects"][1] for t in inconclusive if t["effects"][0] == f.effect.id],
        "_options": item["_options"],
    }


def _warnings(replay: Replay, base: Fit, floors: dict) -> list[str]:
    """What makes a verdict on this log fragile (issue 15, item 4)."""
    out = [f"the {stage} stage is {why}" for stage, why in replay.not_judged.items()]
    if replay.speed_source != "v" and set(replay.stages) & {"yaw", "position"}:
        out.append({"gnss_speed": "no wheel speed v: the yaw and position replays run on the receiver's speed over ground",
                    "track": "no speed column: the yaw replay runs on the speed of the GPS track"}[replay.speed_source])
    duration = replay.t[-1] - replay.t[0]
    if duration < 180:
        out.append(f"the log lasts {duration:.0f} s: with {duration * (1 - replay.fit_fraction):.0f} s held out, "
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
    summary = (f"the {worst['stage']} stage stays {worst['ratio']:.1f} x its noise floor after the catalogued effects "
               f"(excess {shown(worst['stage'], worst['excess'])}); its residual correlates with {xc['signal']} "
               f"(rho {xc['rho']:.2f}); a data-driven {ext['kind']} on {ext['signal']}, fitted on the training part, "
               f"{outcome}")
    return {"id": "unexplained", "stage": worst["stage"], "stages": [c["stage"] for c in misfit],
            "ratio_to_floor": worst["ratio"], "correlates_with": xc, "extension": ext,
            "held_out_gain": ext["held_out_gain"], "by_stage": {c["stage"]: c for c in misfit}, "summary": summary}


def diagnose(log_path: str | Path, out_dir: str | Path, study_path: str | Path | None = None,
             fit_fraction: float = 0.6, min_gain: float = 0.05, plots: bool = True, resample: bool = False,
             recording=None) -> dict:
    """Run the diagnosis; always writes diagnosis.json and report.md (verdict ``cannot decide``
    with the reason when the log cannot be used). Raises nothing for a bad log."""
    out = Path(out_dir)
    study_path = Path(study_path) if study_path else DEFAULT_STUDY
    result: dict = {"log": str(log_path), "study": str(study_path), "verdict": CANNOT_DECIDE, "effects": [],
                    "findings": []}
    try:
        study = load_study(study_path)
        baseline = baseline_from_study(study)
        from measurements.recording import ImportOptions

        recording = (recording or ImportOptions()).for_vehicle(study)     # the study's steering ratio, wheelbase
        frame, imported = load_log(log_path, resample_jitter=resample, recording=recording)
        if imported is not None:
            result["recording"] = imported
        replay = Replay(frame, baseline, fit_fraction=fit_fraction)
    except (LogError, CannotDecide) as exc:
        reason = str(exc)                         # a LogError names the file already; a replay's refusal does not
        result["reason"] = reason if str(log_path) in reason else f"{log_path}: {reason}"
        result["split_time"] = float("nan")
        _write(out, result, [])
        return result
    sel = select(replay, min_gain, seed=study.study.seed)
    base = sel.base
    final, floors = sel.final, sel.floors
    judged = replay.stages
    checks = {s: stage_check(replay, s, final.values, floors, math.sqrt(final.rss[s] / final.n[s]), final.rmse_test[s])
              for s in judged}
    result["split_time"] = replay.t_split
    result["baseline_refit"] = {k: base.values[k] for k in REFIT}
    result["noise_level"] = {SIGNALS[s][0]: sel.sigma[s] for s in judged}
    result["noise_floor"] = {s: floors[s] for s in judged} | {"sensors": floors["_sensors"]}
    result["stages_judged"] = list(judged)
    result["not_judged"] = dict(replay.not_judged)
    effects = [_effect_json(f, baseline, sel.inconclusive) for f in sel.effects]
    options = [o for e in effects for o in (e.pop("_options") or [])]
    unexplained = _unexplained(checks)
    result["effects"] = effects + ([unexplained] if unexplained else [])
    result["verdict"] = effects[0]["id"] if effects else ("unexplained" if unexplained else "none")
    result["inconclusive"] = sel.inconclusive
    result["selection_trace"] = sel.trace
    result["warnings"] = _warnings(replay, base, floors)
    result["stages"] = {s: {**{k: v for k, v in checks[s].items() if k not in ("correlates_with", "extension", "whiteness")},
                            "rms_baseline_test": base.rmse_test[s],
                            "rms_without": {f.effect.id: f.rmse_before[SIGNALS[s][0]] for f in sel.effects if s in f.stages}}
                        for s in judged}
    result["stages"].update({s: {"stage": s, "judged": False, "reason": why} for s, why in replay.not_judged.items()})
    result["residuals"] = {s: stage_evidence(replay, s, base.values) for s in judged}
    if effects:
        result["extended_residuals"] = {s: stage_evidence(replay, s, final.values) for s in judged}
    items = [_finding_json(f, baseline) for f in sel.first_step]
    for item in items:
        item.pop("_options", None)
    result["findings"] = items
    files = []
    if plots:
        touched = {s for f in sel.effects for s in f.stages}
        for s in judged:
            files.append(stage_figure(replay, s, base.values, final.values if s in touched else None,
                                      out / f"{s}.png", result["stages"][s]).name)
        files.append(binned_figure(replay, base.values, final.values if effects else None, out / "binned.png").name)
        files.append(floors_figure(result, out / "noise_floors.png").name)
    if effects and None not in [e["study_option"] for e in effects] and options:
        result["extended_study"] = "extended_study.toml"
        text = study.extension_toml({f"{c}.{name}": value for c, name, value in options},
                                    f"{' + '.join(e['id'] for e in effects)} found by "
                                    f"`python -m orchestrator diagnose {log_path}`")
        atomic_write(out / "extended_study.toml", lambda p: p.write_text(text))
    _write(out, result, files)
    return result


def _write(out: Path, result: dict, plots: list[str]) -> None:
    def clean(v):
        if isinstance(v, float) and not math.isfinite(v):
            return None
        if isinstance(v, dict):
            return {k: clean(x) for k, x in v.items()}
        if isinstance(v, list):
            return [clean(x) for x in v]
        return v
    write_json(out / "diagnosis.json", clean(result))
    atomic_write(out / "report.md", lambda p: p.write_text(markdown(result, plots)))
