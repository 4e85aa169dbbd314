"""``diagnose``: log + baseline study -> DIR/diagnosis.json, DIR/report.md (+ plots) and, when an
extension wins and the study has its component, DIR/extended_study.toml that switches it on."""
from __future__ import annotations

import math
from pathlib import Path

from measurements import LogError, read_log
from orchestrator.results import atomic_write, write_json
from orchestrator.study import load_study

from .baseline import baseline_from_study
from .candidates import STAGES, CannotDecide, Finding, Replay, assess_catalogue
from .catalogue import SIGNALS
from .evidence import stage_evidence
from .report import binned_figure, markdown, stage_figure

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
    signals = ", ".join(f"{k} {f.rmse_before[k]:.4g} -> {f.rmse_after[k]:.4g} {SIGNALS[s][1]}"
                        for s in f.effect.stages for k in [SIGNALS[s][0]])
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
            "refit_baseline": {k: f.fit.values[k] for k in ("steering_time_constant", "cornering_front_scale",
                                                           "cornering_rear_scale")},
            "study_option": option_text,
            "summary": summary,
        },
        "_options": options,
    }


def diagnose(log_path: str | Path, out_dir: str | Path, study_path: str | Path | None = None,
             fit_fraction: float = 0.6, min_gain: float = 0.05, plots: bool = True) -> dict:
    """Run the diagnosis; always writes diagnosis.json and report.md (verdict ``cannot decide``
    with the reason when the log cannot be used). Raises nothing for a bad log."""
    out = Path(out_dir)
    study_path = Path(study_path) if study_path else DEFAULT_STUDY
    result: dict = {"log": str(log_path), "study": str(study_path), "verdict": CANNOT_DECIDE, "findings": []}
    try:
        study = load_study(study_path)
        baseline = baseline_from_study(study)
        frame = read_log(log_path)
        replay = Replay(frame, baseline, fit_fraction=fit_fraction)
    except (LogError, CannotDecide) as exc:
        result["reason"] = str(exc)
        result["split_time"] = float("nan")
        _write(out, result, [])
        return result
    base, sigma, findings = assess_catalogue(replay, min_gain)
    result["split_time"] = replay.t_split
    result["baseline_refit"] = {k: base.values[k] for k in ("steering_time_constant", "cornering_front_scale",
                                                           "cornering_rear_scale")}
    result["noise_level"] = {SIGNALS[s][0]: sigma[s] for s in STAGES}
    items = [_finding_json(f, baseline) for f in findings]
    winner = items[0] if findings[0].supported else None
    result["verdict"] = winner["effect"] if winner else "none"
    result["residuals"] = {s: stage_evidence(replay, s, base.values) for s in STAGES}
    if winner:
        result["extended_residuals"] = {s: stage_evidence(replay, s, findings[0].fit.values)
                                        for s in findings[0].effect.stages}
    files = []
    if plots:
        for s in STAGES:
            extended = findings[0].fit.values if winner and s in findings[0].effect.stages else None
            files.append(stage_figure(replay, s, base.values, extended, out / f"{s}.png").name)
        winner_values = findings[0].fit.values if winner else None
        files.append(binned_figure(replay, base.values, winner_values, out / "binned.png").name)
    options = winner.pop("_options") if winner else None
    for item in items:
        item.pop("_options", None)
    result["findings"] = items
    if winner and options:
        result["extended_study"] = "extended_study.toml"
        text = study.extension_toml({f"{c}.{name}": value for c, name, value in options},
                                    f"{winner['effect']} found by `python -m orchestrator diagnose {log_path}`")
        atomic_write(out / "extended_study.toml", lambda p: p.write_text(text))
    _write(out, result, files)
    return result


def _write(out: Path, result: dict, plots: list[str]) -> None:
    clean = {k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in result.items()}
    write_json(out / "diagnosis.json", clean)
    atomic_write(out / "report.md", lambda p: p.write_text(markdown(result, plots)))
