"""Figures of the identification from driving: steady-state yaw-rate gain against speed with the
log's steady windows, held-out segments against the models, and the misfit against |a_y|."""
from __future__ import annotations

from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np

from .driving import steady_state_gain
from .plots import _save


def write_driving_plots(report: dict, hidden: dict, out_dir: Path) -> list[Path]:
    matplotlib.use("Agg")

    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    lin = report["linear_range"]["value"]
    rows = report["steady_state_gain"]["rows"]
    if rows:            # none when no single K is concluded (ordinary_driving._steady_gain)
        written.append(_gain_figure(report, hidden, rows, out_dir))

    log, model, test = hidden["log"], hidden["model"], hidden["test"]
    sims = model.simulate_many([hidden["linear"], hidden["nl"]], test)
    order = np.argsort([-np.std(log.r[test.idx[i]][test.scored[i]]) if test.scored[i].any() else 0
                        for i in range(len(test.idx))])[:3]
    fig, axes = plt.subplots(len(order), 1, figsize=(9, 2.4 * len(order)), squeeze=False)
    for ax, i in zip(axes[:, 0], order):
        m = test.scored[i]
        t = log.t[test.idx[i]][m]
        ax.plot(t, log.r[test.idx[i]][m], "k", lw=1, label="measured yaw rate")
        ax.plot(t, sims[0][i][m], color="tab:red", lw=1, label="linear tyres")
        ax.plot(t, sims[1][i][m], color="tab:green", lw=1, label="tyre saturation (Magic Formula)")
        ax.set(ylabel="yaw rate [rad/s]")
        ax.grid(alpha=0.3)
    axes[0, 0].set_title("Held-out segments (never used in the fit)")
    axes[-1, 0].set_xlabel("t [s]")
    axes[0, 0].legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    written.append(_save(fig, out_dir / "held_out.png", plt))

    bins = report["residual_by_lateral_acceleration"]
    fig, ax = plt.subplots(figsize=(7.5, 4))
    for key, colour, label in (("linear", "tab:red", "linear tyres"), ("saturation", "tab:green", "tyre saturation")):
        b = bins[key]
        if b:
            ax.plot([0.5 * (x["from"] + x["to"]) for x in b], [x["rms"] for x in b], "o-", color=colour, label=label)
    ax.axvline(lin, color="k", ls="--", lw=0.8, label=f"linear range ends ({lin:.3g} m/s2)")
    ax.set(xlabel="|a_y| = |v r| [m/s2]", ylabel="held-out residual RMS [rad/s]",
           title="Where the linear tyre stops explaining the yaw rate")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    written.append(_save(fig, out_dir / "misfit_by_lateral_acceleration.png", plt))
    return written

def _gain_figure(report: dict, hidden: dict, rows: list[dict], out_dir: Path) -> Path:
    """The steady-state yaw-rate gain against speed with its interval and the steady windows."""
    L, K, g = hidden["L"], hidden["K"], hidden["g"]
    offset = hidden["final"].get("steer_offset", 0.0)
    bias = report["parameters"].get("gyro_bias", {}).get("value", 0.0)
    w = hidden["windows"]
    lin = report["linear_range"]["value"]
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    v = np.array([r["speed"] for r in rows])
    ax.fill_between(v, [r["interval"][0] for r in rows], [r["interval"][1] for r in rows], color="tab:blue", alpha=0.2,
                    label="95 % interval")
    vv = np.linspace(v.min(), v.max(), 200)
    ax.plot(vv, steady_state_gain(vv, K, L, g), color="tab:blue", label=f"identified: K = {K:.3g} rad/(m/s2)")
    ax.plot(vv, steady_state_gain(vv, 0.0, L, 1.0), "k--", lw=0.8, label="kinematic v / L")
    turning = np.abs(w["u"]) > 0.02
    if np.any(turning):
        u_eff = g * w["u"][turning] + offset
        gain = (w["r"][turning] - bias) / u_eff * g
        inside = np.abs(w["a_y"][turning]) <= lin
        ax.plot(w["v"][turning][inside], gain[inside], "o", ms=4, color="tab:green",
                label=f"steady windows, |a_y| <= {lin:.3g} m/s2")
        ax.plot(w["v"][turning][~inside], gain[~inside], "x", ms=4, color="tab:red",
                label=f"steady windows, |a_y| > {lin:.3g} m/s2 (beyond the linear range)")
    ax.set(xlabel="speed v [m/s]", ylabel=f"yaw rate / {report['input']} [(rad/s)/rad]",
           title=f"Steady-state yaw-rate gain ({Path(report['source']).name})")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return _save(fig, out_dir / "steady_state_gain.png", plt)

