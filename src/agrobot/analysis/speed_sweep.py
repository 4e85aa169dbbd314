"""Speed sweep plots (paper section IV-C, Fig. 'poles and zeroes at 1 and 2 m/s', extended to the
swept range): poles and zeros of the physical yaw models against speed, and the steady-state
yaw-rate gain against speed."""
from __future__ import annotations

from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from agrobot.components.models.yaw_dynamics import PHYSICAL_MODELS, TractorParameters, state_space, transfer_function
from agrobot.components.models.paper_models import G_2ND
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study

from .signal_roles import component_named



def tractor_parameters(study: Study) -> TractorParameters:
    return TractorParameters.of(resolve(study).parameters(component_named(study, "yaw_plant")))


def poles_zeros(model: str, p: TractorParameters, v: float) -> tuple[np.ndarray, np.ndarray]:
    """Poles = eig(A); zeros = roots of the numerator of C (sI-A)^-1 B."""
    num, _ = transfer_function(model, p, v)
    return np.linalg.eigvals(state_space(model, p, v)[0]), np.roots(num)


def dc_gain(model: str, p: TractorParameters, v: float) -> float:
    A, B, C = state_space(model, p, v)
    return float(-C @ np.linalg.solve(A, B))


def speed_column(table: pd.DataFrame, study: Study) -> str:
    column = f"{component_named(study, 'reference')}.speed"
    if column not in table:
        raise KeyError(f"the sweep does not vary {column!r}")
    return column


def plots(table: pd.DataFrame, study: Study, out_dir: Path) -> list[Path]:
    matplotlib.use("Agg")
    p = tractor_parameters(study)
    col = speed_column(table, study)
    speeds = np.linspace(float(table[col].min()), float(table[col].max()), 26)
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2))
    cmap = plt.get_cmap("viridis")
    for ax, model in zip(axes, PHYSICAL_MODELS):
        imag = 1.0
        for i, v in enumerate(speeds):
            pol, z = poles_zeros(model, p, v)
            imag = max(imag, 1.15 * float(np.max(np.abs(np.concatenate([pol.imag, z.imag])), initial=0.0)))
            c = cmap(i / max(len(speeds) - 1, 1))
            ax.plot(pol.real, pol.imag, "x", color=c, ms=5)
            ax.plot(z.real, z.imag, "o", mfc="none", color=c, ms=5)
        for v, colour in ((1.0, "blue"), (2.0, "red")):          # the paper's two speeds
            pol, z = poles_zeros(model, p, v)
            ax.plot(pol.real, pol.imag, "x", color=colour, ms=9, mew=2)
            ax.plot(z.real, z.imag, "o", mfc="none", color=colour, ms=9, mew=2)
        ax.axvline(0, color="k", lw=0.5)
        ax.set_xscale("symlog", linthresh=10.0)       # slow modes near 0 and fast real ones (-400) both visible
        ax.set_xlim(-500.0, 5.0)
        ax.set_ylim(-imag, imag)            # real roots only: a 1 rad/s window, not a hair's width
        ax.set_title(f"{model}: poles x, zeros o ({speeds[0]:.2f} to {speeds[-1]:.2f} m/s)", fontsize=9)
        ax.set_xlabel("real [1/s]"), ax.set_ylabel("imag [rad/s]"), ax.grid(alpha=0.3)
    fig.suptitle("Yaw models against speed (paper's 1 m/s blue, 2 m/s red); colour: speed, dark = slow")
    fig.tight_layout()
    pz = out_dir / "poles_zeros_vs_speed.png"
    fig.savefig(pz, dpi=100)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(6.5, 4))
    for model, style in zip(PHYSICAL_MODELS, ("-", "--", ":")):
        ax.plot(speeds, [dc_gain(model, p, v) for v in speeds], style, label=model)
    ax.axhline(G_2ND.num[-1] / G_2ND.den[-1], color="grey", lw=1, label="G_2nd (identified, fixed)")
    ax.plot(speeds, speeds / (p.l_f + p.l_r), "k", lw=0.6, alpha=0.5, label="kinematic v/L")
    ax.set_xlabel("speed [m/s]"), ax.set_ylabel("steady-state yaw-rate gain [1/s]"), ax.legend(), ax.grid(alpha=0.3)
    fig.tight_layout()
    gain = out_dir / "yaw_gain_vs_speed.png"
    fig.savefig(gain, dpi=100)
    plt.close(fig)
    return [pz, gain]
