"""A run as robotics engineers look at it: an MCAP file for Foxglove and PlotJuggler, written with the
Foxglove SDK (``foxglove.open_mcap``), and the same topics served live over the Foxglove WebSocket
protocol (``foxglove.start_server``).

Topics (generic: the orchestrator knows nothing of the system simulated):

- ``/signals/<component>``: every numeric output of the component as one JSON message per step of
  the component (its own rate), ``{"t": s, "<output>": value, ...}``; the JSON schema gives each
  output's unit and description, so PlotJuggler and Foxglove plot them by name.
- the study's ``[output] mcap = true`` asks for the MCAP as ``--mcap`` does (a sweep: one per point);
- whatever a *scene* adds: a project's analysis module may define ``mcap_scene(study)`` returning an
  object with ``channels(context)`` (its typed channels), ``static(t_ns)`` (messages logged once at the
  start: a path, a field) and ``step(t_ns, value)`` (messages of one instant, ``value(column)`` giving
  the signal ``component.output`` or NaN) and ``every``, the base steps between two scene instants;
  live, an optional ``track(value)`` is called at every scene instant of simulated time (what the scene
  gathers from the whole run, such as the path driven so far) and ``static`` again when a viewer subscribes.

Times: log times are the simulated time in nanoseconds from the study's start time (a run has no
date); the MCAP's metadata record ``run`` names the study and its start time.

Imported where used: foxglove (the mcap extra), orchestrator.live_relay (--live only: it loads asyncio and
websockets), pyarrow.parquet (start-up: 0.03 s; a Parquet signal table read block by block).
"""
from __future__ import annotations

import contextlib
import io
import logging
import math
import os
import threading
import time
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from .atomic_files import atomic_write
from .output import OutputError, check_output_file, disk_full, disk_full_error
from .registry import import_study_module
from .resolver import resolve
from .signal_table import SignalTable
from .study import parse_study

SIGNALS_PREFIX = "/signals/"


def check_mcap_path(path: Path, overwrite: bool = False, inputs=()) -> Path:
    """The MCAP file ``path`` before a run, under the one rule for a written file
    (orchestrator.output.check_output_file): a name ending in .mcap, a folder it can be written in, an
    existing file replaced only with ``overwrite``, an input never. An OutputError (exit 2) otherwise."""
    path = Path(path)
    check_output_file(path, overwrite, inputs, suffixes=(".mcap",), flag="--mcap")
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise OutputError(f"--mcap {path}: its folder {parent} does not exist")
    return path


def signal_schema(component: str, outputs: list[str], units: Mapping[str, str], descriptions: Mapping[str, str]) -> dict:
    """The JSON schema of a component's message: time and every output, a number with its unit."""
    props = {"t": {"type": "number", "description": "simulated time [s]"}}
    for name in outputs:
        col = f"{component}.{name}"
        unit = units.get(col, "")
        props[name] = {"type": "number",
                       "description": f"{descriptions.get(col, name)}" + (f" [{unit}]" if unit else "")}
    return {"type": "object", "title": f"{component} outputs", "properties": props}


def components_of(columns: list[str]) -> dict[str, list[str]]:
    """``component.output`` columns grouped by component, in order."""
    grouped: dict[str, list[str]] = {}
    for col in columns:
        if col == "t" or "." not in col:
            continue
        comp, _, port = col.partition(".")
        grouped.setdefault(comp, []).append(port)
    return grouped


class SignalChannels:
    """One JSON channel per component on a Foxglove context; ``log(k, t, value)`` logs the messages of
    base step ``k`` for the components due at it (``ratio``: base steps between two of its steps)."""

    def __init__(self, context, columns: list[str], ratios: Mapping[str, int], units: Mapping[str, str],
                 descriptions: Mapping[str, str], prefix: str = SIGNALS_PREFIX) -> None:
        import foxglove

        self.groups = components_of(columns)
        self.ratios = {c: max(int(ratios.get(c, 1)), 1) for c in self.groups}
        self.channels = {c: foxglove.Channel(prefix + c, schema=signal_schema(c, outs, units, descriptions),
                                             message_encoding="json", context=context,
                                             metadata={"units": ",".join(units.get(f"{c}.{o}", "") for o in outs)})
                         for c, outs in self.groups.items()}

    def log(self, k: int, t: float, value: Callable[[str], float], t_ns: int) -> None:
        for comp, outs in self.groups.items():
            if k % self.ratios[comp]:
                continue
            message = {"t": t}
            for port in outs:
                v = float(value(f"{comp}.{port}"))
                message[port] = v if math.isfinite(v) else None          # JSON has no NaN
            self.channels[comp].log(message, log_time=t_ns)


MCAP_BLOCK_ROWS = 4096     # rows of the signal table read and logged at a time (memory flat in the run's length)


class _Sink(io.RawIOBase):
    """The file the MCAP writer writes through: the first OSError of a write (a full disk) is kept, so that
    the writer, which logs its own write errors and goes on, is stopped at once and the error named."""

    def __init__(self, file) -> None:
        super().__init__()
        self.file, self.error = file, None

    def write(self, data) -> int:
        try:
            return self.file.write(data)
        except OSError as exc:
            self.error = self.error or exc
            raise

    def seek(self, offset: int, whence: int = 0) -> int:
        return self.file.seek(offset, whence)

    def tell(self) -> int:
        return self.file.tell()

    def flush(self) -> None:
        self.file.flush()

    def writable(self) -> bool:
        return True

    def seekable(self) -> bool:
        return True


def row_blocks(signals, rows: int = MCAP_BLOCK_ROWS):
    """The signal table ``signals`` (a DataFrame, or a result's SignalTable read from its file, one row
    group at a time: a run's table is written in row groups of WRITE_EVERY rows) as successive
    ``(t, {column: values})`` blocks of at most ``rows`` rows."""
    path = signals.path if isinstance(signals, SignalTable) else None
    columns = [c for c in signals.columns if c != "t"]
    if path is not None and Path(path).suffix == ".parquet":
        import pyarrow.parquet as pq

        file = pq.ParquetFile(path)
        for group in range(file.num_row_groups):      # a row group at a time (iter_batches reads far ahead)
            table = file.read_row_group(group)
            for a in range(0, table.num_rows, rows):
                part = table.slice(a, rows)
                yield (part.column("t").to_numpy().astype(float),
                       {c: part.column(c).to_numpy().astype(float) for c in columns})
            del table
        return
    if path is not None:
        for chunk in pd.read_csv(path, chunksize=rows):
            yield chunk["t"].to_numpy(float), {c: chunk[c].to_numpy(float) for c in columns}
        return
    for a in range(0, len(signals), rows):
        part = signals.iloc[a:a + rows]
        yield part["t"].to_numpy(float), {c: part[c].to_numpy(float) for c in columns}


def write_run_mcap(path: Path, frame, *, ratios: Mapping[str, int], units: Mapping[str, str],
                   descriptions: Mapping[str, str], scene=None, metadata: Mapping[str, str] | None = None,
                   prefix: str = SIGNALS_PREFIX) -> Path:
    """Every signal of ``frame`` (a DataFrame or a result's SignalTable: a ``t`` column and
    ``component.output`` columns, one row per base step) and the scene's messages, into the MCAP file
    ``path``, streamed MCAP_BLOCK_ROWS rows at a time. Written under a unique temporary name beside it and
    renamed over it (orchestrator.atomic_files.atomic_write); a write that fails (a full disk) leaves
    nothing behind and is an OutputError naming ``path``."""
    path = Path(path)
    try:
        return atomic_write(path, lambda tmp: _write_mcap_file(tmp, frame, ratios, units, descriptions, scene,
                                                               metadata, prefix))
    except OSError as exc:
        why = exc.strerror or os.strerror(exc.errno or 0)
        if disk_full(exc):
            raise disk_full_error(path, exc, "nothing was left behind", "--mcap") from None
        raise OutputError(f"--mcap {path}: cannot be written ({why}); nothing was left behind") from None


def _write_mcap_file(tmp: Path, frame, ratios, units, descriptions, scene, metadata, prefix) -> None:
    import foxglove

    with open(tmp, "wb") as file, _quiet_writer():
        sink = _Sink(file)
        context = foxglove.Context()
        writer = foxglove.open_mcap(sink, context=context)
        try:
            try:
                if metadata:
                    writer.write_metadata("run", dict(metadata))
                _log_rows(context, sink, frame, ratios, units, descriptions, scene, prefix)
            finally:
                writer.close()
        except RuntimeError:             # the SDK's error for a failed write: the sink holds the OSError
            if sink.error is None:
                raise
        if sink.error is not None:
            raise sink.error


def _log_rows(context, sink: _Sink, frame, ratios, units, descriptions, scene, prefix) -> None:
    """The messages of every row of ``frame``, block by block (row_blocks), until a write fails."""
    columns = [c for c in frame.columns if c != "t"]
    signals = SignalChannels(context, columns, ratios, units, descriptions, prefix)
    if scene is not None:
        scene.channels(context)
        scene.static(0)
    every = max(int(getattr(scene, "every", 1)), 1) if scene is not None else 0
    k, t0 = 0, None
    for t, arrays in row_blocks(frame):
        t0 = float(t[0]) if t0 is None and len(t) else t0
        for j in range(len(t)):
            t_ns = int(round((t[j] - t0) * 1e9))
            value = _row_value(arrays, j)
            signals.log(k, float(t[j]), value, t_ns)
            if scene is not None and k % every == 0:
                scene.step(t_ns, value)
            k += 1
        if sink.error is not None:
            return


@contextlib.contextmanager
def _quiet_writer():
    """The SDK's own log of a failed write (one line per message after it) silenced while the MCAP is written:
    the first error is raised, named, instead."""
    logger = logging.getLogger("foxglove")
    level = logger.level
    logger.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        logger.setLevel(level)


def _row_value(arrays: Mapping[str, np.ndarray], k: int) -> Callable[[str], float]:
    def value(column: str) -> float:
        a = arrays.get(column)
        return float(a[k]) if a is not None else math.nan
    return value


def wants_mcap(study) -> bool:
    """The study asks for its run's MCAP (``[output] mcap = true``, a table a project registers)."""
    return bool((study.section("output") or {}).get("mcap", False))


def with_mcap(study):
    """The study with ``[output] mcap = true`` (``sweep --mcap``: every point writes its MCAP)."""
    data = study.to_data()
    data["output"] = {**data.get("output", {}), "mcap": True}
    return parse_study(data, study.path)


def study_signal_facts(study) -> tuple[dict[str, int], dict[str, str], dict[str, str]]:
    """(component -> base steps between its steps, column -> unit, column -> description) of a study."""
    model = resolve(study)
    h = float(study.study.base_step)
    ratios, units, descriptions = {}, {}, {}
    for name, spec in study.components.items():
        step = getattr(spec, "step", None)
        ratios[name] = max(1, int(round(float(step) / h))) if step else 1
        try:
            cls = model.component_class(name)
        except Exception:            # noqa: BLE001 - a component without declarations: no units
            continue
        for v in getattr(cls, "variables", ()):
            if v.causality == "output":
                units[f"{name}.{v.name}"] = v.unit
                descriptions[f"{name}.{v.name}"] = v.description
    return ratios, units, descriptions


def study_scene(study, frame=None):
    """The scene the study's analysis module offers (``mcap_scene(study, frame)``), or None."""
    if not study.study.analysis:
        return None
    factory = getattr(import_study_module(study.study.analysis), "mcap_scene", None)
    return factory(study, frame) if factory is not None else None


def write_study_mcap(study, signals: pd.DataFrame, path: Path) -> tuple[Path, str]:
    """The run of ``study`` whose signals are ``signals`` as the MCAP file ``path``; (the path, what the scene
    says of its choices, such as the map's origin: printed by the caller, written in the metadata)."""
    ratios, units, descriptions = study_signal_facts(study)
    scene = study_scene(study, signals)
    note = str(getattr(scene, "note", "") or "")
    metadata = {"study": str(study.study.name), "start_time_s": repr(float(study.study.start_time)),
                "time": "log times are simulated seconds from the study's start, in ns"}
    if note:
        metadata["scene"] = note
    return write_run_mcap(path, signals, ratios=ratios, units=units, descriptions=descriptions, scene=scene,
                          metadata=metadata), note


LIVE_RATE_HZ = 20.0        # wall-clock instants a second sent to the live view
LIVE_MAX_VIEWERS = 16      # viewers served at once (run --live-viewers N); one more is refused with the reason
LIVE_VIEWERS_CEILING = 64  # --live-viewers at most: each viewer costs the run's machine (docs/foxglove.md)
LIVE_QUEUE_FRAMES = 256    # frames waiting per viewer; past it the oldest message data is dropped
MAX_PORT = 65535


def check_live_options(host: str, port: int, wait: float, max_viewers: int) -> None:
    """The live view's options before anything starts: an OutputError (exit 2) naming the one out of range."""
    where = f"{host}:{port}"
    if not 0 <= port <= MAX_PORT:
        raise OutputError(f"--live {where}: port {port} is beyond 0-{MAX_PORT}")
    if not (math.isfinite(wait) and wait >= 0):
        raise OutputError(f"--live-wait {wait}: expected a finite number of seconds >= 0")
    if not 1 <= max_viewers <= LIVE_VIEWERS_CEILING:
        raise OutputError(f"--live-viewers {max_viewers}: expected 1 to {LIVE_VIEWERS_CEILING} viewers (each one "
                          f"costs the run's machine; see docs/foxglove.md)")


def counted(n: int, noun: str) -> str:
    """``n`` and its noun in the number it takes: 1 viewer, 2 viewers, 0 viewers."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


class LiveView:
    """An observer (orchestrator.observers) serving the running study over the Foxglove WebSocket protocol,
    with the MCAP's topics: at most ``rate`` instants a second of wall time (the latest values of every
    component and the scene), so that the run is not slowed. ``wait`` seconds at the start for a viewer to
    subscribe (0: start at once). ``stop()`` closes the server.

    The SDK's server listens on the loopback at a port of its own; viewers reach it through the relay
    (orchestrator.live_relay, its own process) at ``host:port``, which speaks ``foxglove.websocket.v1`` beside
    the SDK's ``foxglove.sdk.v1``, serves at most ``max_viewers`` at once and drops a slow viewer's oldest
    messages: the run logs to the SDK's channels, which never wait on a viewer."""

    def __init__(self, study, host: str = "127.0.0.1", port: int = 8765, rate: float = LIVE_RATE_HZ,
                 wait: float = 0.0, max_viewers: int = LIVE_MAX_VIEWERS) -> None:
        import foxglove

        from .live_relay import RelayProcess, RelayRefused

        check_live_options(host, port, wait, max_viewers)
        self.study, self.rate, self.wait, self.max_viewers = study, float(rate), float(wait), int(max_viewers)
        self.context = foxglove.Context()
        self.subscribed = threading.Event()
        self._resend: set[str] = set()
        self.server = foxglove.start_server(host="127.0.0.1", port=0, context=self.context,
                                            server_listener=_listener(self.subscribed, self._resend),
                                            name=f"{__name__.split('.')[0]} {study.study.name}")
        try:
            self.relay = RelayProcess(self.server.port, host, port, self.max_viewers, LIVE_QUEUE_FRAMES)
        except RelayRefused as exc:
            self.server.stop()
            raise OutputError(f"--live {host}:{port}: cannot serve there ({exc}); choose another port with "
                              f"--live {host}:PORT") from None
        self.host, self.port = host, self.relay.port
        ratios, units, descriptions = study_signal_facts(study)
        self._ratios, self._units, self._descriptions = ratios, units, descriptions
        self.scene = study_scene(study)
        self._track = getattr(self.scene, "track", None)
        self._every = max(int(getattr(self.scene, "every", 1)), 1)
        self.sent = 0
        self.viewers: dict | None = {}
        self._next = 0.0

    @property
    def url(self) -> str:
        return f"ws://{self.host}:{self.port}"

    @property
    def report(self) -> str:
        """What the view did: instants sent, viewers by subprotocol, refused, messages dropped for slow viewers."""
        v = self.viewers
        if v is None:
            return f"{counted(self.sent, 'instant')} sent to {self.url}; the relay's counts of viewers did not come in time"
        served = {p: n for p, n in v.items() if p.startswith("foxglove.")}
        text = f"{counted(self.sent, 'instant')} sent to {self.url}; {counted(sum(served.values()), 'viewer')}"
        if served:
            text += " (" + ", ".join(f"{n} {p}" for p, n in sorted(served.items())) + ")"
        if v.get("refused_full"):
            text += f"; {v['refused_full']} refused beyond {self.max_viewers} at once (--live-viewers N)"
        if v.get("refused_subprotocol"):
            text += f"; {v['refused_subprotocol']} refused without a Foxglove subprotocol"
        if v.get("dropped"):
            text += f"; {counted(v['dropped'], 'message')} dropped for slow viewers"
        if v.get("closed_slow"):
            text += f"; {counted(v['closed_slow'], 'viewer')} closed as too slow"
        return text

    # observer hooks
    advanced = None
    _k = 0

    def instant(self, k: int) -> None:
        self._k = k                  # the base step being taken (sim.k moves only between calls of advance)

    def started(self, sim) -> None:
        self.sim = sim
        self.signals = SignalChannels(self.context, list(sim.columns), {c: 1 for c in self._ratios}, self._units,
                                      self._descriptions)
        if self.scene is not None:
            self.scene.channels(self.context)
        if self.wait > 0:
            self.subscribed.wait(self.wait)
        self._resend.clear()
        if self.scene is not None:
            self.scene.static(0)
        self._period = 1.0 / self.rate if self.rate > 0 else 0.0
        self._next = time.perf_counter()
        published = sim.published

        def value(column: str) -> float:
            comp, _, port = column.partition(".")
            try:
                return float(published[comp][port])
            except (KeyError, TypeError, ValueError):
                return math.nan
        self._value = value

    def recorded(self, phase: int) -> None:
        if self._track is not None and self._k % self._every == 0:
            self._track(self._value)
        now = time.perf_counter()
        if now < self._next:
            return
        self._next = now + self._period
        sim = self.sim
        t = sim.t0 + self._k * sim.h
        t_ns = int(round((t - sim.t0) * 1e9))
        self.signals.log(0, t, self._value, t_ns)
        if self.scene is not None:
            if self._resend:                 # a viewer subscribed since: the messages logged once, again
                self._resend.clear()
                self.scene.static(t_ns)
            self.scene.step(t_ns, self._value)
        self.sent += 1

    def stop(self) -> None:
        """The relay told to end (it reports first), the SDK's server stopped (the relay drains what its viewers
        wait for and closes them), the relay's counts."""
        self.relay.finish()
        self.server.stop()
        self.viewers = self.relay.stop()
        if not self.viewers and self.relay.late:
            self.viewers = None


def _listener(event, resend: set):
    """A foxglove.ServerListener that sets ``event`` when a viewer subscribes to a channel and adds the
    channel's topic to ``resend``."""
    import foxglove

    class Listener(foxglove.ServerListener):
        def on_subscribe(self, client, channel) -> None:
            resend.add(channel.topic)
            event.set()
    return Listener()
