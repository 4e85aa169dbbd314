"""The readable report: Markdown with plots (measured against simulated, residuals over time,
spectra, cross-correlations, residuals by speed and amplitude), baseline against the winner."""
from __future__ import annotations

import math
import re
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
from matplotlib.ticker import StrMethodFormatter
import numpy as np

from agrobot.measurements.recording import describe
from agrobot.orchestrator.atomic_files import atomic_write

from .catalogue import DISPLAY, SIGNALS
from .evidence import AMPLITUDE_BINS_DEG, SPEED_BINS, binned, cross_correlation, spectrum
from .unexplained import RATIO

UNIT_SCALE = DISPLAY          # every number of the report and its plots: angles in degrees, SI otherwise
UNITS_NOTE = ("Units: angles in deg and angular rates in deg/s, everything else SI (m, m/s, s); the study-file "
              "lines are in SI as study files take them (rad, rad/s).")


def stage_figure(replay, stage: str, base: dict, winner: dict | None, path: Path, levels: dict | None = None) -> Path:
    """The stage's measured and simulated signal, residual, spectrum and cross-correlation;
    ``levels`` (the stage's judgement: floor, healthy_level, misfit) draws the RMS levels the verdict
    compares the residual with."""
    matplotlib.use("Agg")

    k, unit = UNIT_SCALE[stage]
    rows = 1 if stage == "position" else 2
    fig, ax = plt.subplots(rows, 2, figsize=(12, 3.8 * rows), squeeze=False)
    models = [("baseline", base, "tab:red")] + ([("final model", winner, "tab:green")] if winner else [])
    if stage == "position":
        for label, v, color in models:
            t, r = replay.residual_series(stage, v)
            ax[0, 0].plot(t, k * r, ".", ms=1, color=color, label=label)
        ax[0, 0].set(title="antenna position residual after per-window alignment", xlabel=_time_label(replay, ax[0, 0]),
                     ylabel=f"[{unit}]")
        _shade_held_out(ax[0, 0], replay)
        _draw_levels(ax[0, 0], levels, k, unit, signed=False)
        track = replay.gps
        ax[0, 1].plot(track[:, 0], track[:, 1], lw=0.6, color="k")
        ax[0, 1].set(title="measured GPS track", xlabel="east [m]", ylabel="north [m]", aspect="equal")
    else:
        keep = replay.scored(stage)
        t = replay.t
        first = replay.held_out_spans()[0][0]
        window = (t >= first) & (t < first + 30)
        ax[0, 0].plot(t[window], k * replay.measured(stage)[window], color="k", lw=1, label="measured")
        for label, v, color in models:
            ax[0, 0].plot(t[window], k * replay.predicted(stage, v)[window], color=color, lw=1, label=label)
            res = (replay.measured(stage) - replay.predicted(stage, v))
            ax[0, 1].plot(t[keep], k * res[keep], lw=0.5, color=color, label=label)
            f, p = spectrum(res[keep], 1 / replay.h)
            ax[1, 0].semilogy(f, k ** 2 * p, color=color, label=label)
            x = {"steering": replay.cmd, "speed": replay.speed}.get(stage, replay.delta)
            lags, rho, bound = cross_correlation(res[keep], x[keep], 1 / replay.h)
            ax[1, 1].plot(lags, rho, color=color, label=label)
        ax[1, 1].axhspan(-bound, bound, color="0.85", label="95% bound (white)")
        _shade_held_out(ax[0, 0], replay, (first, first + 30))
        ax[0, 0].set(title=f"{SIGNALS[stage][0]}: 30 s from the first held-out stretch",
                     xlabel=_time_label(replay, ax[0, 0], (first, first + 30)), ylabel=f"[{unit}]")
        ax[0, 1].set(title="residual (measured - simulated)", xlabel=_time_label(replay, ax[0, 1]), ylabel=f"[{unit}]")
        _shade_held_out(ax[0, 1], replay)
        _draw_levels(ax[0, 1], levels, k, unit)
        ax[1, 0].set(title="residual spectrum", xlabel="f [Hz]", ylabel=f"PSD [({unit})^2/Hz]")
        ax[1, 1].set(title=f"residual x {({'steering': 'delta_cmd', 'speed': 'v'}).get(stage, 'delta')} cross-correlation",
                     xlabel="lag [s]", ylabel="correlation [-]")
    for a in ax.flat:
        if a.get_legend_handles_labels()[0]:
            a.legend(fontsize=7)
            a.grid(alpha=0.3)
    fig.suptitle(f"{stage} stage (grey: held out)")
    fig.tight_layout()
    atomic_write(path, lambda p: fig.savefig(p, dpi=90, format="png"))
    plt.close(fig)
    return path


def _time_label(replay, ax, span: tuple[float, float] | None = None) -> str:
    """The time axis' label; a log whose judged stretches are joined (identification.from_log.
    joined_stretches) runs on the joined clock: each join is drawn as a dotted line."""
    joins = [j for j in replay.frame.attrs.get("joins", ()) if span is None or span[0] <= j <= span[1]]
    for j in joins:
        ax.axvline(j, color="0.3", ls=":", lw=1)
    if not replay.frame.attrs.get("joins"):
        return "t [s]"
    return "t, judged stretches joined [s] (dotted: a join)"


def _draw_levels(ax, levels: dict | None, k: float, unit: str, signed: bool = True) -> None:
    """The RMS levels the final model's residual is judged by: its noise floor, the healthy level (what a fault-free
    tractor leaves) and the misfit level (RATIO x floor and a material excess over the healthy
    level), at +- for a signed residual."""
    if not levels:
        return
    floor, healthy = levels["floor"], levels.get("healthy_level", levels["floor"])
    for value, style, colour, label in ((floor, ":", "0.5", "noise floor (RMS)"),
                                        (healthy, "-", "k", "healthy level (RMS)"),
                                        (levels.get("misfit_level", RATIO * floor), "--", "tab:red",
                                         "misfit above (RMS)")):
        for sign in ((-1, 1) if signed else (1,)):
            ax.axhline(sign * k * value, color=colour, ls=style, lw=1.2,
                       label=f"{label} {k * value:.3g} {unit}" if sign > 0 else None)
    ax.legend(fontsize=7, loc="upper right")


# a person reads angles in degrees (the report's one unit system): SI unit -> (factor, shown unit)
DEGREES = {"rad": (180 / math.pi, "deg"), "rad/s": (180 / math.pi, "deg/s"),
           "rad/(m/s2)": (180 / math.pi, "deg/(m/s2)"), "N/rad": (math.pi / 180, "N/deg")}


def vehicle_lines(iv: dict | None, understeer_note: str | None = None) -> list[str]:
    """The vehicle identify fits on this log beside the study's, the independent estimates and the
    physical checks (markdown lines; console: the same lines without the table rule);
    ``understeer_note``: why the identified understeer gradient is not concluded (printed in its place)."""
    if not iv:
        return []
    if iv.get("identified") is None:
        return [f"The vehicle could not be identified on this log: {iv.get('why_not', '')}", ""]
    st, me = iv["study"], iv["identified"]
    k_deg, c_deg = DEGREES["rad/(m/s2)"][0], DEGREES["N/rad"][0]

    def q(d, k=1.0, f="{:.4g}"):
        if not d.get("identifiable", True):
            return f.format(k * d["value"]) + " (not identifiable)"
        return f.format(k * d["value"]) + " [" + ", ".join(f.format(k * x) for x in d["interval"]) + "]"

    out = ["## This vehicle against the study", "",
           f"Identified on this log by the model `identify` fits (input {me['input']}; final model "
           f"{me['final_model']}, held-out fit {me['held_out_fit']:.0f} %):", "",
           "| quantity | study | identified (95 %) |", "|---|---:|---:|",
           f"| understeer gradient K [deg/(m/s2)] | {k_deg * st['understeer_gradient']:.4g} | "
           f"{understeer_note or q(me['understeer_gradient'], k_deg)} |",
           f"| cornering stiffness front [N/deg] | {c_deg * st['cornering_stiffness_front']:.4g} | "
           f"{q(me['cornering_stiffness_front'], c_deg)} |",
           f"| cornering stiffness rear [N/deg] | {c_deg * st['cornering_stiffness_rear']:.4g} | "
           f"{q(me['cornering_stiffness_rear'], c_deg)} |",
           f"| steering delay [s] | {st['delay']:.3g} | {q(me['delay'])} |", ""]
    for c in iv.get("comparisons", []):
        k, unit = DEGREES.get(c["unit"], (1.0, c["unit"]))
        out.append(f"- {c['quantity']} [{unit}]: " + "; ".join(
            f"{m} {k * e['value']:.4g} [{k * e['interval'][0]:.4g}, {k * e['interval'][1]:.4g}]"
            for m, e in c["estimates"].items())
            + (" (not compared: identify does not conclude its value)" if c.get("concluded") is False else
               " (agree)" if c["agree"] else f" **disagree**: {c['suggests']}")
            + (f"; **implausible for the vehicle**: {c['implausible']}" if c.get("implausible") else ""))
    held = me.get("held_out_yaw") or {}
    if math.isfinite(held.get("diagnosis_rms", math.nan)):
        k = DEGREES["rad/s"][0]
        out.append(f"- yaw rate on the same unseen stretches ({held['seconds']:.0f} s of identify's held-out segments "
                   f"inside the diagnosis's held-out part) [deg/s]: RMS misfit {k * held['rms']:.4g} identify's model, "
                   f"{k * held['diagnosis_rms']:.4g} the diagnosis's final model")
    for c, chk in iv.get("physical_checks", {}).items():
        out.append(f"- physical check `{c}` ({chk['what']}): held-out fit {chk['fit_percent']:.0f} %, RMS "
                   f"{chk['rms']:.3g} {chk['unit']} against a measured std of {chk['measured_std']:.3g}")
    return out + [""]


def _shade_held_out(ax, replay, within: tuple[float, float] = (-math.inf, math.inf)) -> None:
    """Grey spans over the held-out part."""
    for a, b in replay.held_out_spans():
        if b > within[0] and a < within[1]:
            ax.axvspan(max(a, within[0]), min(b, within[1]), color="0.9", zorder=0)


def split_sentence(result: dict) -> str:
    """What the fit saw and what was held out, and why when the split was not the last part."""
    split = result.get("split") or {}
    if split.get("kind", "tail") == "tail":
        return f"Fit on t < {result['split_time']:.1f} s, measured on the rest (held out)."
    spans = ", ".join(f"{a:.0f}-{b:.0f} s" for a, b in split["spans"])
    return (f"Held out: {split['held_out']} ({spans}), fit on the rest" + (f"; {split['why']}" if split.get("why") else "")
            + ".")


def markdown(result: dict, plots: list[str]) -> str:
    """report.md: the verdict and every effect judged, each stage's residual against its noise floor,
    each catalogue effect alone against the baseline, the baseline's residuals, the figures."""
    lines = [f"# Diagnosis of `{result['log']}`", "",
             f"Baseline model: `{result['study']}`. {split_sentence(result)} {UNITS_NOTE}", "",
             *geometry_lines(result),
             *before_verdict(result), f"## Verdict: **{result['verdict']}**", ""]
    if result["verdict"] == "cannot decide":
        lines += [result.get("reason", ""), ""]
        return "\n".join(lines)
    lines += _verdict_lines(result)
    lines += _stage_table(result)
    lines += _findings_table(result)
    lines += _residual_lines(result)
    lines += [""] + [f"![{p}]({p})" for p in plots] + [""]
    return "\n".join(lines)


def geometry_lines(result: dict) -> list[str]:
    """The steering geometry the baseline's yaw model is driven under, where from and what it passed
    over (pipeline: Baseline.steering_geometry, geometry_choice's line)."""
    choice = result.get("steering_geometry")
    return [f"Steering geometry: {choice['says'].removeprefix('steering geometry: ')}.", ""] if choice else []


def before_verdict(result: dict) -> list[str]:
    """What is said before any verdict: the study not being the log's vehicle, a log in the kinematic
    regime, the class's default outline taken for a vehicle without dimensions."""
    notes = result.get("before_verdict") or []
    return ["## Before the verdict", "", *[f"- {n}" for n in notes], ""] if notes else []


def refit_lines(result: dict) -> list[str]:
    """The baseline refit: each parameter's study value, the value fitted, moved or not, and the
    bound it ended on (no estimate then)."""
    rows = result.get("baseline_refit_summary") or []
    if not rows:
        return []
    out = ["", "Baseline refit (the study's uncertain parameters fitted to this log before any effect):", "",
           "| parameter | study | fitted | moved | searched in | ended on a bound |", "|---|---:|---:|---|---|---|"]
    for r in rows:
        edge = f"**{r['at_bound']}** (no estimate)" if r["at_bound"] else "no"
        searched = f"[{r['bounds'][0]:.3g}, {r['bounds'][1]:.3g}]" if r["bounds"] else f"held: {r.get('held')}"
        out.append(f"| {r['name']} [{r['unit']}] | {r['study']:.4g} | {r['value']:.4g} | {'yes' if r['moved'] else 'no'} "
                   f"| {searched} | {edge} |")
    return out + [""]


def _verdict_lines(result: dict) -> list[str]:
    """The verdict's statement and bullets, the identified vehicle, every effect judged with the
    study option that switches it on, the inconclusive pairs and the warnings."""
    lines = []
    if result.get("recording"):
        lines += ["The log was imported from a raw recording (details in diagnosis.json, `recording`):", "", "```",
                  describe(result["recording"]), "```", ""]
    lines += [f"{result.get('verdict_statement', '')} ({result.get('verdict_status', '')}).", ""]
    lines += [f"- {b}" for b in result.get("verdict_bullets", [])] + ([""] if result.get("verdict_bullets") else [])
    lines += refit_lines(result)
    lines += vehicle_lines(result.get("identified_vehicle"), result.get("understeer_note"))
    lines += ["Every effect judged:", ""]
    for e in result["effects"]:
        lines += [f"- **{e['id']}**: {e['summary']}"]
        if e["id"] != "unexplained":
            lines += [f"  Switch it on in a study: `{e['study_option']}`"]
    if result.get("extended_study"):
        lines += ["", "All found effects are switched on in `extended_study.toml`."]
    if not result["effects"]:
        lines += ["No extension beats the noise, and every stage's residual is at its noise floor."]
    for tie in result.get("inconclusive", []):
        a, b = tie["effects"]
        lines += ["", f"**Inconclusive**: {a} and {b} explain the same misfit equally well (dBIC {tie['delta_bic'][0]:.0f} "
                      f"against {tie['delta_bic'][1]:.0f}); {a} is kept. Separate them with a new run, {tie['experiment']}."]
    for w in result.get("warnings", []):
        lines += ["", f"> Warning: {w}"]
    return lines


def _stage_table(result: dict) -> list[str]:
    """Each stage's held-out RMS against its floor and healthy level: baseline, without each found
    effect, final (x floor, excess over healthy against the materiality), the data-driven extension;
    then how each healthy level was found."""
    lines = ["", "## Residual by stage against the noise floor (held-out RMS)", "",
             "The floor is the sensors' white noise, estimated from the log (top of the residual spectrum; for the",
             "position and speed stages propagated through the dead reckoning). 'without X': the final model",
             "refitted without effect X. 'healthy': what a tractor with no fault, described exactly by the",
             "study, leaves in this log's replay (the baseline's own simplifications: the steering's first-order",
             "equivalent, a quantised wheel-angle sensor; see below). A stage is misfit above "
             f"{RATIO:.1f} x its floor and a material excess over the healthy level.", "",
             "| " + " | ".join(["stage", "unit", "floor", "healthy", "baseline"]
                               + [f"without {e['id']}" for e in result["effects"] if e["id"] != "unexplained"]
                               + ["final", "x floor", "excess over healthy (materiality)", "data-driven extension"]) + " |",
             "|---|---|---:|---:|---:|" + "---:|" * sum(e["id"] != "unexplained" for e in result["effects"])
             + "---:|---:|---:|---|"]
    by_stage = next((e["by_stage"] for e in result["effects"] if e["id"] == "unexplained"), {})
    for stage, st in result.get("stages", {}).items():
        k, unit = UNIT_SCALE[stage]
        if not st.get("judged", True):
            lines.append(f"| {stage} | {unit} | {st['reason']} |")
            continue
        cells = [f"{k * st['rms_without'][e['id']]:.3g}" if e["id"] in st["rms_without"] else "-"
                 for e in result["effects"] if e["id"] != "unexplained"]
        ext = by_stage.get(stage, {}).get("extension")
        ext_text = (f"{ext['kind']} on {ext['signal']}: {k * ext['rms_after']:.3g} ({100 * ext['held_out_gain']:.0f}% off)"
                    if ext else "-")
        healthy = st.get("healthy_level", st["floor"])
        lines.append(f"| {stage} | {unit} | {k * st['floor']:.3g} | {k * healthy:.3g} | {k * st['rms_baseline_test']:.3g} | "
                     + "".join(c + " | " for c in cells)
                     + f"{k * st['rms_test']:.3g} | {st['ratio']:.2f}{' (misfit)' if st['misfit'] else ''} | "
                     + f"{k * st.get('excess_over_healthy', 0.0):.3g} ({k * st['materiality']:.3g}) | {ext_text} |")
    lines += ["", "How the healthy level was found:", ""]
    lines += [f"- {stage}: {st.get('healthy_how', 'the noise floor')}" for stage, st in result.get("stages", {}).items()
              if st.get("judged", True)]
    return lines + [""]


def _findings_table(result: dict) -> list[str]:
    """Each catalogue effect fitted alone against the baseline, best first: dBIC, held-out gain,
    parameters, supported or why not."""
    lines = ["## Each catalogue effect alone against the baseline, best first", "",
             "| effect | subsystem | dBIC | held-out gain | parameters | supported | why not |",
             "|---|---|---:|---:|---|---|---|"]
    for f in result["findings"]:
        params = ", ".join(f"{k} = {v:.4g}" for k, v in f["parameters_display"].items())
        lines.append(f"| {f['id']} | {f['subsystem']} | {f['delta_bic']:.1f} | "
                     f"{100 * f['held_out_gain']:.1f}% | {params} | {'yes' if f['supported'] else 'no'} | "
                     f"{'; '.join(f['reasons'])} |")
    return lines


def _residual_lines(result: dict) -> list[str]:
    """The baseline's residual per stage: RMS (fit, held out), mean, cross-correlations against
    their 95 % bound, mean by speed, RMS by steering amplitude."""
    lines = ["", "## Baseline residuals", ""]
    for stage, ev in result["residuals"].items():
        k, unit = UNIT_SCALE[stage]
        lines.append(f"- **{stage}** [{unit}]: RMS {k * ev['rms_fit']:.4g} (fit) / {k * ev['rms_test']:.4g} (held out)"
                     + (f", mean {k * ev['mean']:.3g}" if "mean" in ev else ""))
        for name, xc in ev.get("cross_correlation", {}).items():
            lines.append(f"  - cross-correlation with {name}: peak {xc['peak']:.2f} at lag {xc['lag_s']:.2f} s "
                         f"({'outside' if xc['outside_bound'] else 'inside'} the 95% bound {xc['bound']:.3f})")
        if ev.get("by_speed"):
            cells = ", ".join(f"{b['from']:.2g}-{b['to']:.2g} m/s: {k * b['mean']:.3g}±{k * b['sem']:.1g}"
                              for b in ev["by_speed"])
            lines.append(f"  - mean by speed [{unit}]: {cells}")
        if ev.get("by_steering_amplitude_deg"):
            cells = ", ".join(f"{b['from']:.0f}-{b['to']:.0f} deg: rms {k * b['rms']:.3g}"
                              for b in ev["by_steering_amplitude_deg"])
            lines.append(f"  - RMS [{unit}] by |delta_cmd|: {cells}")
    return lines


def binned_figure(replay, base: dict, winner: dict | None, path: Path) -> Path:
    """Residual mean (with its standard error) by speed and RMS by steering amplitude, for the
    steering and yaw stages, baseline against the winner."""
    matplotlib.use("Agg")

    stages = [s for s in ("steering", "yaw") if s in replay.stages]
    fig, ax = plt.subplots(max(len(stages), 1), 2, figsize=(12, 3 * max(len(stages), 1)), squeeze=False)
    models = [("baseline", base, "tab:red")] + ([("final model", winner, "tab:green")] if winner else [])
    for row, stage in enumerate(stages):
        k, unit = UNIT_SCALE[stage]
        sel = replay.scored(stage)
        for j, (label, v, color) in enumerate(models):
            _, res = replay.residual_series(stage, v)
            by_v = binned(res, replay.speed[sel], SPEED_BINS)
            by_a = binned(res, np.degrees(np.abs((replay.cmd if stage == "steering" else replay.delta)[sel])),
                          AMPLITUDE_BINS_DEG)
            off = 0.15 * (j - 0.5 * (len(models) - 1))
            ax[row, 0].errorbar([0.5 * (b["from"] + min(b["to"], 4.0)) + off for b in by_v], [k * b["mean"] for b in by_v],
                                yerr=[1.96 * k * b["sem"] for b in by_v], fmt="o", color=color, label=label)
            ax[row, 1].bar([i + off for i in range(len(by_a))], [k * b["rms"] for b in by_a], width=0.3,
                           color=color, label=label)
            ax[row, 1].set_xticks(range(len(by_a)), [f"{b['from']:.0f}-{b['to']:.0f}" for b in by_a])
        ax[row, 0].axhline(0, color="k", lw=0.6)
        ax[row, 0].set(title=f"{stage}: residual mean by speed (95% interval)", xlabel="speed [m/s]", ylabel=f"[{unit}]")
        amp = "delta_cmd" if stage == "steering" else "delta"
        ax[row, 1].set(title=f"{stage}: residual RMS by |{amp}|", xlabel=f"|{amp}| [deg]", ylabel=f"[{unit}]")
        for a in ax[row]:
            a.legend(fontsize=7)
            a.grid(alpha=0.3)
    fig.tight_layout()
    atomic_write(path, lambda p: fig.savefig(p, dpi=90, format="png"))
    plt.close(fig)
    return path


def verdict_title(result: dict) -> str:
    """The verdict figure's conclusion, from the result: the effect found with its fitted values (in the
    report's units) and its held-out gain, and the verdict's status when it is not conclusive; the stage
    left unexplained and how far above its floor; or that the study explains the log."""
    effects = {e["id"]: e for e in result["effects"]}
    verdict, status = result["verdict"], result.get("verdict_status", "conclusive")
    if verdict == "none":
        judged = {s: st for s, st in result["stages"].items() if st.get("judged", True)}
        if not judged:
            return "Diagnosis: no fault found (no stage could be judged)"
        worst = max(judged, key=lambda s: judged[s]["rms_test"] / judged[s]["floor"])
        return (f"Diagnosis: no fault; the study explains the log to its noise floor (highest: {worst} "
                f"{judged[worst]['rms_test'] / judged[worst]['floor']:.2f} x its floor, no misfit)")
    if verdict == "unexplained":
        u = effects["unexplained"]
        gain = u["held_out_gain"]
        return (f"Diagnosis: unexplained misfit, the {u['stage']} stage at {u['ratio_to_floor']:.1f} x its noise floor "
                + (f"(a data-driven extension takes {100 * gain:.0f} % off held out)" if gain >= 0.05 else
                   "(no data-driven extension carries over to the held-out part)"))
    if verdict not in effects:           # the study wrong for the log (verdict.on_wrong_study)
        return f"Diagnosis: {verdict.replace('_', ' ')}: {result.get('verdict_statement', '').split(':', 1)[0]}"
    e = effects[verdict]
    values = []
    for name, value in e["parameters_display"].items():
        m = re.fullmatch(r"(.*?) \[(.*)\]", name)
        values.append(f"{m.group(1)} {value:.3g} {m.group(2)}" if m else f"{name} {value:.3g}")
    others = [x.replace("_", " ") for x in effects if x not in (verdict, "unexplained")]
    return (f"Diagnosis: {verdict.replace('_', ' ')}, {', '.join(values)} (held-out gain {100 * e['held_out_gain']:.0f} %)"
            + ("" if status == "conclusive" else f": {status}") + (f"; also {', '.join(others)}" if others else ""))


def floors_figure(result: dict, path: Path) -> Path:
    """Held-out residual RMS of each stage in multiples of its noise floor: baseline, the final
    model without each found effect, the final model, and the data-driven extension."""
    matplotlib.use("Agg")

    stages = [s for s, st in result["stages"].items() if st.get("judged", True)]
    found = [e["id"] for e in result["effects"] if e["id"] != "unexplained"]
    by_stage = next((e["by_stage"] for e in result["effects"] if e["id"] == "unexplained"), {})
    # each series differs in lightness or hatch as well as hue (it reads in grey): dark red, hatched white,
    # mid green, dotted pale purple
    series = [("baseline", lambda s, st: st["rms_baseline_test"], "#b2182b", None)]
    series += [(f"without {eid}", (lambda eid: lambda s, st: st["rms_without"].get(eid, np.nan))(eid), "white",
                ("//", "\\\\", "xx", "--", "++")[i % 5]) for i, eid in enumerate(found)]
    series += [("final model", lambda s, st: st["rms_test"], "#4dac26", None),
               ("+ data-driven extension", lambda s, st: by_stage[s]["extension"]["rms_after"] if s in by_stage else np.nan,
                "#c2a5cf", "..")]
    fig, ax = plt.subplots(figsize=(11, 4.6))
    width = 0.8 / len(series)
    for i, (label, get, color, hatch) in enumerate(series):
        ratios = [get(s, result["stages"][s]) / result["stages"][s]["floor"] for s in stages]
        ax.bar(np.arange(len(stages)) + (i - (len(series) - 1) / 2) * width, ratios, width, label=label, color=color,
               hatch=hatch, edgecolor="0.2", linewidth=0.5)
    ax.axhline(1.0, color="0.5", lw=1, label="noise floor")
    judged = [result["stages"][s] for s in stages]        # each stage's own judgement: healthy and misfit levels
    xs = np.arange(len(stages))
    ax.hlines([st.get("healthy_level", st["floor"]) / st["floor"] for st in judged], xs - 0.45, xs + 0.45, color="k",
              lw=2.5, label="healthy level (what the study's fault-free vehicle leaves)")
    ax.hlines([st.get("misfit_level", RATIO * st["floor"]) / st["floor"] for st in judged], xs - 0.45, xs + 0.45,
              color="#d6604d", ls="--", lw=1.5, label=f"misfit above: {RATIO:g} x floor and a material excess over healthy")
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(StrMethodFormatter("{x:g}")), ax.yaxis.set_minor_formatter(StrMethodFormatter("{x:g}"))
    ax.set_xticks(range(len(stages)), [f"{s}\nfinal: {'MISFIT' if result['stages'][s]['misfit'] else 'no misfit'}\nfloor "
                                       f"{UNIT_SCALE[s][0] * result['stages'][s]['floor']:.2g} {UNIT_SCALE[s][1]}"
                                       for s in stages])
    ax.set(ylabel="held-out residual RMS / noise floor [-]", xlabel="stage: the final model's judgement, its noise floor")
    ax.set_title(f"{verdict_title(result)}\nwhat each model leaves of the held-out residual, against the noise floor",
                 fontsize=10)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.grid(alpha=0.3, axis="y", which="both")
    fig.tight_layout()
    atomic_write(path, lambda p: fig.savefig(p, dpi=90, format="png", bbox_inches="tight"))
    plt.close(fig)
    return path
