"""``margins`` and ``tune``: the analysis tools' sub-commands.

Imported where used: agrobot.analysis.margin_plots (start-up: it loads matplotlib.pyplot, about 1.1 s here, on
every command, ``--help`` included; the Bode and Nyquist plots alone need it), agrobot.api (start-up: 0.1 s, measured
with ``python3 -X importtime -m agrobot --help``; the margins and tune commands' runs alone need it).
"""
from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

from pydantic import BaseModel, ConfigDict, field_validator

from agrobot.orchestrator.cli import add_output_options, add_set_option
from agrobot.orchestrator.observers import PROGRESS
from agrobot.orchestrator.study import StudyError

from .margins_simulation import simulated_delay_limit
from .tune import Targets


def _progress(line: str) -> None:
    if PROGRESS["shown"]:
        print(line, flush=True)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("study", type=Path, help="a guidance study: tracker, yaw-rate controller, steering, yaw plant, "
                   "a reference (figure-8 or field route)")
    add_set_option(p)
    add_output_options(p, "write the Bode and Nyquist plots (bode*.png, nyquist*.png) and margins.json here",
                       required=False, plots=True)
    p.add_argument("--simulate", action="store_true", help="also find the steering command delay at which the "
                   "simulation loses stability (bisection, each run printed)")
    p.add_argument("--duration", type=float, default=160.0, help="simulated seconds per run of --simulate "
                   "(default 160)")


def _simulated_lines(analysis, duration: float) -> list[str]:
    """Bisection on the steering command delay around the prediction at the reference's first
    operating point (the figure-8's path, a route's work speed: where a run spends its time)."""
    an = analysis.anatomy
    main = analysis.points[0]
    predicted = main.delay_limit
    _progress(f"\nsimulating pairs of {duration:.0f} s runs of the study with the steering command delayed "
              f"(predicted loss of stability at {predicted:.3f} s at {main.op.speed:g} m/s) ...")
    start = time.perf_counter()
    lo, hi, runs = simulated_delay_limit(analysis.study, an, predicted, duration, progress=_progress)
    ratio = f"{lo / predicted:.2f} .. {hi / predicted:.2f}" if math.isfinite(hi) and predicted > 0 else "n/a"
    lines = ["", "steering command delay at which the loop loses stability"]
    for r in analysis.points:
        lines.append(f"  predicted at {r.op.speed:g} m/s ({r.op.label}, closed-loop poles):{r.delay_limit:>10.3f} s")
    lines.append(f"  simulated ({len(runs)} pairs of runs, {time.perf_counter() - start:.0f} s):"
                 f"{'':>14}{lo:.3f} .. {hi:.3f} s   (simulated / predicted {ratio})")
    lines.append("  (the steering's dead zones and potentiometer steps, left out of the linear model, lower the "
                 "simulated limit by up to about 20 %)")
    return lines


def run(args: argparse.Namespace) -> int:
    """Parse, analyse through agrobot.api, print."""
    from agrobot.api import margins

    if not args.duration > 0:
        raise StudyError(f"--duration {args.duration:g}: expected a positive number of seconds")
    found = margins(args.study, args.set, args.out, progress=_progress, overwrite=args.overwrite,
                    plots=not args.no_plots)
    print(found.report())
    if args.out is not None:
        print(f"\nwritten to {args.out}/ ({', '.join(found.files)})")
    else:
        print("\n(--out DIR writes the Bode and Nyquist plots; --simulate checks the delay limit in simulation)")
    if args.simulate:
        print("\n".join(_simulated_lines(found.analysis, args.duration)))
    return 0


# --- tune ------------------------------------------------------------------------------------

def add_tune_arguments(p: argparse.ArgumentParser) -> None:
    t = Targets()
    p.add_argument("study", type=Path, help="a guidance study (its yaw plant: the tractor as identified)")
    add_output_options(p, "the tuned study file to write (.toml): it extends STUDY", file=True)
    add_set_option(p)
    p.add_argument("--delay-margin", type=float, default=t.delay, metavar="S",
                   help=f"extra steering delay the loop must tolerate [s] (default {t.delay:g})")
    p.add_argument("--phase-margin", type=float, default=t.phase_deg, metavar="DEG",
                   help=f"phase margin at the steering command [deg] (default {t.phase_deg:g})")
    p.add_argument("--gain-margin", type=float, default=t.gain_db, metavar="DB",
                   help=f"gain margin at the steering command [dB] (default {t.gain_db:g})")
    p.add_argument("--along-track-error", type=float, default=t.along_track, metavar="M",
                   help=f"time-based reference: the largest steady along-track error the speed law may leave [m] "
                        f"(default {t.along_track:g})")
    p.add_argument("--identified", type=Path, default=None, metavar="IDENTIFICATION_JSON",
                   help="an `identify` result: its fitted model becomes the plant and the yaw-rate controller's model")
    p.add_argument("--model", default="second_order", help="the fitted model of --identified to use (default second_order)")
    p.add_argument("--grid", type=float, default=1.0, help="density of the searched grid of gains (default 1; "
                   "0.5: a quarter of the candidates for two gains)")
    p.add_argument("--no-simulation", action="store_true", help="skip the simulated check of the proposal")
    p.add_argument("--duration", type=float, default=160.0, help="simulated seconds per run (default 160)")


def run_tune(args: argparse.Namespace) -> int:
    """Parse, tune through agrobot.api, print (the simulated check after the file is written)."""
    from agrobot.api import tune

    found = tune(args.study, args.set, args.out, delay_margin=args.delay_margin, phase_margin=args.phase_margin,
                 gain_margin=args.gain_margin, along_track_error=args.along_track_error, identified=args.identified,
                 model=args.model, grid=args.grid, simulate=False, duration=args.duration, overwrite=args.overwrite,
                 progress=_progress)
    print("\n" + found.comparison())
    print(f"\nwritten to {args.out} (extends {args.study})")
    if not args.no_simulation:
        print("\n".join(found.simulate(args.duration, _progress)))
    return 0


class OutputSettings(BaseModel):
    """``[output]``: what a run's MCAP and live view show (analysis.mcap_scene)."""

    model_config = ConfigDict(extra="forbid")
    origin: tuple[float, float] | None = None     # (lat, lon) degrees of the simulation frame's origin, on the map
    mcap: bool = False                            # write the run's MCAP (run.mcap; in a sweep, one per point)

    @field_validator("origin")
    @classmethod
    def _on_earth(cls, value):
        if value is not None and not (-90.0 <= value[0] <= 90.0 and -180.0 <= value[1] <= 180.0):
            raise ValueError(f"origin {list(value)}: expected [latitude, longitude] in degrees "
                             f"(latitude within +-90, longitude within +-180)")
        return value


def register(registry) -> None:
    registry.add_section("output", "the run's MCAP and live view (analysis.mcap_scene): origin = [lat, lon] in "
                                   "degrees places the simulation frame on the map", OutputSettings)
    registry.add_command("margins", "gain, phase and delay margins of a study's guidance loop from its own components "
                         "(Bode and Nyquist plots with --out; the simulated delay limit with --simulate)",
                         add_arguments, run)
    registry.add_command("tune", "tracker gains from the study's plant that meet delay, phase and gain margin targets, "
                         "written as a study that extends it and checked in simulation", add_tune_arguments, run_tune)
