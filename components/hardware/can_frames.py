"""CAN frames through cantools: the DBC that lays them out (the project's own by default) and a
codec for one outgoing and one incoming message, with the end-to-end checks the DBC defines: a
rolling 4-bit ``Counter`` and a ``Checksum`` byte, CRC-8/SAE-J1850 over bytes 0-6 followed by
the identifier's low byte (so a frame cannot pass as another message).

Imported where used: cantools (the hardware extra).
"""
from __future__ import annotations

import math
from pathlib import Path

DEFAULT_DBC = Path(__file__).resolve().parent / "agrobot_tractor.dbc"
MAX_COUNTER_STEP = 3            # a counter may advance 1..3 (two frames lost); 0 is a repeat


def load_dbc(path: str | Path | None):
    """The frame layout; ``""``/None means the project's own agrobot_tractor.dbc."""
    import cantools

    return cantools.database.load_file(str(path or DEFAULT_DBC))


def crc8_j1850(data: bytes) -> int:
    """CRC-8/SAE-J1850: polynomial x^8 + x^4 + x^3 + x^2 + 1 (0x1D), init 0xFF, final XOR 0xFF."""
    crc = 0xFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1D) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc ^ 0xFF


def frame_checksum(frame_id: int, data: bytes) -> int:
    """The Checksum byte of a frame: CRC-8/SAE-J1850 of bytes 0-6 and the identifier's low byte."""
    return crc8_j1850(bytes(data[:7]) + bytes([frame_id & 0xFF]))


class FrameCodec:
    """Encode one outgoing message and decode one incoming message by name. Outgoing: the DBC
    range clamps finite values, a non-finite one is refused (ValueError); the counter rolls and
    the checksum is set. Incoming frames are refused and counted (never raised) when they do not
    decode (``bad``), carry a wrong checksum or a repeated or far-skipped counter (``bad_e2e``),
    or a value outside its DBC range (``out_of_range``)."""

    def __init__(self, db, send: str, receive: str) -> None:
        self.db = db
        self.tx = db.get_message_by_name(send)
        self.rx = db.get_message_by_name(receive)
        self.counter = 0
        self.bad = self.bad_e2e = self.out_of_range = 0
        self.last_counter: int | None = None
        self.tx_names = {s.name for s in self.tx.signals}
        self.rx_names = {s.name for s in self.rx.signals}

    def encode(self, **signals) -> tuple[int, bytes]:
        bad = [k for k, v in signals.items() if not math.isfinite(v)]
        if bad:
            raise ValueError(f"{self.tx.name}: {', '.join(bad)} not finite")
        self.counter = (self.counter + 1) % 16
        values = {**signals, "Counter": self.counter}
        if "Checksum" in self.tx_names:
            values["Checksum"] = 0
        for sig in self.tx.signals:                 # clamp to the DBC range
            if sig.name in values and sig.minimum is not None and sig.maximum is not None:
                values[sig.name] = min(max(values[sig.name], sig.minimum), sig.maximum)
        data = bytearray(self.tx.encode(values))
        if "Checksum" in self.tx_names:
            data[7] = frame_checksum(self.tx.frame_id, data)
        return self.tx.frame_id, bytes(data)

    def decode(self, message) -> dict | None:
        if message is None or message.arbitration_id != self.rx.frame_id:
            return None
        data = bytes(message.data)
        try:
            f = self.rx.decode(data, decode_choices=False)
        except Exception:           # noqa: BLE001 - a bad frame is counted, not fatal
            self.bad += 1
            return None
        if "Checksum" in self.rx_names and f["Checksum"] != frame_checksum(self.rx.frame_id, data):
            self.bad_e2e += 1
            return None
        if "Counter" in self.rx_names:
            last, self.last_counter = self.last_counter, int(f["Counter"])
            if last is not None and not 1 <= (self.last_counter - last) % 16 <= MAX_COUNTER_STEP:
                self.bad_e2e += 1   # a repeat or a jump: refused, the next in sequence is taken again
                return None
        for sig in self.rx.signals:
            if sig.minimum is not None and sig.maximum is not None and not sig.minimum <= f[sig.name] <= sig.maximum:
                self.out_of_range += 1
                return None
        return f
