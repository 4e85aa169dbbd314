"""``python -m orchestrator emulate STUDY --nmea-port PORT``: run a study holding an
``nmea_server`` in real time until its stop time or until interrupted (Ctrl-C, SIGTERM); the
signals recorded so far are written either way."""
from __future__ import annotations

import signal
import sys
from pathlib import Path

from orchestrator.engine import RunError
from orchestrator.runner import run_study
from orchestrator.study import StudyError, load_raw, parse_study


def _interrupt(signum, frame):          # SIGTERM ends the run like Ctrl-C: partial results are kept
    raise KeyboardInterrupt


def emulate(study_path: Path, nmea_port: int, out: Path | None, overrides: list[str], duration: float | None) -> int:
    raw = load_raw(study_path, overrides)
    servers = [n for n, c in raw.get("components", {}).items() if str(c.get("type", "")).endswith("nmea_server")]
    if len(servers) != 1:
        print(f"error: {study_path}: components: emulate needs exactly one nmea_server component, found {servers}",
              file=sys.stderr)
        return 2
    raw["components"][servers[0]].setdefault("parameters", {})["port"] = nmea_port
    raw["study"]["realtime"] = True
    if duration is not None:
        raw["study"]["stop_time"] = float(duration)
    try:
        study = parse_study(raw, study_path)
    except StudyError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    signal.signal(signal.SIGTERM, _interrupt)
    print(f"emulating {study.study.name}: NMEA on 127.0.0.1:{nmea_port}, real time, until "
          f"t = {study.study.stop_time:g} s or Ctrl-C", flush=True)
    try:
        result = run_study(study, out, plots=False)
    except RunError as exc:
        print(f"emulator stopped: {exc}" + (f"; signals so far in {out}" if out else ""), flush=True)
        return 0 if "interrupted" in str(exc) else 1
    except StudyError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(result.summary, flush=True)
    return 0
