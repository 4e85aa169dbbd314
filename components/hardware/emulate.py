"""``python -m agrobot emulate STUDY --nmea-port PORT``: run a study holding an
``nmea_server`` in real time until its stop time or until interrupted (Ctrl-C, SIGTERM); the
signals recorded so far are written either way, and the exit status is 130 (Ctrl-C) or 143
(SIGTERM). The command parses, calls agrobot.api.emulate and prints.

Imported where used: agrobot.api (start-up: it loads the results' modules, on every command,
``--help`` included; only the emulate command's run needs it)."""
from __future__ import annotations

import argparse
from pathlib import Path

from agrobot.orchestrator.cli import add_output_options, add_set_option
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study

from .can_link import binding
from .record import record_adapters, record_folder


def emulated_study(study: Study, nmea_port: int, duration: float | None, record: Path | None):
    """(the study served in real time on ``nmea_port``, its model, the NMEA server's name, the files
    the user named): ``duration`` its stop time, ``record`` the buses recorded as a field log."""
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
    return study, model, server, named


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
    """Parse, emulate through agrobot.api (until the end), print how it ended."""
    from agrobot.api import emulate

    done = emulate(args.study, args.nmea_port, args.set, args.out, duration=args.duration, record=args.record,
                   overwrite=args.overwrite, progress=not args.no_progress,
                   announce=lambda line: print(line, flush=True))
    print(done.stopped or done.summary, flush=True)
    return done.exit_status


def register(registry) -> None:
    registry.add_command("emulate", "serve a simulated tractor in real time over NMEA/TCP and CAN", add_arguments, run)
