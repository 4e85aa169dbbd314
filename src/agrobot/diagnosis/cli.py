"""``diagnose``: the diagnosis tool's sub-command.

``python -m agrobot --help`` loads this module; a deferred import's cost is measured on top of what
that loads already.

Imported where used: agrobot.diagnosis.pipeline (start-up: 0.75-0.85 s on every command, the replay,
fitting and figure stack), agrobot.diagnosis.report (start-up: 0.7 s on every command, matplotlib).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from agrobot.api import diagnose
from agrobot.measurements.cli import add_mode_options, add_recording_options, recording_options
from agrobot.measurements.recording import describe
from agrobot.orchestrator.cli import add_output_options
from agrobot.orchestrator.observers import timed_progress


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("log", type=Path, help="measured log (.csv/.parquet): t, delta_cmd, delta, v, yaw_rate, x, y; "
                   "or a raw recording: a folder of *.nmea files and CAN logs (*.log candump, *.asc, *.blf)")
    p.add_argument("--study", type=Path, default=None, help="baseline study (default: studies/figure8.toml)")
    add_output_options(p, "output folder (diagnosis.json, report.md, figures)", plots=True)
    p.add_argument("--fit-fraction", type=float, default=0.6, help="share of the log used to fit; the rest is held out")
    p.add_argument("--min-gain", type=float, default=0.05, help="least held-out RMS reduction to accept an extension")
    p.add_argument("--resample", action="store_true",
                   help="interpolate a log whose clock jitters onto an even grid (its median step)")
    p.add_argument("--no-identify", action="store_true",
                   help="do not identify the vehicle on the same log first (faster: the report then has no "
                        "identified vehicle beside the study's, and tyre saturation is judged by the diagnosis alone)")
    p.add_argument("--split", choices=("auto", "tail", "blocks"), default="auto",
                   help="what is held out: the log's last part (tail, the --fit-fraction rest), every third 10 s "
                        "(blocks), or auto (default): blocks when the last part is driven beyond the first's conditions "
                        "(lateral acceleration or speed 1.5 x higher), said in the warnings")
    p.add_argument("--steering-geometry", choices=("auto", "w", "tan"), default="auto",
                   help="the yaw model driven by the wheel angle (w) or its tangent (tan: the turn without slip "
                        "v tan(delta) / L); auto (default): the study's yaw plant steering_geometry if it sets one, "
                        "else the one identify chooses on the log (w without --no-identify's identification)")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="processes for the candidate fits (default: every core); the result is the same whatever N")
    p.add_argument("--no-screen", action="store_true",
                   help="fit every pair of effects, also those whose linearised gain cannot be supported (slower; "
                        "the screen's decisions are in diagnosis.json's selection_trace)")
    p.add_argument("--mcap", action="store_true", help="also write diagnosis.mcap: the measured stages, the "
                   "baseline's and the final model's replays and residuals on one time axis (Foxglove, PlotJuggler)")
    add_mode_options(p)
    add_recording_options(p)


def run(args: argparse.Namespace) -> int:
    """Exit 0 with a verdict (the strongest effect, 'unexplained' or 'none'); 2 when the log or study cannot be used (the
    verdict 'cannot decide' and the reason are still written)."""
    from .pipeline import CANNOT_DECIDE

    result = diagnose(args.log, args.study, args.out, fit_fraction=args.fit_fraction, min_gain=args.min_gain,
                      plots=not args.no_plots, resample=args.resample, recording=recording_options(args),
                      progress=timed_progress(), mcap=args.mcap, identify=not args.no_identify, split=args.split,
                      overwrite=args.overwrite, workers=args.workers, screen=not args.no_screen,
                      steering_geometry=args.steering_geometry).result
    if result.get("recording"):
        print(describe(result["recording"]))
    for note in result.get("before_verdict", []):
        print(f"before the verdict: {note}")
    if result["verdict"] == CANNOT_DECIDE:
        print(f"error: {result['reason']}\nverdict: {CANNOT_DECIDE} (written to {args.out}/diagnosis.json)", file=sys.stderr)
        return 2
    print(f"verdict: {result['verdict']} ({result['verdict_status']}): {result['verdict_statement']}")
    for bullet in result.get("verdict_bullets", []):
        print(f"  - {bullet}")
    from .report import vehicle_lines

    for line in vehicle_lines(result.get("identified_vehicle"), result.get("understeer_note")):
        if line and not line.startswith(("|---", "## ")):
            print("  " + line)
    for e in result["effects"]:
        if e["id"] == "unexplained":
            xc, ext = e["correlates_with"], e["extension"]
            print(f"  unexplained in the {e['stage']} stage ({e['ratio_to_floor']:.1f} x its noise floor; also: "
                  f"{', '.join(s for s in e['stages'] if s != e['stage']) or 'none'}): correlates with {xc['signal']} "
                  f"(rho {xc['rho']:.2f}); data-driven {ext['kind']} on {ext['signal']}: held-out gain "
                  f"{100 * ext['held_out_gain']:.0f}%")
            continue
        print(f"  {e['id']:26s} dBIC {e['delta_bic']:9.1f}  held-out gain {100 * e['held_out_gain']:5.1f}%  "
              + ", ".join(f"{k} = {v:.4g}" for k, v in e["parameters_display"].items()))
    for tie in result.get("inconclusive", []):
        print(f"  inconclusive: {' or '.join(tie['effects'])}: {tie['why']}; {tie['experiment']}")
    for w in result.get("warnings", []):
        print(f"warning: {w}", file=sys.stderr)
    print(f"report: {args.out}/report.md" + (f", extended study: {args.out}/{result['extended_study']}"
                                             if "extended_study" in result else ""))
    return 0


def register(registry) -> None:
    registry.add_command("diagnose", "name what the simulation gets wrong about a measured log", add_arguments, run)
