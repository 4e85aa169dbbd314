"""``--record DIR`` (``run`` and ``emulate``): record a study's tractor buses as a field logger
would, as raw NMEA (host-stamped) and a candump CAN log.

- A study serving an emulated tractor (an ``nmea_server`` or a ``tractor_link``) records what its
  adapters send and receive (their ``record_file``), in real time.
- A hardware-in-the-loop study (a ``hardware_tractor``) records what its adapters receive and send.
- A study with a simulated tractor (the component of role ``tractor``) gets a ``bus_recorder``
  wired to the tractor's outputs and to what feeds its set-point inputs: the recording takes no
  real-time wait. DIR also receives ``simulation_log.csv``, the same signals as the measured log.

Imported where used: agrobot.components.hardware_tractor (start-up: 15 ms of CPU on every command, measured:
the components plugin loads this module; the hardware tractor brings the CAN message sets and the NMEA
receiver); agrobot.orchestrator.output (the rule of written files, for a run without ``--out`` only:
the components plugin loads this module on every command).
"""
from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path

from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import StudyError

RECORDER = "bus_recorder"
FIELD_DATUM = {"datum_latitude": "50.8637 deg", "datum_longitude": "4.6782 deg", "datum_height": 60.0}   # the paper's field
# recorder input <- tractor output
FROM_TRACTOR = {"x": "gps_x", "y": "gps_y", "vel_east": "gps_vel_east", "vel_north": "gps_vel_north",
                "fix_valid": "fix_valid", "steer_angle_measured": "steer_angle_measured", "yaw_rate": "yaw_rate",
                "speed": "speed_measured", "machine_ready": "machine_ready", "machine_lockout": "machine_lockout"}
# recorder input <- the source of this tractor input
TO_TRACTOR = {"steer_angle_cmd": "steer_angle_cmd", "speed_cmd": "speed_cmd", "safe_state": "safe_state"}


def record_folder(value) -> Path:
    folder = Path(value)
    if folder.exists() and not folder.is_dir():
        raise StudyError(f"--record {folder}: is a file; expected a folder for gps.nmea and can.log")
    return folder


def record_adapters(study, folder: Path):
    """The emulator's adapters record into ``folder`` (None when the study has none)."""
    model = resolve(study)
    servers, links = model.find(role="nmea_server"), model.find(role="tractor_link")
    if not servers and not links:
        return None
    folder.mkdir(parents=True, exist_ok=True)
    values = {f"{s}.record_file": str(folder / "gps.nmea") for s in servers}
    values.update({f"{link}.record_file": str(folder / "can.log") for link in links})
    return study.with_values(values)


def record_study(study, value):
    """The study with its buses recorded into the folder ``value``."""
    folder = record_folder(value)
    adapters = record_adapters(study, folder)
    if adapters is not None:
        return adapters
    model = resolve(study)
    tractor = model.one(role="tractor", purpose="--record")
    from ..hardware_tractor import HardwareTractor

    cls = model.component_class(tractor)
    if issubclass(cls, HardwareTractor):         # hardware in the loop: what its adapters receive and send
        folder.mkdir(parents=True, exist_ok=True)
        return study.with_values({f"{tractor}.nmea_record_file": str(folder / "gps.nmea"),
                                  f"{tractor}.can_record_file": str(folder / "can.log")})
    outputs = {v.name for v in cls.variables if v.causality == "output"}
    add = [f"{tractor}.{o} -> {RECORDER}.{i}" for i, o in FROM_TRACTOR.items() if o in outputs]
    for conn in study.connections:
        if conn.target == tractor and conn.input in TO_TRACTOR.values():
            i = next(k for k, v in TO_TRACTOR.items() if v == conn.input)
            add.append(f"{conn.source}.{conn.output} -> {RECORDER}.{i}")
    if RECORDER in study.components:
        raise StudyError(f"{study.where}: --record: the study already has a component named {RECORDER!r}")
    folder.mkdir(parents=True, exist_ok=True)
    step = study.components[tractor].step if tractor in study.components else None
    params = {"nmea_record_file": str(folder / "gps.nmea"), "can_record_file": str(folder / "can.log"),
              "reference_record_file": str(folder / "simulation_log.csv"), **FIELD_DATUM}
    return study.with_component(RECORDER, type=RECORDER, step=max(0.05, step or 0.05), parameters=params) \
        .with_connections(add=add)


@contextmanager
def recordings_aside(study, overwrite: bool, record: Path | None = None):
    """``with recordings_aside(study, overwrite, record) as placed:`` a run without ``--out`` (the
    emulator's) writes every file its study names (``record_file`` parameters: the recordings of
    ``--record`` DIR) under the rule of a single written file (orchestrator.output.write_aside), kept
    when the block ends, stopped or not (what was recorded until then); a full disk is a named
    OutputError with every temporary file removed."""
    from agrobot.orchestrator.output import study_inputs, write_aside

    record = None if record is None else Path(record).resolve()

    def flag_of(field: str, full: Path) -> str:
        return "--record" if record is not None and full.parent == record else f"{study.origin(field)}:"
    placed, aside = write_aside(study, overwrite, study_inputs(study), flag_of=flag_of)
    with aside.kept():
        yield placed
