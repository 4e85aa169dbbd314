"""CAN through python-can, frames through cantools: one bus per component, the DBC shipped here."""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from orchestrator.component import par

DEFAULT_DBC = Path(__file__).resolve().parent / "agrobot_tractor.dbc"


def load_dbc(path: str | Path | None):
    """The frame layout; ``""``/None means the project's own agrobot_tractor.dbc."""
    import cantools

    return cantools.database.load_file(str(path or DEFAULT_DBC))


def open_bus(interface: str, channel: str, port: int = 0, bitrate: int = 0):
    """A python-can bus: 'virtual' (one process, tests), 'udp_multicast' (processes on one host),
    'socketcan', 'pcan', ... as python-can knows them."""
    import can

    options = {}
    if port:
        options["port"] = int(port)
    if bitrate:
        options["bitrate"] = int(bitrate)
    return can.Bus(interface=interface, channel=channel, **options)


class FrameCodec:
    """Encode one outgoing message and decode one incoming message by name, with a rolling
    4-bit counter; bad frames (wrong length, undecodable) are counted, never raised."""

    def __init__(self, db, send: str, receive: str) -> None:
        self.db = db
        self.tx = db.get_message_by_name(send)
        self.rx = db.get_message_by_name(receive)
        self.counter = 0
        self.bad = 0

    def encode(self, **signals) -> tuple[int, bytes]:
        self.counter = (self.counter + 1) % 16
        values = {**signals, "Counter": self.counter}
        for sig in self.tx.signals:                 # clamp to the DBC range instead of refusing
            if sig.name in values and sig.minimum is not None and sig.maximum is not None:
                values[sig.name] = min(max(values[sig.name], sig.minimum), sig.maximum)
        return self.tx.frame_id, self.tx.encode(values)

    def decode(self, message) -> dict | None:
        if message is None or message.arbitration_id != self.rx.frame_id:
            return None
        try:
            return self.rx.decode(bytes(message.data))
        except Exception:           # noqa: BLE001 - a bad frame is counted, not fatal
            self.bad += 1
            return None


CAN_PARAMETERS = (
    par("interface", "", "virtual", "python-can interface"),
    par("channel", "", "agrobot", "python-can channel"),
    par("port", "1", 0, "UDP port of the udp_multicast interface (0: its default)"),
    par("bitrate", "1/s", 0, "bus bit rate (0: leave the interface's)"),
    par("protocol", "", "agrobot", "message set: 'agrobot' (the project's frames) or 'isobus' (ISO 11783-7 "
        "guidance, J1939 29-bit ids)"),
    par("dbc", "", "", "DBC file (empty: the protocol's own, agrobot_tractor.dbc or isobus_guidance.dbc)"),
    par("wheelbase", "m", 1.4, "isobus: curvature = tan(wheel angle) / wheelbase"),
    par("source_address", "1", -1, "isobus: J1939 source address of what this side sends (-1: the DBC's)"),
    par("record_file", "", "", "record every frame sent and received: a candump .log, Vector .asc or .blf "
        "file (empty: no recording)"),
)


class RecordingBus:
    """A python-can bus that also writes every frame it sends or receives to a log file, in the
    format its suffix names (python-can's Logger: candump ``.log``, Vector ``.asc``, ``.blf``);
    each frame is written as it passes, so an interrupted run keeps what it recorded."""

    def __init__(self, bus, path: str) -> None:
        import can

        self.bus = bus
        self.log = can.Logger(path)

    def send(self, msg, timeout=None) -> None:
        import time

        if not msg.timestamp:
            msg.timestamp = time.time()
        msg.is_rx = False                        # the log marks it transmitted
        self.bus.send(msg, timeout)
        self.log(msg)

    def recv(self, timeout=None):
        msg = self.bus.recv(timeout)
        if msg is not None:
            self.log(msg)
        return msg

    def shutdown(self) -> None:
        try:
            self.log.stop()
        finally:
            self.bus.shutdown()


def prefixed(parameters, prefix: str):
    """The same parameters named ``prefix + name`` (for a composite holding this adapter)."""
    return tuple(replace(v, name=prefix + v.name) for v in parameters)


def connect(component, side: str):
    """(messages, bus) for a component declaring CAN_PARAMETERS (``side``: 'guidance' or
    'tractor'); failures become the component's error naming the DBC, protocol or bus."""
    from .guidance_messages import messages_for

    p = component.p
    messages = bus = None
    try:
        messages = messages_for(p["protocol"], p["dbc"], side, p["wheelbase"], int(p["source_address"]))
    except (OSError, KeyError, ValueError) as exc:
        component.require(False, f"CAN messages (protocol {p['protocol']!r}, DBC {p['dbc'] or 'default'}): {exc}")
    try:
        bus = open_bus(p["interface"], p["channel"], p["port"], p["bitrate"])
    except Exception as exc:                    # noqa: BLE001 - python-can raises many kinds
        component.require(False, f"cannot open CAN {p['interface']}:{p['channel']}: {exc}")
    if p.get("record_file"):
        try:
            bus = RecordingBus(bus, str(p["record_file"]))
        except (OSError, ValueError) as exc:    # an unwritable path, an unknown suffix
            bus.shutdown()
            component.require(False, f"cannot record CAN to {p['record_file']!r}: {exc} (suffix .log, .asc or .blf)")
    return messages, bus


def drain(bus, read):
    """Every frame waiting on the bus that ``read`` (a message set's reader) decodes."""
    frames = []
    while True:
        msg = bus.recv(timeout=0.0)
        if msg is None:
            return frames
        frame = read(msg)
        if frame is not None:
            frames.append(frame)


def send(bus, frames, extended: bool) -> None:
    """Send (identifier, data) pairs."""
    import can

    for fid, data in frames:
        bus.send(can.Message(arbitration_id=fid, data=data, is_extended_id=extended))
