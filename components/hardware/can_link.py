"""CAN through python-can: one bus per component, its options, and what is sent and received on it
(the message sets of components.hardware.guidance_messages, framed by components.hardware.can_frames)."""
from __future__ import annotations

from dataclasses import replace

from agrobot.orchestrator.component import par

from .guidance_messages import messages_for


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
