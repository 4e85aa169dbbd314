"""CAN frames through cantools: the DBC that lays them out (the project's own by default) and a
codec for one outgoing and one incoming message with a rolling 4-bit counter."""
from __future__ import annotations

from pathlib import Path

DEFAULT_DBC = Path(__file__).resolve().parent / "agrobot_tractor.dbc"


def load_dbc(path: str | Path | None):
    """The frame layout; ``""``/None means the project's own agrobot_tractor.dbc."""
    import cantools

    return cantools.database.load_file(str(path or DEFAULT_DBC))


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
