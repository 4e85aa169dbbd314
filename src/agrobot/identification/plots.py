"""Plots of section IV: measured FRF with the fitted models, the nonlinear-distortion spectrum,
poles and zeros per speed."""
from __future__ import annotations

from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np


# Poles and zeros beyond this multiple of the top measured angular frequency are not seen by the
# data (a fit can put them anywhere out there): off the figure's scale, listed instead.
OFF_SCALE = 4.0


def root_points(roots: dict) -> list[tuple[float, str, str, complex]]:
    """{speed: {model: (poles, zeros)}} -> [(speed, model, 'pole'|'zero', value)], finite values only."""
    return [(float(v), name, kind, complex(p)) for v, models in sorted(roots.items()) for name, pz in models.items()
            for kind, values in zip(("pole", "zero"), pz) for p in np.atleast_1d(values) if np.isfinite(p)]


def off_scale(points: list, w_top: float) -> list:
    """The points beyond OFF_SCALE x ``w_top`` [rad/s]."""
    return [q for q in points if abs(q[3]) > OFF_SCALE * w_top]


def physical_scale(points: list, w_top: float) -> float:
    """Half-width of the s-plane window [rad/s]: the on-scale roots with a margin."""
    near = [max(abs(q[3].real), abs(q[3].imag)) for q in points if q not in off_scale(points, w_top)]
    return 1.15 * max(near + [1.0])


def _root_text(q) -> str:
    v, name, kind, p = q
    value = f"{p.real:+.3g}" + (f" {p.imag:+.3g}j" if abs(p.imag) > 1e-9 else "")
    return f"{kind} {value} rad/s at {v:g} m/s" + (" (RHP)" if kind == "zero" and p.real > 0 else "")


def root_notes(report: dict) -> list[str]:
    """The printed lines: roots off the plot's scale, and right-half-plane zeros, per model."""
    roots = {float(v): {n: tuple(np.array([complex(*z) for z in m[k]]) for k in ("poles", "zeros"))
                        for n, m in s["models"].items()} for v, s in report["speeds"].items()}
    w_top = 2 * np.pi * max(max(s["frf"]["freq_hz"]) for s in report["speeds"].values())
    points = root_points(roots)
    far = off_scale(points, w_top)
    rhp = [q for q in points if q[2] == "zero" and q[3].real > 0]
    lines = []
    if far:
        lines.append(f"poles and zeros off the scale of poles_zeros.png (|s| > {OFF_SCALE * w_top:.0f} rad/s, "
                     f"{OFF_SCALE:g} x the top measured frequency: beyond what the data sees):")
        lines += [f"  {q[1]}: {_root_text(q)}" for q in far]
    if rhp:
        lines.append("right-half-plane zeros (non-minimum phase; " + (
            "all beyond the measured band" if all(abs(q[3]) > w_top for q in rhp) else "inside the measured band")
            + "):")
        lines += [f"  {q[1]}: {_root_text(q)}" for q in rhp]
    return lines


def _db_limits(values: np.ndarray) -> tuple[float, float]:
    """A magnitude axis around the data: at least 6 dB tall, 15 % margins."""
    lo, hi = float(np.min(values)), float(np.max(values))
    span = max(hi - lo, 6.0)
    mid = 0.5 * (lo + hi)
    return mid - 0.65 * span, mid + 0.65 * span


def write_plots(analyses: dict, main_speed: float, out_dir: Path) -> list[Path]:
    """frf.png, nonlinear_distortion.png and poles_zeros.png in ``out_dir``; returns their paths."""
    matplotlib.use("Agg")

    out_dir.mkdir(parents=True, exist_ok=True)
    main = analyses[main_speed]
    return [_frf_figure(main, main_speed, out_dir / "frf.png"),
            _distortion_figure(main, out_dir / "nonlinear_distortion.png"),
            _poles_zeros_figure(analyses, list(main["fits"]), out_dir / "poles_zeros.png")]


def _frf_figure(main: dict, main_speed: float, path: Path) -> Path:
    """The measured FRF with each fitted model (magnitude 20 log10 |G|, unwrapped phase), and its
    uncertainty: the noise and nonlinear variances of G in dB (10 log10)."""
    r = main["frf"]
    fig, (a1, a2, a3) = plt.subplots(3, 1, sharex=True, figsize=(7, 8), gridspec_kw={"height_ratios": [3, 2, 2]})
    db = lambda x: 20 * np.log10(np.abs(x))  # noqa: E731
    f = np.logspace(np.log10(r.freq.min()), np.log10(r.freq.max()), 300)
    a1.semilogx(r.freq, db(r.G), "k.", label="measured FRF")
    a2.semilogx(r.freq, np.degrees(np.unwrap(np.angle(r.G))), "k.")
    for (name, fit), ls in zip(main["fits"].items(), ("-", "--", "-.", ":", (0, (5, 1)))):
        g = fit.response(f)
        a1.semilogx(f, db(g), ls=ls, label=name)
        a2.semilogx(f, np.degrees(np.unwrap(np.angle(g))), ls=ls, label=name)
    a1.set_ylim(*_db_limits(db(r.G)))           # the FRF's own range (the fits follow it)
    a3.semilogx(r.freq, db(r.G), "k.", ms=3, label="|G| (for scale)")
    levels = [db(r.G)]
    for var, style, label in ((r.var_noise, "c.-", "noise variance of G"),
                              (r.var_nl, "m.", "nonlinear variance of G (where above 0)")):
        level = 10 * np.log10(np.where(var > 0, var, np.nan))
        a3.semilogx(r.freq, level, style, lw=0.8, ms=4, label=label)
        levels.append(level[np.isfinite(level)])
    top = float(np.max(db(r.G))) + 5.0
    a3.set_ylim(max(float(np.min(np.concatenate(levels))) - 5.0, top - 80.0), top)
    a1.set_ylabel("|G| [dB]"), a2.set_ylabel("phase [deg]"), a3.set_ylabel("[dB]"), a3.set_xlabel("frequency [Hz]")
    a3.set_title("uncertainty of the measured FRF (variances in dB, 10 log10)", fontsize=9)
    for a in (a1, a2, a3):
        a.grid(alpha=0.3, which="both")
    a1.legend(fontsize=7, ncol=2), a3.legend(fontsize=7)
    a1.set_title(f"Steering angle to yaw rate at {main_speed:g} m/s")
    fig.tight_layout()
    return _save(fig, path, plt)


def _distortion_figure(main: dict, path: Path) -> Path:
    """The output's level at the excited, odd and even lines against the noise level (10 log10)."""
    d = main.get("frf_wide", main["frf"]).detection
    fig, ax = plt.subplots(figsize=(7, 4))
    for kind, style in (("excited", "k^"), ("odd", "ro"), ("even", "bs")):
        sel = d["kind"] == kind
        ax.semilogx(d["freq"][sel], 10 * np.log10(d["level"][sel]), style, ms=3, label=f"{kind} lines")
    ax.semilogx(d["freq"], 10 * np.log10(d["noise"]), "g-", lw=0.8, label="noise level")
    ax.set_xlabel("frequency [Hz]"), ax.set_ylabel("yaw-rate level [dB]"), ax.grid(alpha=0.3), ax.legend(fontsize=7)
    ax.set_title("Nonlinear contributions at the non-excited lines")
    fig.tight_layout()
    return _save(fig, path, plt)


def _poles_zeros_figure(analyses: dict, names: list[str], path: Path) -> Path:
    """Poles and zeros of each model per speed in the s-plane at the physical scale (physical_scale);
    those beyond OFF_SCALE x the top measured angular frequency drawn at the edge and listed."""
    roots = {v: {n: (f.poles, f.zeros) for n, f in a["fits"].items()} for v, a in analyses.items()}
    w_top = 2 * np.pi * max(float(np.max(a["frf"].freq)) for a in analyses.values())
    fig, axes = plt.subplots(1, len(names), figsize=(3.8 * len(names), 5.2), squeeze=False)
    colours = plt.get_cmap("tab10")
    speeds = sorted(analyses)
    for ax, name in zip(axes[0], names):
        points = [q for q in root_points(roots) if q[1] == name]
        far = off_scale(points, w_top)
        lim = physical_scale(points, w_top)
        for v, _, kind, p in points:
            colour = colours(speeds.index(v))
            if (v, name, kind, p) in far:            # off scale: an arrow at the edge, listed below
                x = float(np.clip(p.real, -lim, lim))
                y = float(np.clip(p.imag, -lim, lim))
                ax.plot(x, y, "<" if p.real < 0 else ">", color=colour, ms=7, mfc="none" if kind == "zero" else colour)
                continue
            ax.plot(p.real, p.imag, "x" if kind == "pole" else "o", mfc="none" if kind == "zero" else colour,
                    color=colour, ms=7, mew=1.5)
            if kind == "zero" and p.real > 0:
                ax.annotate("RHP zero", (p.real, p.imag), fontsize=7, xytext=(0, 6), textcoords="offset points",
                            ha="center")
        for i, v in enumerate(speeds):
            ax.plot([], [], "s", color=colours(i), label=f"{v:g} m/s")
        ax.set_xlim(-lim, lim), ax.set_ylim(-lim, lim), ax.set_aspect("equal", adjustable="box")
        ax.axvline(0, color="k", lw=0.5), ax.axhline(0, color="k", lw=0.3)
        ax.grid(alpha=0.3), ax.set_title(f"{name}: x poles, o zeros", fontsize=9)
        ax.set_xlabel("real part [rad/s]"), ax.set_ylabel("imaginary part [rad/s]")
        ax.legend(fontsize=7, loc="upper left")
        text = [f"off scale (|s| > {OFF_SCALE * w_top:.0f} rad/s), at the edge:"] + [_root_text(q) for q in far] \
            if far else ["all poles and zeros on scale"]
        ax.text(0.0, -0.18, "\n".join(text), transform=ax.transAxes, fontsize=7, va="top", ha="left")
    fig.suptitle(f"Poles and zeros at the physical scale (up to {OFF_SCALE:g} x the top measured frequency, "
                 f"{w_top / (2 * np.pi):.2g} Hz); RHP: right half-plane (non-minimum phase)", fontsize=9)
    fig.tight_layout(rect=(0, 0.1, 1, 1))        # room below for the off-scale lists
    return _save(fig, path, plt)


def _save(fig, path: Path, plt) -> Path:
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
