"""Bode and Nyquist plots of a study's guidance loops with their margins marked (analysis.margins)."""
from __future__ import annotations

import math
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np

from .margins import LOOPS, Analysis, Margins, PointResult

COLOURS = {"whole loop": "tab:blue", "yaw-rate loop": "tab:orange", "path loop": "tab:green"}


def _grid(dt: float) -> np.ndarray:
    return np.logspace(-2, math.log10(0.999 * math.pi / dt), 1500)


def _phase_deg(L: np.ndarray) -> np.ndarray:
    """Unwrapped phase in degrees, shifted by whole turns so that it reads in (-360, 0] where |L|
    crosses 1 (else at the lowest frequency)."""
    ph = np.degrees(np.unwrap(np.angle(L)))
    mag = np.abs(L)
    cross = np.flatnonzero(np.sign(mag[:-1] - 1) != np.sign(mag[1:] - 1))
    ref = ph[cross[0]] if len(cross) else ph[0]
    return ph - 360.0 * math.ceil(ref / 360.0)


def bode(result: PointResult, title: str, path: Path) -> Path:
    matplotlib.use("Agg")
    fig, axes = plt.subplots(2, 3, figsize=(15, 7.5), sharex="col")
    for col, (name, loop) in enumerate(result.open_loops.items()):
        m: Margins = result.loops[name]
        w = _grid(loop.dt)
        L = -loop.response(w)
        mag, ph = 20 * np.log10(np.abs(L)), _phase_deg(L)
        ax_m, ax_p = axes[0, col], axes[1, col]
        colour = COLOURS[name]
        ax_m.semilogx(w, mag, color=colour)
        ax_p.semilogx(w, ph, color=colour)
        ax_m.axhline(0.0, color="k", lw=0.6)
        turns = np.unique(np.round((ph[np.abs(ph) < 1e4] + 180.0) / 360.0))
        for k in turns[:3]:
            ax_p.axhline(-180.0 + 360.0 * k, color="k", lw=0.6, ls=":")
        if np.isfinite(m.crossover):
            pc = float(np.interp(m.crossover, w, ph))
            floor = pc - m.phase_deg
            ax_m.plot([m.crossover], [0.0], "o", color="crimson")
            ax_p.plot([m.crossover, m.crossover], [floor, pc], color="crimson", lw=2)
            ax_p.plot([m.crossover], [pc], "o", color="crimson")
            ax_p.annotate(f"PM {m.phase_deg:.1f} deg at {m.crossover:.2f} rad/s\ndelay margin {m.delay:.3f} s",
                          (m.crossover, 0.5 * (floor + pc)), xytext=(8, 0), textcoords="offset points",
                          color="crimson", fontsize=9, va="center")
        if np.isfinite(m.gain):
            gm_db = -m.gain_db
            wp = max(m.phase_crossover, w[0])                 # w = 0 (a static gain) at the left edge
            where = f"{m.phase_crossover:.2f} rad/s" if m.phase_crossover > 0 else "0 rad/s (static gain)"
            ax_m.plot([wp, wp], [gm_db, 0.0], color="purple", lw=2)
            ax_m.plot([wp], [gm_db], "o", color="purple")
            ax_m.annotate(f"GM {m.gain_db:.1f} dB ({m.gain:.2f}x)\nat {where}",
                          (wp, 0.5 * gm_db), xytext=(8, 0), textcoords="offset points",
                          color="purple", fontsize=9, va="center")
            ax_p.plot([wp], [float(np.interp(wp, w, ph))], "o", color="purple")
        ax_m.set_title(f"{name}: opened at the {LOOPS[name]}", fontsize=10)
        ax_m.set_ylim(min(max(-80.0, mag.min() - 5), -5.0), max(min(80.0, mag.max() + 5), 5.0))
        lo = np.min(ph[w > w[0] * 3]) if len(ph) else -360
        ax_p.set_ylim(max(lo - 20, -720), min(np.max(ph) + 20, 180))
        ax_p.set_xlabel("angular frequency [rad/s]")
        ax_m.grid(True, which="both", alpha=0.3)
        ax_p.grid(True, which="both", alpha=0.3)
        ax_p.axvline(math.pi / loop.dt, color="grey", lw=0.6)
    axes[0, 0].set_ylabel("|L| [dB]")
    axes[1, 0].set_ylabel("arg L [deg]")
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def nyquist(result: PointResult, title: str, path: Path) -> Path:
    matplotlib.use("Agg")
    fig, axes = plt.subplots(1, 3, figsize=(15, 5.4))
    circle = np.exp(1j * np.linspace(0, 2 * math.pi, 361))
    for ax, (name, loop) in zip(axes, result.open_loops.items()):
        m: Margins = result.loops[name]
        w = _grid(loop.dt)
        L = -loop.response(w)
        colour = COLOURS[name]
        ax.plot(L.real, L.imag, color=colour, label=r"$L(e^{j\omega T})$, $\omega > 0$")
        ax.plot(L.real, -L.imag, color=colour, ls="--", lw=0.8, label=r"$\omega < 0$")
        ax.plot(circle.real, circle.imag, color="grey", lw=0.6)
        ax.plot([-1], [0], "x", color="k", ms=9, mew=2)
        if np.isfinite(m.crossover):
            Lc = -loop.response(np.array([m.crossover]))[0]
            arc = np.exp(1j * np.linspace(math.pi, math.pi + math.radians(m.phase_deg), 60))
            ax.plot(arc.real, arc.imag, color="crimson", lw=2.5)
            ax.plot([Lc.real], [Lc.imag], "o", color="crimson")
            ax.annotate(f"PM {m.phase_deg:.1f} deg", (Lc.real, Lc.imag), xytext=(6, -14), textcoords="offset points",
                        color="crimson", fontsize=9)
        if np.isfinite(m.gain):
            ax.plot([-1.0 / m.gain], [0.0], "o", color="purple")
            ax.annotate(f"GM {m.gain:.2f}x ({m.gain_db:.1f} dB)", (-1.0 / m.gain, 0.0), xytext=(4, 8),
                        textcoords="offset points", color="purple", fontsize=9)
        ax.axhline(0, color="k", lw=0.4)
        ax.axvline(0, color="k", lw=0.4)
        ax.set_xlim(-3.0, 1.5)
        ax.set_ylim(-2.25, 2.25)
        ax.set_aspect("equal")
        ax.set_title(f"{name}: opened at the {LOOPS[name]}", fontsize=10)
        ax.set_xlabel("Re L")
        ax.grid(True, alpha=0.3)
        outside = np.mean((np.abs(L.real) > 3) | (np.abs(L.imag) > 2.25))
        if outside > 0.01:
            ax.text(0.02, 0.02, "low frequencies leave the frame (integrators)", transform=ax.transAxes, fontsize=8,
                    color="grey")
    axes[0].set_ylabel("Im L")
    axes[0].legend(loc="upper left", fontsize=8)
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_plots(analysis: Analysis, out: Path) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    files = []
    for r in analysis.points:
        what = (f"{analysis.study.study.name}, tracker {analysis.study.components[analysis.anatomy.tracker].type}: "
                f"the loop gain L linearised on a straight at {r.op.speed:g} m/s ({r.op.label} speed), margins marked")
        suffix = f"_{r.op.label}" if len(analysis.points) > 1 else ""
        files.append(bode(r, what, out / f"bode{suffix}.png"))
        files.append(nyquist(r, what, out / f"nyquist{suffix}.png"))
    return files
