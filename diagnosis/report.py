"""The readable report: Markdown with plots (measured against simulated, residuals over time,
spectra, cross-correlations, residuals by speed and amplitude), baseline against the winner."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from orchestrator.results import atomic_write

from .catalogue import SIGNALS
from .evidence import cross_correlation, spectrum

UNIT_SCALE = {"steering": (180 / np.pi, "deg"), "yaw": (1.0, "rad/s"), "position": (100.0, "cm")}


def stage_figure(replay, stage: str, base: dict, winner: dict | None, path: Path) -> Path:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    k, unit = UNIT_SCALE[stage]
    rows = 1 if stage == "position" else 2
    fig, ax = plt.subplots(rows, 2, figsize=(12, 3.8 * rows), squeeze=False)
    models = [("baseline", base, "tab:red")] + ([("extended", winner, "tab:green")] if winner else [])
    if stage == "position":
        for label, v, color in models:
            t, r = replay.residual_series(stage, v)
            ax[0, 0].plot(t, k * r, ".", ms=1, color=color, label=label)
        ax[0, 0].set(title="antenna position residual after per-window alignment", xlabel="t [s]", ylabel=f"[{unit}]")
        ax[0, 0].axvline(replay.t_split, color="k", ls="--", lw=0.8)
        track = replay.gps
        ax[0, 1].plot(track[:, 0], track[:, 1], lw=0.6, color="k")
        ax[0, 1].set(title="measured GPS track", xlabel="east [m]", ylabel="north [m]", aspect="equal")
    else:
        keep = replay.scored(stage)
        t = replay.t
        window = (t >= replay.t_split) & (t < replay.t_split + 30)
        ax[0, 0].plot(t[window], k * replay.measured(stage)[window], color="k", lw=1, label="measured")
        for label, v, color in models:
            ax[0, 0].plot(t[window], k * replay.predicted(stage, v)[window], color=color, lw=1, label=label)
            res = (replay.measured(stage) - replay.predicted(stage, v))
            ax[0, 1].plot(t[keep], k * res[keep], lw=0.5, color=color, label=label)
            f, p = spectrum(res[keep], 1 / replay.h)
            ax[1, 0].semilogy(f, p, color=color, label=label)
            x = replay.cmd if stage == "steering" else replay.delta
            lags, rho, bound = cross_correlation(res[keep], x[keep], 1 / replay.h)
            ax[1, 1].plot(lags, rho, color=color, label=label)
        ax[1, 1].axhspan(-bound, bound, color="0.85", label="95% bound (white)")
        ax[0, 0].set(title=f"{SIGNALS[stage][0]}: 30 s of the held-out part", xlabel="t [s]", ylabel=f"[{unit}]")
        ax[0, 1].set(title="residual (measured - simulated)", xlabel="t [s]", ylabel=f"[{unit}]")
        ax[0, 1].axvline(replay.t_split, color="k", ls="--", lw=0.8)
        ax[1, 0].set(title="residual spectrum", xlabel="f [Hz]", ylabel="PSD")
        ax[1, 1].set(title=f"residual x {'delta_cmd' if stage == 'steering' else 'delta'} cross-correlation",
                     xlabel="lag [s]")
    for a in ax.flat:
        if a.get_legend_handles_labels()[0]:
            a.legend(fontsize=7)
            a.grid(alpha=0.3)
    fig.suptitle(f"{stage} stage (dashed: start of the held-out part)")
    fig.tight_layout()
    atomic_write(path, lambda p: fig.savefig(p, dpi=90, format="png"))
    plt.close(fig)
    return path


def markdown(result: dict, plots: list[str]) -> str:
    lines = [f"# Diagnosis of `{result['log']}`", "",
             f"Baseline model: `{result['study']}`. Fit on t < {result['split_time']:.1f} s, "
             f"measured on the rest (held out).", "",
             f"## Verdict: **{result['verdict']}**", ""]
    if result["verdict"] == "cannot decide":
        lines += [result.get("reason", ""), ""]
        return "\n".join(lines)
    win = next((f for f in result["findings"] if f["effect"] == result["verdict"]), None)
    if win:
        lines += [f"{win['evidence']['summary']}", "",
                  f"Switch it on in a study: `{win['evidence']['study_option']}` "
                  f"(written to `extended_study.toml` when the study has that component).", ""]
    else:
        lines += ["No extension beats the noise: each one fails a test below.", ""]
    lines += ["## Candidates, best first", "",
              "| effect | subsystem | dBIC | held-out gain | parameters | supported | why not |",
              "|---|---|---:|---:|---|---|---|"]
    for f in result["findings"]:
        params = ", ".join(f"{k} = {v:.4g}" for k, v in f["params_display"].items())
        lines.append(f"| {f['effect']} | {f['subsystem']} | {f['evidence']['delta_bic']:.1f} | "
                     f"{100 * f['gain']:.1f}% | {params} | {'yes' if f['evidence']['supported'] else 'no'} | "
                     f"{'; '.join(f['evidence']['reasons'])} |")
    lines += ["", "## Baseline residuals", ""]
    for stage, ev in result["residuals"].items():
        lines.append(f"- **{stage}**: RMS {ev['rms_fit']:.4g} (fit) / {ev['rms_test']:.4g} (held out)"
                     + (f", mean {ev['mean']:.3g}" if "mean" in ev else ""))
        for name, xc in ev.get("cross_correlation", {}).items():
            lines.append(f"  - cross-correlation with {name}: peak {xc['peak']:.2f} at lag {xc['lag_s']:.2f} s "
                         f"({'outside' if xc['outside_bound'] else 'inside'} the 95% bound {xc['bound']:.3f})")
        if ev.get("by_speed"):
            cells = ", ".join(f"{b['from']:.2g}-{b['to']:.2g} m/s: {b['mean']:.3g}±{b['sem']:.1g}" for b in ev["by_speed"])
            lines.append(f"  - mean by speed: {cells}")
        if ev.get("by_steering_amplitude_deg"):
            cells = ", ".join(f"{b['from']:.0f}-{b['to']:.0f} deg: rms {b['rms']:.3g}" for b in ev["by_steering_amplitude_deg"])
            lines.append(f"  - RMS by |delta_cmd|: {cells}")
    lines += [""] + [f"![{p}]({p})" for p in plots] + [""]
    return "\n".join(lines)


def binned_figure(replay, base: dict, winner: dict | None, path: Path) -> Path:
    """Residual mean (with its standard error) by speed and RMS by steering amplitude, for the
    steering and yaw stages, baseline against the winner."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .evidence import AMPLITUDE_BINS_DEG, SPEED_BINS, binned

    fig, ax = plt.subplots(2, 2, figsize=(12, 6))
    models = [("baseline", base, "tab:red")] + ([("extended", winner, "tab:green")] if winner else [])
    for row, stage in enumerate(("steering", "yaw")):
        k, unit = UNIT_SCALE[stage]
        sel = replay.scored(stage)
        for j, (label, v, color) in enumerate(models):
            _, res = replay.residual_series(stage, v)
            by_v = binned(res, replay.speed[sel], SPEED_BINS)
            by_a = binned(res, np.degrees(np.abs(replay.cmd[sel])), AMPLITUDE_BINS_DEG)
            off = 0.15 * (j - 0.5 * (len(models) - 1))
            ax[row, 0].errorbar([0.5 * (b["from"] + min(b["to"], 4.0)) + off for b in by_v], [k * b["mean"] for b in by_v],
                                yerr=[1.96 * k * b["sem"] for b in by_v], fmt="o", color=color, label=label)
            ax[row, 1].bar([i + off for i in range(len(by_a))], [k * b["rms"] for b in by_a], width=0.3,
                           color=color, label=label)
            ax[row, 1].set_xticks(range(len(by_a)), [f"{b['from']:.0f}-{b['to']:.0f}" for b in by_a])
        ax[row, 0].axhline(0, color="k", lw=0.6)
        ax[row, 0].set(title=f"{stage}: residual mean by speed (95% interval)", xlabel="speed [m/s]", ylabel=f"[{unit}]")
        ax[row, 1].set(title=f"{stage}: residual RMS by |delta_cmd|", xlabel="|delta_cmd| [deg]", ylabel=f"[{unit}]")
        for a in ax[row]:
            a.legend(fontsize=7)
            a.grid(alpha=0.3)
    fig.tight_layout()
    atomic_write(path, lambda p: fig.savefig(p, dpi=90, format="png"))
    plt.close(fig)
    return path
