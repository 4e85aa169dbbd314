"""``python -m agrobot emulate STUDY --nmea-port PORT``: run a study holding an
``nmea_server`` in real time until its stop time or until interrupted (Ctrl-C, SIGTERM); the
signals recorded so far are written either way, and the exit status is 130 (Ctrl-C) or 143
(SIGTERM)."""
from __future__ import annotations

import argparse
from pathlib import Path

from agrobot.orchestrator.cli import add_output_options, add_set_option
from agrobot.orchestrator.engine import RunError
from agrobot.orchestrator.errors import Interrupted, Terminated, install_signal_handlers
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.study import Study, StudyError

from .can_link import binding
from .record import record_adapters, record_folder


def emulate(study_path: Path, nmea_port: int, out: Path | None, overrides: list[str], duration: float | None,
            record: Path | None = None, overwrite: bool = False, progress: bool = True) -> int:
    if not 0 <= nmea_port <= 65535:
        raise StudyError(f"--nmea-port {nmea_port}: expected a TCP port, 0-65535")
    if duration is not None and not duration > 0:
        raise StudyError(f"--duration {duration:g}: expected a positive number of seconds")
    study = Study.load(study_path, overrides)
    model = resolve(study)
    server = model.one(role="nmea_server", purpose="emulate")
    values = {f"{server}.port": nmea_port, "study.realtime": True}
    if duration is not None:
        values["study.stop_time"] = float(duration)
    study = study.with_values(values)
    named: tuple[Path, ...] = ()
    if record is not None:             # the receiver's NMEA with host stamps and the CAN bus, as a field log has them
        study = record_adapters(study, record_folder(record))
        named = (record / "gps.nmea", record / "can.log")
    install_signal_handlers()                   # SIGTERM ends the run like Ctrl-C: partial results are kept
    print(f"emulating {study.study.name}: {reach(study, model, server, nmea_port)}, real time, until "
          f"t = {study.study.stop_time:g} s or Ctrl-C", flush=True)
    try:
        result = run_study(study, out, plots=False, overwrite=overwrite, progress=progress, named=named)
    except Interrupted as exc:
        print(f"emulator stopped {exc}", flush=True)
        return exc.exit_status
    except RunError as exc:
        cause = exc.__cause__
        print(f"emulator stopped: {exc}", flush=True)
        if isinstance(cause, KeyboardInterrupt):
            return 143 if isinstance(cause, Terminated) else 130
        return 1
    print(result.summary, flush=True)
    return 0


def reach(study, model, server: str, nmea_port: int) -> str:
    """Where the emulator listens, as its components bind: the NMEA server's host and port, and each
    CAN link's bus (python-can's udp_multicast listens on every interface)."""
    host = study.components[server].parameters.get("host", "127.0.0.1")
    parts = [f"NMEA on {host}:{nmea_port}" + ("" if str(host).startswith("127.") else " (reachable from other hosts)")]
    for link in model.find(role="tractor_link"):
        p = study.components[link].parameters if link in study.components else {}
        parts.append(binding(p.get("interface", "virtual"), p.get("channel", "agrobot"), p.get("port", 0)))
    return "; ".join(parts)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("study", type=Path, help="a study with an nmea_server, e.g. studies/tractor_emulator.toml")
    p.add_argument("--nmea-port", type=int, required=True, help="TCP port for NMEA clients (on the nmea_server's host, 127.0.0.1 by default)")
    add_output_options(p, "write the emulated tractor's signals here", required=False)
    p.add_argument("--duration", type=float, default=None, help="stop after this many seconds")
    p.add_argument("--record", type=Path, default=None, metavar="DIR",
                   help="record the buses as a field log: DIR/gps.nmea (host-stamped NMEA) and DIR/can.log (candump)")
    add_set_option(p)


def run(args: argparse.Namespace) -> int:
    return emulate(args.study, args.nmea_port, args.out, args.set, args.duration, args.record, args.overwrite,
                   not args.no_progress)


def register(registry) -> None:
    registry.add_command("emulate", "serve a simulated tractor in real time over NMEA/TCP and CAN", add_arguments, run)
