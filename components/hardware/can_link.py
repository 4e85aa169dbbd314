"""CAN through python-can: one bus per component, its options, and what is sent and received on it
(the message sets of components.hardware.guidance_messages, framed by components.hardware.can_frames).

Who may talk: a frame is taken only from the configured channel (a frame python-can reports on
another is refused), and on ``udp_multicast`` only from an address of this host: python-can binds
that bus to every interface (("", port)) and drops the datagram's sender, so LocalSenderBus reads
the datagrams itself through the bus's socket. Work per step is bounded: ``drain`` reads at most
``max_frames`` frames; sending never waits (timeout 0), a frame the interface cannot take is counted.

Imported where used: can (the hardware extra, python-can).
"""
from __future__ import annotations

import os
import select
import socket
import time
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
    bus = can.Bus(interface=interface, channel=channel, **options)
    return LocalSenderBus(bus) if interface == "udp_multicast" else bus


def _is_local(address: str, known: dict[str, bool]) -> bool:
    """True when ``address`` belongs to this host (a socket can bind to it)."""
    if address not in known:
        family = socket.AF_INET6 if ":" in address else socket.AF_INET
        try:
            with socket.socket(family, socket.SOCK_DGRAM) as s:
                s.bind((address, 0))
            known[address] = True
        except OSError:
            known[address] = False
    return known[address]


NOT_A_FRAME = object()     # what a bus's recv gives for a datagram that is no frame for this side (read, refused)


class LocalSenderBus:
    """A python-can udp_multicast bus that takes frames from this host only: datagrams are read
    from the bus's own socket (``fileno``) with their sender, one per ``recv``; one from another
    host or that does not unpack (python-can packs frames with msgpack) is NOT_A_FRAME, so that a
    flood of junk uses up the step's allowance (``drain``) as a flood of frames does."""

    def __init__(self, bus) -> None:
        self.bus, self._known = bus, {}
        self.sock = socket.socket(fileno=os.dup(bus.fileno()))     # the same socket, its sender visible
        self.bound = self.sock.getsockname()

    def send(self, msg, timeout=None) -> None:
        self.bus.send(msg, timeout)

    def recv(self, timeout=None):
        from can.interfaces.udp_multicast.utils import unpack_message

        if not select.select([self.sock], [], [], timeout or 0.0)[0]:
            return None
        data, sender = self.sock.recvfrom(4096)
        if not _is_local(sender[0], self._known):
            return NOT_A_FRAME
        try:
            return unpack_message(data, replace={"timestamp": time.time()}, check=True)
        except Exception:                      # noqa: BLE001 - an unreadable datagram is not a frame
            return NOT_A_FRAME

    def shutdown(self) -> None:
        self.sock.close()
        self.bus.shutdown()


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
    par("peer_address", "1", -1, "isobus: the only J1939 source address taken from the other side (-1: the DBC's "
        "sender, -2: any)"),
    par("max_frames", "1", 64, "frames read per step at most (a step reading them all is flooded: its frames are "
        "not taken as fresh)"),
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
        if not msg.timestamp:
            msg.timestamp = time.time()
        msg.is_rx = False                        # the log marks it transmitted
        self.bus.send(msg, timeout)
        self.log(msg)

    def recv(self, timeout=None):
        msg = self.bus.recv(timeout)
        if msg is not None and msg is not NOT_A_FRAME:
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
    component.require(int(p["max_frames"]) >= 1, f"max_frames {p['max_frames']}: expected at least 1 frame per step")
    try:
        messages = messages_for(p["protocol"], p["dbc"], side, p["wheelbase"], int(p["source_address"]),
                                int(p["peer_address"]))
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


def binding(interface: str, channel: str, port: int = 0, bus=None) -> str:
    """Who can reach this bus, in words (the address actually bound when the bus is open)."""
    while bus is not None and not isinstance(bus, LocalSenderBus) and hasattr(bus, "bus"):
        bus = bus.bus                           # through a RecordingBus
    if interface == "udp_multicast":
        where = "{}:{}".format(*bus.bound[:2]) if isinstance(bus, LocalSenderBus) else f"0.0.0.0:{port or 43113}"
        return (f"CAN udp_multicast group {channel}: python-can listens on {where} (every interface); frames "
                "taken from this host's addresses only")
    if interface == "virtual":
        return f"CAN virtual channel {channel!r} (this process only)"
    return f"CAN {interface} channel {channel!r} (frames from that interface only)"


class Drained:
    """What one bounded read gave: decoded frames in order, the frames and datagrams read, whether
    the step's allowance was used up (``flooded``) and what was read but refused (``foreign``: a
    frame of another channel, a datagram of another host or that is no frame)."""

    def __init__(self) -> None:
        self.frames: list[dict] = []
        self.read = self.foreign = 0
        self.flooded = False


def drain(bus, read, channel=None, max_frames: int = 64) -> Drained:
    """At most ``max_frames`` frames or datagrams waiting on the bus (what is no frame counts against
    the allowance as a frame does), those ``read`` (a message set's reader) decodes kept; a frame
    python-can reports on another channel than ``channel``, and NOT_A_FRAME, are refused."""
    got = Drained()
    while got.read < max_frames:
        msg = bus.recv(timeout=0.0)
        if msg is None:
            return got
        got.read += 1
        if msg is NOT_A_FRAME or (channel is not None and msg.channel is not None and str(msg.channel) != str(channel)):
            got.foreign += 1
            continue
        frame = read(msg)
        if frame is not None:
            got.frames.append(frame)
    got.flooded = True
    return got


def send(bus, frames, extended: bool) -> int:
    """Send (identifier, data) pairs without waiting; the number the interface refused."""
    import can

    failed = 0
    for fid, data in frames:
        try:
            bus.send(can.Message(arbitration_id=fid, data=data, is_extended_id=extended), timeout=0.0)
        except can.CanError:
            failed += 1
    return failed
