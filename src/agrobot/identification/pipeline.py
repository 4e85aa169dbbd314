"""Section IV end to end: experiments -> FRF and nonlinearity analysis -> NLS fits -> physical
parameters -> time-domain validation -> speed dependence; JSON, plots and the paper's numbers.

Imported where used: identification.plots (matplotlib: only a run that draws figures or prints the summary loads it).
"""
from __future__ import annotations

import json
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
from scipy.signal import lsim

from agrobot.components.models import paper_models
from agrobot.components.models.yaw_dynamics import (PHYSICAL_MODELS, TractorParameters, controllable_canonical,
                                                    transfer_function)
from agrobot.measurements.recording import ImportOptions
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.atomic_files import write_json, write_table
from agrobot.orchestrator.study import Study

from . import frf as frf_mod
from .experiment import (Experiment, IdentificationConfig, config_of, experiment_from_log,
                         experiment_to_log, read_log, simulate_experiment)
from .fitting import Fit, fit
from .physical import rlfr_physical

PAPER = {
    "models": {name: {"num": list(tf.num), "den": list(tf.den)} for name, tf in paper_models.IDENTIFIED.items()},
    "rmse": paper_models.VALIDATION_RMSE,
    "physical": paper_models.PHYSICAL,
}


def starting_points(model: str, params: TractorParameters, speed: float) -> list[tuple]:
    """Extra NLS starts: the physical model with the given parameters at the experiment's speed,
    and the paper's identified model (when it has this structure)."""
    starts = []
    if model in PHYSICAL_MODELS:
        starts.append(transfer_function(model, params, speed))
    if model in PAPER["models"]:
        starts.append((PAPER["models"][model]["num"], PAPER["models"][model]["den"]))
    return starts


def analyse(exp: Experiment, models: list[str], delay: bool, params: TractorParameters, band=None) -> dict[str, Any]:
    result = frf_mod.analyse(exp.u, exp.y, exp.fs, exp.excited)
    sel = np.ones(len(result.freq), bool)
    if band is not None:
        sel = (result.freq >= band[0] - 1e-12) & (result.freq <= band[1] + 1e-12)
    var = result.var_fit[sel]
    fits = {m: fit(m, result.freq[sel], result.G[sel], var, delay, starting_points(m, params, exp.speed))
            for m in models}
    nl = {}
    for kind in ("odd", "even"):
        try:
            nl[f"{kind}_ratio"] = frf_mod.nonlinearity_ratio(result, kind)
        except ValueError:
            nl[f"{kind}_ratio"] = None
    nl["nonlinear_dominant_above_hz"] = frf_mod.nonlinear_dominant_above(result)
    return {"frf": result, "fits": fits, "nonlinearity": nl}


def simulate_fit(f: Fit, u: np.ndarray, fs: float) -> np.ndarray:
    """Output of the fitted continuous model for an input sampled at fs, linearly interpolated
    between samples (the measured steering angle is a sampled continuous signal)."""
    A, B, C = controllable_canonical(f.num, f.den)
    t = np.arange(len(u)) / fs
    _, y, _ = lsim((A, B.reshape(-1, 1), C.reshape(1, -1), np.zeros((1, 1))), u, t, interp=True)
    lag = int(round((f.delay or 0.0) * fs))
    if lag > 0:
        y = np.concatenate([np.zeros(lag), y[:-lag]])
    return y


def validation_rmse(f: Fit, exp: Experiment) -> float:
    """RMSE between the measured yaw rate and the model driven by the measured steering angle,
    over the steady-state part of every realisation."""
    errs = []
    for log in exp.full:
        y_model = simulate_fit(f, log["delta"].to_numpy(), exp.fs)
        errs.append(log["yaw_rate"].to_numpy()[exp.transient_samples:] - y_model[exp.transient_samples:])
    e = np.concatenate(errs)
    return float(np.sqrt(np.mean(e**2)))


def _c(z) -> list[list[float]]:
    return [[float(v.real), float(v.imag)] for v in np.atleast_1d(z)]


def frf_summary(r: frf_mod.FRF) -> dict[str, Any]:
    return {"freq_hz": r.freq.tolist(), "G_re": r.G.real.tolist(), "G_im": r.G.imag.tolist(),
            "var_total": r.var_total.tolist(), "var_noise": r.var_noise.tolist(), "var_nl": r.var_nl.tolist(),
            "var_fit": r.var_fit.tolist(),
            "realisations": r.realisations, "periods": r.periods}


def tractor_parameters(study: Study | None) -> TractorParameters:
    if study is None:
        return TractorParameters()
    model = resolve(study)
    return TractorParameters.of(model.parameters(model.one(role="yaw_plant", purpose="identification")))


def build_report(analyses: dict[float, dict], main_speed: float, validation: dict[str, Experiment],
                 params: TractorParameters, notes: list[str], source: str) -> dict[str, Any]:
    main = analyses[main_speed]
    models = {}
    for name, f in main["fits"].items():
        d = f.as_dict()
        d["validation_rmse"] = {band: validation_rmse(f, exp) for band, exp in validation.items()}
        models[name] = d
    if "rlfr" in main["fits"]:
        f = main["fits"]["rlfr"]
        sols = rlfr_physical(f.num, f.den, main_speed, params.m, params.l_f, params.l_r)
        models["rlfr"]["physical"] = {
            "known": {"m": params.m, "l_f": params.l_f, "l_r": params.l_r, "I": params.m * params.l_f * params.l_r},
            "solutions": [{k: (bool(v) if k == "equally_good" else float(v)) for k, v in s.items()} for s in sols],
            "several_fit_equally": sum(s["equally_good"] for s in sols) > 1}
    per_speed = {}
    for v, a in analyses.items():
        per_speed[f"{v:g}"] = {
            "nonlinearity": a["nonlinearity"],
            "models": {n: {"num": f.num.tolist(), "den": f.den.tolist(), "poles": _c(f.poles), "zeros": _c(f.zeros),
                           "cost": f.cost, "cost_expected": f.cost_expected} for n, f in a["fits"].items()},
            "frf": frf_summary(a["frf"])}
    return {"source": source, "notes": notes, "main_speed": main_speed, "models": models,
            "nonlinearity": main["nonlinearity"], "nonlinearity_wide": main.get("nonlinearity_wide"),
            "speeds": per_speed, "paper": PAPER}


def identify_study(study: Study, out_dir: Path | None, plots: bool = True) -> dict[str, Any]:
    """``study_identification`` written into the existing folder ``out_dir`` when given."""
    report, write = study_identification(study)
    if out_dir is not None:
        write(Path(out_dir), plots)
    return report


def study_identification(study: Study):
    """The identification of a study's simulated experiment: (report, write), nothing written;
    ``write(folder, plots)`` writes identification.json, the figures and experiment_log.csv."""
    cfg: IdentificationConfig = config_of(study)
    seed = study.study.seed
    params = tractor_parameters(study)
    analyses, experiments = {}, {}
    for i, v in enumerate(cfg.speeds):
        exp = simulate_experiment(study, cfg, v, cfg.band, cfg.kind, cfg.realisations, cfg.periods, seed + 101 * i)
        experiments[v] = exp
        analyses[v] = analyse(exp, cfg.models, cfg.delay, params)
    main = cfg.speeds[0]
    notes = []
    if cfg.detection_band is not None:
        wide = simulate_experiment(study, cfg, main, cfg.detection_band, cfg.kind,
                                   cfg.detection_realisations, cfg.periods, seed + 4099)
        wide_frf = frf_mod.analyse(wide.u, wide.y, wide.fs, wide.excited)
        analyses[main]["nonlinearity_wide"] = {
            "band_hz": list(cfg.detection_band), "odd_ratio": frf_mod.nonlinearity_ratio(wide_frf, "odd"),
            "even_ratio": frf_mod.nonlinearity_ratio(wide_frf, "even"),
            "nonlinear_dominant_above_hz": frf_mod.nonlinear_dominant_above(wide_frf)}
        analyses[main]["frf_wide"] = wide_frf
    validation = {}
    for j, band in enumerate(cfg.validation_bands):
        validation[f"{band[0]:g}-{band[1]:g}Hz"] = simulate_experiment(
            study, cfg, main, band, "full", 1, cfg.validation_periods, seed + 7919 * (j + 1))
    report = build_report(analyses, main, validation, params, notes, f"study {study.path}")
    return report, partial(_write_study, report=report, analyses=analyses, experiment=experiments[main])


def _write_study(out_dir: Path, plots: bool, report: dict, analyses: dict, experiment) -> None:
    write_outputs(report, analyses, out_dir, plots)
    write_table(Path(out_dir) / "experiment_log", experiment_to_log([experiment]), "csv")


def identify_log(path: Path, out_dir: Path | None, period: float | None = None, speed: float | None = None,
                 band=None, models=None, delay: bool = False, plots: bool = True,
                 resample: bool = False, recording=None, study: Study | None = None) -> dict[str, Any]:
    """``log_identification`` written into the existing folder ``out_dir`` when given."""
    report, write = log_identification(path, period, speed, band, models, delay, resample, recording, study)
    if out_dir is not None:
        write(Path(out_dir), plots)
    return report


def log_identification(path: Path, period: float | None = None, speed: float | None = None, band=None, models=None,
                       delay: bool = False, resample: bool = False, recording=None, study: Study | None = None):
    """Identification from a measured periodic experiment: (report, write), nothing written;
    ``write(folder, plots)`` writes identification.json and the figures. ``study``: the vehicle it
    comes from (its yaw plant's m, l_f, l_r, stiffnesses for the physical back-out and the starts;
    its [vehicle] table for reading a recording), else the paper's tractor."""
    params = tractor_parameters(study)
    frame, imported = read_log(path, resample, (recording or ImportOptions()).for_vehicle(study))
    exp = experiment_from_log(frame, str(path), period, speed, band)
    models = models or ["second_order", "bicycle", "rlf", "rlfr"]
    analyses = {exp.speed: analyse(exp, models, delay, params)}
    # time-domain check on the same log (a measured log rarely has a separate validation record)
    report = build_report(analyses, exp.speed, {"log": exp}, params, exp.notes, f"log {path}")
    if imported is not None:
        report["recording"] = imported
    return report, lambda folder, plots: write_outputs(report, analyses, folder, plots)


def write_outputs(report: dict, analyses: dict, out_dir: Path, plots: bool) -> None:
    out_dir = Path(out_dir)
    write_json(out_dir / "identification.json", json.loads(json.dumps(report, default=_json_default)))
    if plots:
        from .plots import write_plots

        write_plots(analyses, report["main_speed"], out_dir)


def _json_default(o):
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.bool_):
        return bool(o)
    raise TypeError(type(o))


def _hz_or(value, text: str) -> str:
    return f"{value:g} Hz" if value else text


def summary(report: dict) -> str:
    """Our coefficients and RMSE beside the paper's."""
    lines = [f"identification ({report['source']}), main speed {report['main_speed']:g} m/s"]
    lines += [f"  {n}" for n in report["notes"]]
    nl = report["nonlinearity"]
    lines.append(f"nonlinearity: odd-line ratio {nl['odd_ratio'] or float('nan'):.2f}, even-line ratio "
                 f"{nl['even_ratio'] or float('nan'):.2f} (about 1 = linear); distortion dominates above: "
                 + _hz_or(nl['nonlinear_dominant_above_hz'], "not reached in the band"))
    wide = report.get("nonlinearity_wide")
    if wide:
        lines.append(f"wide odd-odd run {wide['band_hz'][0]:g}-{wide['band_hz'][1]:g} Hz: odd-line ratio "
                     f"{wide['odd_ratio']:.1f}, even {wide['even_ratio']:.1f}; distortion as large as the linear "
                     f"output above: {_hz_or(wide['nonlinear_dominant_above_hz'], 'nowhere in the band')} "
                     "(paper: after 2 Hz)")
    fmt = lambda c: "[" + ", ".join(f"{x:.4g}" for x in c) + "]"  # noqa: E731
    for name, m in report["models"].items():
        lines.append(f"\n{name}: num {fmt(m['num'])} +- {fmt(m['num_std'])}")
        lines.append(f"{'':>{len(name)}}  den {fmt(m['den'])} +- {fmt(m['den_std'][1:])}")
        rmse = ", ".join(f"{b}: {v:.4f}" for b, v in m["validation_rmse"].items()) \
            or "not computed (no validation bands: the study's identification.validation_bands is empty)"
        lines.append(f"{'':>{len(name)}}  cost {m['cost']:.1f} (expected {m['cost_expected']:.1f}); RMSE {rmse}")
        paper = PAPER["models"].get(name)
        if paper:
            lines.append(f"{'':>{len(name)}}  paper: num {fmt(paper['num'])} den {fmt(paper['den'])}; RMSE "
                         + ", ".join(f"{b}: {v}" for b, v in PAPER["rmse"][name].items()))
    phys = report["models"].get("rlfr", {}).get("physical")
    if phys and not phys["solutions"]:
        lines.append("\nRLFR physical: no physical parameters reproduce these coefficients (every start diverged)")
    elif phys:
        best = phys["solutions"][0]
        lines.append(f"\nRLFR physical (m, l_f, l_r known, I = m l_f l_r): C_f {best['C_f']:.0f} N/rad, "
                     f"C_r {best['C_r']:.0f} N/rad, sigma_f {best['sigma_f']:.4f} m, sigma_r {best['sigma_r']:.4f} m"
                     f"; paper: 8000+-500, 90000+-7000, 0.1942, 1.6657"
                     + ("; several solutions fit about equally" if phys["several_fit_equally"] else ""))
    from .plots import root_notes

    notes = root_notes(report)
    return "\n".join(lines + ([""] + notes if notes else []))
