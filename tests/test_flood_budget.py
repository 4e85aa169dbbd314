"""Per-step budgets count everything: datagrams on the CAN/UDP port that are no frame (junk, or from
another host) use up a step's allowance as frames do, so a flood of junk ends the step's reading at
``max_frames``, marks the step flooded and is reported as refused."""
from __future__ import annotations

import random
import socket
import time

import can
from can.interfaces.udp_multicast.utils import pack_message

from agrobot.components.hardware.can_link import drain
from agrobot.components.hardware.guidance_messages import messages_for
from tests.test_hardware_safety import _multicast


def test_a_flood_of_junk_datagrams_counts_against_the_step_and_is_reported():
    port = random.randint(40000, 49999)
    bus = _multicast(port)
    tractor = messages_for("agrobot", "", "tractor", 1.4)
    guidance = messages_for("agrobot", "", "guidance", 1.4)
    (fid, data), *_ = guidance.command(0.1, 2.0, False)
    out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        for k in range(300):                               # junk: no msgpack frame
            out.sendto(b"\xc1junk%d" % k, ("127.0.0.1", port))
        time.sleep(0.2)
        got = drain(bus, tractor.read_command, None, 64)
        assert got.read == 64 and got.flooded and got.foreign == 64 and got.frames == []
        drain(bus, tractor.read_command, None, 1000)        # the rest of the junk
        packed = pack_message(can.Message(arbitration_id=fid, data=data, is_extended_id=False))
        out.sendto(b"junk", ("127.0.0.1", port))
        out.sendto(packed, ("127.0.0.1", port))
        time.sleep(0.1)
        got = drain(bus, tractor.read_command, None, 64)   # junk and a command: both read, the command taken
        assert got.read == 2 and got.foreign == 1 and len(got.frames) == 1 and not got.flooded
    finally:
        out.close()
        bus.shutdown()
