"""Command line: ``run`` and ``sweep`` are the orchestrator's; every other sub-command is
registered by a tool (orchestrator.registry). Errors become exit codes and one-line messages
through one table (orchestrator.errors).

Imported where used: orchestrator.engine, orchestrator.runner, orchestrator.output (start-up: 0.3 s of numpy
and pandas, measured from this module alone; loaded after the signal handlers, so that an interrupt while they
load ends as a named one), orchestrator.mcap_out (the same; --mcap and --live only), orchestrator.sweep (the
same and 0.03 s more; the sweep command only).
"""
from __future__ import annotations

import argparse
import contextlib
import os
import sys
import warnings
from pathlib import Path

from .errors import Terminated, exit_code, install_signal_handlers
from .observers import PROGRESS, Stage
from .registry import registry
from .study import Study, StudyError

PROG = f"python -m {__name__.split('.')[0]}"


def add_set_option(parser: argparse.ArgumentParser, help: str = "override a parameter (or study.FIELD=VALUE); repeatable") -> None:
    """The ``--set COMP.PARAM=VALUE`` option every study-taking command shares."""
    parser.add_argument("--set", action="append", default=[], metavar="COMP.PARAM=VALUE", help=help)


def add_engine_option(parser: argparse.ArgumentParser, default: str = "auto") -> None:
    parser.add_argument("--engine", choices=("python", "compiled", "auto"), default=default,
                        help=f"python: the Python components (the reference engine); compiled: the study's whole "
                             f"loop from the components' C cores, one compiled program (every component needs one and "
                             f"a C compiler is found); auto: compiled when it can, the Python engine otherwise, saying "
                             f"which ran and why (default: {default})")
OUT_RULE = ("a new or empty folder is written; an earlier result of this command is replaced (in one step, when "
            "the command ends) only with --overwrite; anything else, or an input, is refused")


def add_output_options(parser: argparse.ArgumentParser, what: str = "output folder", required: bool = True,
                       file: bool = False, plots: bool = False, progress: bool = True) -> None:
    """The output options every command shares, spelt and checked alike (orchestrator.output):
    ``--out``, ``--overwrite``, ``--quiet``, and ``--no-plots`` / ``--no-progress`` where the
    command draws figures or reports progress."""
    rule = ("a new file is written; an existing one is replaced only with --overwrite; an input never"
            if file else OUT_RULE)
    parser.add_argument("--out", type=Path, required=required, help=f"{what}: {rule}")
    parser.add_argument("--overwrite", action="store_true", help="replace an earlier result at --out")
    if plots:
        parser.add_argument("--no-plots", action="store_true", help="skip the figures")
    if progress:
        parser.add_argument("--no-progress", action="store_true", help="no progress lines or bars")
    parser.add_argument("--quiet", action="store_true", help="print only warnings and errors (no results table, "
                        "no progress): what the command finds is in --out")


def add_isolate_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--isolate-fmus", action="store_true", help="run each FMU in a child process: a crash or a "
                        "hang (study.fmu_timeout) is a named error, Ctrl-C ends the run at once, the signals so far "
                        "are kept (as study.isolate_fmus = true)")


def _isolated(args: argparse.Namespace) -> list[str]:
    return ["study.isolate_fmus=true"] if getattr(args, "isolate_fmus", False) else []


def _run_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("study", type=Path, help="study file (.toml/.yaml)")
    add_output_options(p, "output folder (metrics.json, run.json, the signals, plots)", plots=True)
    add_set_option(p)
    p.add_argument("--mcap", nargs="?", const="", default=None, metavar="FILE",
                   help="also write the run as an MCAP file for Foxglove/PlotJuggler (default OUT/run.mcap)")
    p.add_argument("--live", nargs="?", const="127.0.0.1:8765", default=None, metavar="HOST:PORT",
                   help="serve the running study to Foxglove over its WebSocket protocol (default 127.0.0.1:8765; "
                        "the MCAP's topics at 20 instants a second of wall time)")
    p.add_argument("--live-wait", type=float, default=0.0, metavar="SECONDS",
                   help="with --live: wait up to SECONDS for a viewer to subscribe before the run starts")
    p.add_argument("--live-viewers", type=int, default=16, metavar="N",
                   help="with --live: serve at most N viewers at once (default 16, at most 64); one more is refused with the "
                        "reason")
    add_engine_option(p)
    add_isolate_option(p)
    for option in registry().run_options:
        p.add_argument(option.flag, default=None, metavar=option.metavar, help=option.help)


def _run(args: argparse.Namespace) -> int:
    chosen = [(o, getattr(args, o.flag.lstrip("-").replace("-", "_"), None)) for o in registry().run_options]
    chosen = [(o, v) for o, v in chosen if v is not None]
    if not chosen:
        study = Study.load(args.study, args.set + _isolated(args))
    else:           # a plugin's option first, so that --set also reaches what it adds (a recorder ...)
        study = Study.load(args.study)
        for option, value in chosen:
            study = option.apply(study, value)
        if args.set or _isolated(args):
            study = study.with_overrides(args.set + _isolated(args))
    mcap = _mcap_path(args, study)
    with _mcap_lock(args, mcap):
        return _run_study(args, study, mcap, tuple(Path(value) for _, value in chosen))


def _run_study(args: argparse.Namespace, study, mcap: Path | None, named: tuple[Path, ...]) -> int:
    """The run of ``_run``'s study, its report and its MCAP."""
    from .engine import RunError
    from .runner import AnalysisError, run_study

    live = _live_view(study, args.live, args.live_wait, args.live_viewers) if args.live else None
    engine = args.engine
    if live is not None and engine == "auto":
        engine = "python"
        print("engine: python (auto: --live watches every instant, which the compiled engine does not show)",
              file=sys.stderr)
    try:
        result = run_study(study, args.out, plots=not args.no_plots, overwrite=args.overwrite,
                           progress=not args.no_progress, engine=engine, observers=[live] if live else [],
                           named=named)
    except AnalysisError as exc:
        print(f"error: {exc}; the signals are in {getattr(exc, 'where', args.out)}{getattr(exc, 'kept', '')}",
              file=sys.stderr)
        return 1
    except RunError as exc:
        print(f"error: run failed {exc}; results recorded so far are in {getattr(exc, 'where', args.out)}"
              f"{getattr(exc, 'kept', '')}", file=sys.stderr)
        return 1
    finally:
        if live is not None:
            live.stop()
            print(f"live view: {live.report}")
    ended = result.metrics.get("ended_by")
    if ended:
        print(f"the run ended at t = {ended['t']:.6g} s, before the stop time: {ended['component']} asked "
              f"to terminate ({ended['reason']})")
    print(result.summary)
    for warning in result.warnings:
        print(f"warning: {warning}", file=sys.stderr)
    if result.failed_bounds:
        print("FAIL: " + "; ".join(result.failed_bounds))
    print(f"\nresults written to {args.out}/ ({', '.join(p.name for p in result.files)})")
    return _write_mcap(study, result, mcap) if mcap is not None else 0


def _live_view(study, where: str, wait: float, viewers: int):
    """The live view's server, bound where ``--live`` says (loopback unless a host is named)."""
    from .mcap_out import LiveView, counted
    from .output import OutputError

    host, _, port = where.rpartition(":")
    try:
        port_number = int(port)
    except ValueError:
        raise OutputError(f"--live {where}: expected HOST:PORT or PORT (a number), e.g. 127.0.0.1:8765") from None
    view = LiveView(study, host or "127.0.0.1", port_number, wait=wait, max_viewers=viewers)
    print(f"live view: serving {view.url} to at most {counted(viewers, 'viewer')} (Foxglove, Lichtblick: open a connection, "
          f"Foxglove WebSocket, to this address)",
          flush=True)
    return view


def _mcap_path(args: argparse.Namespace, study) -> Path | None:
    """Where ``--mcap`` writes: OUT/run.mcap by default (or with the study's ``[output] mcap = true``: it goes
    and is replaced with the folder), else the file named, checked before the run under the rule of every
    written file (orchestrator.output: an existing file only with --overwrite, an input never)."""
    from .mcap_out import check_mcap_path, wants_mcap
    from .output import study_inputs

    if args.mcap is None:
        return None if not wants_mcap(study) else args.out / "run.mcap"
    if args.mcap == "":
        return args.out / "run.mcap"
    return check_mcap_path(Path(args.mcap), args.overwrite, study_inputs(study))


def _mcap_lock(args: argparse.Namespace, path: Path | None):
    """One writer per ``--mcap FILE`` from before the run until the file is in place (orchestrator.output);
    OUT/run.mcap is under --out's own lock and staging."""
    from .output import OutputLock

    if path is None or args.mcap in (None, ""):
        return contextlib.nullcontext()
    return OutputLock(path, "--mcap")


def _write_mcap(study, result, path: Path) -> int:
    """The run's MCAP after its other results are in place: a failure here loses none of them. The signals
    are read back from the result's file block by block (memory flat in the run's length)."""
    from .mcap_out import write_study_mcap
    from .output import OutputError

    try:
        _, note = write_study_mcap(study, result.frame, path)
    except OutputError as exc:
        print(f"error: {exc}; the run's other results are in place", file=sys.stderr)
        return 2
    print(f"MCAP written to {path} (open it in Foxglove or PlotJuggler; topics: docs/foxglove.md)"
          + (f"; {note}" if note else ""))
    return 0


def _sweep_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("study", type=Path, help="study file with a [sweep] section")
    add_output_options(p, "output folder (the same command into it again resumes the sweep; --overwrite starts "
                          "afresh)", plots=True)
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1, help="worker processes (default: all cores)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="a Dask scheduler address, or 'local' to start a local Dask cluster")
    add_set_option(p)
    p.add_argument("--retry-failed", action="store_true", help="run failed points again")
    p.add_argument("--mcap", action="store_true", help="also write each point's run as points/<point>/run.mcap "
                   "(the study's [output] mcap = true does the same)")
    add_engine_option(p)
    p.add_argument("--keep-signals", nargs="?", const="all", choices=("all", "worst", "none"), default=None,
                   help="which points keep their signals: all (the option alone), worst (every point's metrics, the "
                        "signals of the 10 points farthest outside their bounds and of a sample of 10), none "
                        "(default: all up to 50 points with the Python engine, worst beyond; none with the compiled "
                        "engine, whose Monte Carlo runs thousands of points)")
    p.add_argument("--no-keep-signals", dest="keep_signals", action="store_const", const="none",
                   help="keep no point's signals (--keep-signals none)")
    p.add_argument("--accept-cost", action="store_true",
                   help="run a sweep expected to take more than 12 h or 5 GB on disk (printed before it starts; "
                        "refused without this)")
    add_isolate_option(p)


def _sweep(args: argparse.Namespace) -> int:
    from .sweep import SweepRun, sweep_plots, sweep_summary

    if args.workers < 1:
        raise StudyError("--workers must be >= 1")
    study = Study.load(args.study, args.set + _isolated(args))
    if args.mcap:
        from .mcap_out import with_mcap

        study = with_mcap(study)
    runner = SweepRun(study, args.out, args.overwrite, engine=args.engine, keep_signals=args.keep_signals,
                      accept_cost=args.accept_cost)
    try:
        table = runner.run(args.workers, args.scheduler, args.retry_failed, progress=not args.no_progress)
    except KeyboardInterrupt as exc:
        print(f"\ninterrupted: finished points are kept in {runner.kept_in}; run the same command"
              f"{'' if runner.kept_in == args.out else f' with --out {runner.kept_in}'} to resume", file=sys.stderr)
        return 143 if isinstance(exc, Terminated) else 130
    with Stage("drawing the sweep's figures"):
        files = [] if args.no_plots else sweep_plots(study, table, args.out / "plots", runner.nominal)
    text, reasons = sweep_summary(study, table, runner.nominal)
    print(text)
    print(f"\nresults in {args.out}/results.{study.study.signals_format}, one folder per point in {args.out}/points"
          + (f"; plots: {', '.join(p.name for p in files)}" if files else ""))
    if runner.keeper is not None:
        print(f"signals kept (the worst points and a sample; --keep-signals all keeps every one): "
              f"{', '.join(runner.keeper.kept())}")
    failed = sum(len(points) for _, points in reasons)
    if failed and failed == len(table) and len(reasons) == 1:
        print(f"error: every point failed: {reasons[0][0]}", file=sys.stderr)
        return 2
    return 0 if failed == 0 else 1


CORE = {"run": ("run a study file and write metrics, signals and plots", _run_arguments, _run),
        "sweep": ("run every point of a study's [sweep] section", _sweep_arguments, _sweep)}


def build_parser() -> argparse.ArgumentParser:
    invoked = Path(sys.argv[0]).name
    parser = argparse.ArgumentParser(
        prog=PROG if invoked in ("__main__.py", "-c", "") else invoked,
        description="Run co-simulation studies and sweeps, and the tools the installed project registers.")
    root = sys.modules.get(__name__.split(".")[0])
    parser.add_argument("--version", action="version",
                        version=f"%(prog)s {getattr(root, '__version__', 'unknown')} (Python {sys.version.split()[0]})")
    sub = parser.add_subparsers(dest="command", required=True)
    commands = {**{k: v for k, v in CORE.items()},
                **{c.name: (c.help, c.add_arguments, c.run) for c in registry().commands.values()}}
    for name, (help, add_arguments, run) in commands.items():
        p = sub.add_parser(name, help=help, description=help)
        add_arguments(p)
        p.set_defaults(handler=run if name in CORE else _in_stage(name, run))
    return parser


def _in_stage(name: str, run):
    """A registered command's handler inside a Stage: a tool that says nothing while it works
    still shows, after 5 s, that it is working and for how long (with what it reports through
    ``report_progress``)."""
    def handler(args: argparse.Namespace) -> int:
        with Stage(name):
            return run(args)
    return handler


def _handle(args: argparse.Namespace) -> int:
    PROGRESS["shown"] = not (getattr(args, "no_progress", False) or getattr(args, "quiet", False))
    return args.handler(args)


def _quietly(args: argparse.Namespace) -> int:
    """``--quiet``: what the command prints on stdout goes nowhere (warnings and errors, on
    stderr, still show)."""
    with open(os.devnull, "w") as sink, contextlib.redirect_stdout(sink):
        return _handle(args)


def _one_line_warning(message, category, filename, lineno, line=None) -> str:
    return f"warning: {category.__name__}: {message}\n"


def main(argv: list[str] | None = None) -> int:
    warnings.formatwarning = _one_line_warning
    install_signal_handlers()
    try:            # a signal may land while the plugins' modules load, before any command runs
        args = build_parser().parse_args(argv)
        return _quietly(args) if getattr(args, "quiet", False) else _handle(args)
    except (Exception, KeyboardInterrupt) as exc:
        known = exit_code(exc)
        if known is None:
            raise
        code, message = known
        print(message, file=sys.stderr)
        return code
