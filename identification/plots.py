"""Plots of section IV: measured FRF with the fitted models, the nonlinear-distortion spectrum,
poles and zeros per speed."""
from __future__ import annotations

from pathlib import Path

import numpy as np


def write_plots(analyses: dict, main_speed: float, out_dir: Path) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    main = analyses[main_speed]
    r = main["frf"]
    fig, (a1, a2) = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
    db = lambda x: 20 * np.log10(np.abs(x))  # noqa: E731
    a1.semilogx(r.freq, db(r.G), "k.", label="measured FRF")
    floor = float(np.min(db(r.G))) - 60.0          # variances far below the FRF carry no information
    for var, style, label in ((r.var_noise, "c-", "noise variance"), (r.var_nl, "m-", "nonlinear variance")):
        level = 10 * np.log10(np.maximum(var, 1e-300))
        a1.semilogx(r.freq, np.where(level > floor, level, np.nan), style, lw=0.8, label=label)
    a1.set_ylim(bottom=floor)
    f = np.logspace(np.log10(r.freq.min()), np.log10(r.freq.max()), 300)
    for name, fit in main["fits"].items():
        g = fit.response(f)
        a1.semilogx(f, db(g), label=name)
        a2.semilogx(f, np.degrees(np.unwrap(np.angle(g))), label=name)
    a2.semilogx(r.freq, np.degrees(np.unwrap(np.angle(r.G))), "k.")
    a1.set_ylabel("|G| [dB]"), a2.set_ylabel("phase [deg]"), a2.set_xlabel("frequency [Hz]")
    a1.legend(fontsize=7), a1.grid(alpha=0.3), a2.grid(alpha=0.3)
    a1.set_title(f"Steering angle to yaw rate at {main_speed:g} m/s")
    fig.tight_layout()
    written.append(_save(fig, out_dir / "frf.png", plt))

    d = main.get("frf_wide", r).detection
    fig, ax = plt.subplots(figsize=(7, 4))
    for kind, style in (("excited", "k^"), ("odd", "ro"), ("even", "bs")):
        sel = d["kind"] == kind
        ax.semilogx(d["freq"][sel], 10 * np.log10(d["level"][sel]), style, ms=3, label=f"{kind} lines")
    ax.semilogx(d["freq"], 10 * np.log10(d["noise"]), "g-", lw=0.8, label="noise level")
    ax.set_xlabel("frequency [Hz]"), ax.set_ylabel("yaw-rate level [dB]"), ax.grid(alpha=0.3), ax.legend(fontsize=7)
    ax.set_title("Nonlinear contributions at the non-excited lines")
    fig.tight_layout()
    written.append(_save(fig, out_dir / "nonlinear_distortion.png", plt))

    names = list(main["fits"])
    fig, axes = plt.subplots(1, len(names), figsize=(3.6 * len(names), 3.8), squeeze=False)
    colours = plt.get_cmap("tab10")
    for ax, name in zip(axes[0], names):
        points = [(v, complex(p), kind) for v, a in sorted(analyses.items())
                  for kind, values in (("pole", a["fits"][name].poles), ("zero", a["fits"][name].zeros))
                  for p in np.atleast_1d(values) if np.isfinite(p)]
        near = [abs(p.real) for _, p, _ in points if abs(p) < 200.0] + [abs(p.imag) for _, p, _ in points]
        lim = 1.15 * max(near + [5.0])
        speeds = sorted(analyses)
        for v, p, kind in points:
            colour = colours(speeds.index(v))
            x = min(max(p.real, -lim), lim)
            marker = ("x" if kind == "pole" else "o") if x == p.real else ("<" if p.real < 0 else ">")
            ax.plot(x, p.imag, marker, mfc="none" if kind == "zero" else colour, color=colour, ms=6)
            if x != p.real:         # off scale: drawn at the edge, its value written
                ax.annotate(f"{kind} {p.real:.3g}", (x, p.imag), fontsize=6, xytext=(0, 6), textcoords="offset points",
                            ha="right" if p.real > 0 else "left")
        for i, v in enumerate(speeds):
            ax.plot([], [], "s", color=colours(i), label=f"{v:g} m/s")
        ax.set_xlim(-lim, lim)
        ax.axvline(0, color="k", lw=0.5), ax.grid(alpha=0.3), ax.set_title(f"{name}: x poles, o zeros", fontsize=9)
        ax.set_xlabel("real part [rad/s]"), ax.set_ylabel("imaginary part [rad/s]")
        ax.legend(fontsize=7)
    fig.tight_layout()
    written.append(_save(fig, out_dir / "poles_zeros.png", plt))
    return written


def _save(fig, path: Path, plt) -> Path:
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
