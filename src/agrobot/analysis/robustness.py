"""Monte Carlo robustness of the figure-8: P50, P95 and max of the straight and curved
maximum errors, the fraction of runs within the paper's bounds (over all runs and over those with
at most 0.1 s of actuator delay), and the max error against the actuator delay.

Sweep analysis hooks: ``plots(table, study, out_dir)`` writes ``max_error_vs_delay.png`` and
``robustness.json``; ``summary(table, study)`` is what the sweep prints of them (the P50/P95 of the
errors are in the sweep's own table of key figures)."""
from __future__ import annotations

import json
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.ticker import StrMethodFormatter

from agrobot.orchestrator.atomic_files import write_json
from agrobot.orchestrator.sweep_judgement import ratio_column

from .figure8 import OSCILLATION, PAPER_BOUNDS

DELAY = "steering.command_delay"
REQUIRED_DELAY = 0.1          # s: the bounds must hold up to here; beyond it is reported
HUNTING = ratio_column(OSCILLATION[0])      # the sweep's oscillation ratio (orchestrator.sweep_judgement)
OSCILLATION_RATIO = OSCILLATION[1]


def hunting(table: pd.DataFrame) -> np.ndarray:
    """The completed runs whose steering rate is beyond the sweep's oscillation bound (none when
    the table has no ratio to the nominal run)."""
    if HUNTING not in table:
        return np.zeros(len(table), dtype=bool)
    return ((table["status"] == "completed") & (table[HUNTING] > OSCILLATION_RATIO)).to_numpy()


def within(table: pd.DataFrame) -> np.ndarray:
    ok = table["status"] == "completed"
    return (ok & (table["euclid_max_straight"] < PAPER_BOUNDS["euclid_max_straight"])
            & (table["euclid_max_curved"] < PAPER_BOUNDS["euclid_max_curved"])).to_numpy()


def summarise(table: pd.DataFrame) -> dict:
    """Percentiles of both errors over completed runs, fractions within bounds (failed runs count
    as out of bounds)."""
    done = table[table["status"] == "completed"]
    out: dict = {"runs": int(len(table)), "failed": int((table["status"] != "completed").sum())}
    for key in ("euclid_max_straight", "euclid_max_curved"):
        x = done[key].to_numpy()
        out[key] = {"p50": float(np.percentile(x, 50)), "p95": float(np.percentile(x, 95)),
                    "max": float(x.max())} if len(x) else None
    inside = within(table)
    out["within_bounds"] = float(inside.mean()) if len(table) else float("nan")
    out["hunting"] = int(hunting(table).sum())
    if DELAY in table:
        low = (table[DELAY] <= REQUIRED_DELAY).to_numpy()
        out["within_bounds_delay_le_0.1s"] = float(inside[low].mean()) if low.any() else float("nan")
    return out


def summary(table: pd.DataFrame, study) -> str:
    """The fractions of runs within both of the paper's bounds, over all runs and up to the
    required actuator delay."""
    s = summarise(table)
    text = f"within both of the paper's bounds: {s['within_bounds']:.0%} of {s['runs']} runs"
    if "within_bounds_delay_le_0.1s" in s:
        low = int((table[DELAY] <= REQUIRED_DELAY).sum())
        text += f"; {s['within_bounds_delay_le_0.1s']:.0%} of the {low} with {DELAY} <= {REQUIRED_DELAY:g} s"
    if HUNTING in table:
        text += (f"\nhunting (steering rate over {OSCILLATION_RATIO:g} x the nominal run's): {s['hunting']} of "
                 f"{s['runs']} runs")
    return text


def plots(table: pd.DataFrame, study, out_dir: Path) -> list[Path]:
    matplotlib.use("Agg")
    out_dir = Path(out_dir)
    summary = summarise(table)
    written = [write_json(out_dir / "robustness.json", {"study": study.study.name, **summary})]
    done = table[table["status"] == "completed"]
    if DELAY not in done or done.empty:
        return written
    fig, ax = plt.subplots(figsize=(7, 4))
    delay_ms = 1000 * done[DELAY]
    ax.scatter(delay_ms, done["euclid_max_straight"], s=10, label="max error, straights")
    ax.scatter(delay_ms, done["euclid_max_curved"], s=10, marker="x", label="max error, curves")
    hunt = hunting(done)
    if hunt.any():
        ax.scatter(delay_ms[hunt], done["euclid_max_curved"][hunt], s=60, facecolors="none", edgecolors="tab:red",
                   label=f"hunting: steering rate > {OSCILLATION_RATIO:g} x nominal ({int(hunt.sum())})")
    ax.axhline(PAPER_BOUNDS["euclid_max_straight"], color="C0", ls="--", lw=1, label="paper bound, straights (0.40 m)")
    ax.axhline(PAPER_BOUNDS["euclid_max_curved"], color="C1", ls="--", lw=1, label="paper bound, curves (0.60 m)")
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(StrMethodFormatter("{x:g}")), ax.yaxis.set_minor_formatter(StrMethodFormatter("{x:g}"))
    ax.set_xlabel("actuator delay steering.command_delay [ms]")
    ax.set_ylabel("max Euclidean error [m]")
    ax.set_title(f"{study.study.name}: {summary['within_bounds']:.0%} of {summary['runs']} runs within bounds")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    path = out_dir / "max_error_vs_delay.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return written + [path]


def compare(tables: dict[str, pd.DataFrame], out: Path) -> Path:
    """One figure: each run's max error over its bound, the larger of straight / 0.40 m and curved /
    0.60 m (within the bounds below 1), against the delay, one colour per study."""
    matplotlib.use("Agg")
    fig, ax = plt.subplots(figsize=(7, 4))
    for i, (name, table) in enumerate(tables.items()):
        done = table[table["status"] == "completed"]
        worst = np.maximum(done["euclid_max_straight"] / PAPER_BOUNDS["euclid_max_straight"],
                           done["euclid_max_curved"] / PAPER_BOUNDS["euclid_max_curved"])
        ax.scatter(1000 * done[DELAY], worst, s=10, color=f"C{i}", label=f"{name}: {within(table).mean():.0%} within")
    ax.axhline(1.0, color="tab:red", ls="--", lw=1.2, label="the paper's bounds (0.40 m straights, 0.60 m curves)")
    ax.axvline(1000 * REQUIRED_DELAY, color="0.5", ls=":", lw=1, label=f"required up to {1000 * REQUIRED_DELAY:.0f} ms")
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(StrMethodFormatter("{x:g}")), ax.yaxis.set_minor_formatter(StrMethodFormatter("{x:g}"))
    ax.set_xlabel("actuator delay steering.command_delay [ms]")
    ax.set_ylabel("max Euclidean error / its bound [-]")
    ax.set_title("Worst of straight and curve against its bound", fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def load(folder: Path) -> dict:
    return json.loads((Path(folder) / "plots" / "robustness.json").read_text())
