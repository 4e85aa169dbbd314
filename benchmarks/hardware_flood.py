"""The hardware loop flooded: worst step time and the watchdog's reaction time.

The guidance side's adapters (nmea_gps over loopback TCP, can_actuators and the emulated
tractor's can_tractor_link on python-can's virtual bus) and the safety watchdog, stepped at 20 Hz
against the wall clock, while a peer floods one link:

- ``nmea normal``: a receiver at 20 Hz, then it falls silent (the stale-fix reaction);
- ``nmea flood``: the receiver resends its fix as fast as loopback TCP takes it;
- ``can feedback flood``: frames poured onto the guidance's feedback bus every step;
- ``can command flood``: frames poured onto the tractor's command bus every step.

Reaction: loop time (the steps' clock) and wall time from the fault (the last fix the loop could trust, or the flood's start on
the tractor side) to the safe state (watchdog tripped, or the tractor's speed set to 0); the bound
is 0.5 s + one 50 ms step (a feedback flood stops nothing: nan). Only loopback and the in-process
virtual bus are used.

    python benchmarks/hardware_flood.py [--seconds 5]
"""
from __future__ import annotations

import argparse
import os
import random
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from agrobot.components.can_actuators import CANActuators
from agrobot.components.can_tractor_link import CANTractorLink
from agrobot.components.nmea_gps import NMEAGPS
from agrobot.components.safety_watchdog import SafetyWatchdog

ROOT = Path(__file__).resolve().parents[1]
DT = 0.05
FAULT = 2.5                 # s: the fault starts (the watchdog has left its start-up trip by then)
GEO = {"datum_latitude": 0.8877, "datum_longitude": 0.0816, "datum_height": 60.0}
RECEIVER = r"""
import socket, sys, time
sys.path[:0] = [{root!r}]
from agrobot.components.hardware.nmea import gga_vtg
srv = socket.create_server(("127.0.0.1", 0))
print(srv.getsockname()[1], flush=True)
conn, _ = srv.accept()
sys.stdin.readline()                                # the loop starts: the receiver's clock too
fix = gga_vtg(1.0, 0.8877, 0.0816, 60.0, 2.0, 0.0)
t0 = time.monotonic()
try:
    while time.monotonic() - t0 < {normal}:
        conn.sendall(fix); time.sleep(0.05)
    print(time.monotonic(), flush=True)             # the fault starts
    t1 = time.monotonic()
    while {flood} and time.monotonic() - t1 < {seconds}:
        conn.sendall(fix * 200)
    time.sleep({seconds})
except OSError:
    pass
"""


def loop(seconds: float, nmea_flood: bool, can_flood: str | None):
    """Step the adapters and the watchdog for ``seconds``; the step times and the reaction."""
    normal = seconds if can_flood else FAULT              # the CAN runs keep a good receiver
    receiver = subprocess.Popen([sys.executable, "-c", RECEIVER.format(root=str(ROOT), normal=normal, seconds=seconds,
                                                                        flood=nmea_flood)],
                                stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    port = int(receiver.stdout.readline())
    channel = f"b{random.getrandbits(32)}"
    gps = NMEAGPS("gps", {"url": f"socket://127.0.0.1:{port}", **GEO})
    act = CANActuators("act", {"interface": "virtual", "channel": channel})
    link = CANTractorLink("link", {"interface": "virtual", "channel": channel})
    dog = SafetyWatchdog("dog", {})
    for c in (gps, act, link, dog):
        c.initialize(0.0, DT)
    import can

    hostile = can.Bus(interface="virtual", channel=channel)
    steps, last_fix_wall, trip_wall, stop_wall, flood_wall = [], None, None, None, None
    last_fix_t = trip_t = stop_t = flood_t = None
    engaged = False
    receiver.stdin.write("go\n")
    receiver.stdin.flush()
    start = time.perf_counter()
    try:
        for k in range(int(seconds / DT)):
            t = k * DT
            time.sleep(max(0.0, start + t - time.perf_counter()))
            if can_flood and t >= FAULT:                  # the peer pours 200 frames a step (its cost not timed)
                flood_wall, flood_t = flood_wall or time.perf_counter(), flood_t or t
                fid = 0x280 if can_flood == "feedback" else 0x180
                for i in range(200):
                    hostile.send(can.Message(arbitration_id=fid, data=bytes(8), is_extended_id=False))
            w0, c0 = time.perf_counter(), time.thread_time()
            act.step(t, DT)
            gps.step(t, DT)
            dog.u.update(steer_angle_cmd=0.05, speed_cmd=2.0, steer_angle_measured=act.y["steer_angle_measured"],
                         fix_age=gps.y["fix_age"], fix_quality=gps.y["fix_quality"])
            dog.step(t, DT)
            act.u.update(steer_angle_cmd=dog.y["steer_angle_cmd_out"], speed_cmd=dog.y["speed_cmd_out"],
                         safe_state=dog.y["safe_state"])
            act.actuate(t)
            link.u.update(steer_angle_measured=0.05, yaw_rate=0.0, speed=2.0)
            link.step(t, DT)
            now = time.perf_counter()
            steps.append((now - w0, time.thread_time() - c0))
            if gps.y["fix_valid"] > 0.5:
                last_fix_wall, last_fix_t = now, t
            if t > FAULT - DT and dog.y["safe_state"] > 0.5 and trip_wall is None:
                trip_wall, trip_t = now, t
            if flood_wall and link.y["speed_cmd"] == 0.0 and stop_wall is None:
                stop_wall, stop_t = now, t
            if abs(t - (FAULT - DT)) < 1e-9:
                engaged = dog.y["safe_state"] == 0.0 and link.y["speed_cmd"] > 0.0
    finally:
        hostile.shutdown()
        for c in (gps, act, link):
            c.terminate()
        receiver.kill()
        receiver.wait()
    s = np.array(steps) * 1e3
    nan = (float("nan"), float("nan"))
    if can_flood == "command":
        reaction = (stop_t - flood_t, stop_wall - flood_wall) if stop_wall else nan
    elif can_flood:
        reaction = nan                                 # nothing to stop for: the feedback only ages
    else:
        reaction = (trip_t - last_fix_t, trip_wall - last_fix_wall) if trip_wall and last_fix_wall \
            and trip_wall > last_fix_wall else nan
    counts = (gps.y["flooded_steps"], act.y["flooded_steps"], link.y["flooded_steps"], gps.y["dropped_bytes"])
    if not engaged:
        reaction = nan                                 # the loop was not guiding when the fault came
    return s, reaction, counts


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=5.0, help="wall time of each run (the fault at 2.5 s)")
    args = parser.parse_args()
    print(f"load average at start: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; period {DT * 1e3:.0f} ms, "
          f"watchdog bound {0.5 + DT:.2f} s")
    print(f"{'run':<22}{'steps':>6}{'wall p50/p99/max [ms]':>24}{'CPU max [ms]':>14}{'flooded gps/act/link':>22}"
          f"{'dropped B':>11}{'reaction loop/wall [s]':>24}")
    for name, nmea_flood, can_flood in (("nmea normal, stops", False, None), ("nmea flood", True, None),
                                        ("can feedback flood", False, "feedback"), ("can command flood", False, "command")):
        s, reaction, c = loop(args.seconds, nmea_flood, can_flood)
        wall = np.percentile(s[:, 0], [50, 99]).tolist() + [s[:, 0].max()]
        print(f"{name:<22}{len(s):>6}{'/'.join(f'{v:.1f}' for v in wall):>24}{s[:, 1].max():>14.1f}"
              f"{'/'.join(str(int(v)) for v in c[:3]):>22}{int(c[3]):>11}{'/'.join(f'{v:.3f}' for v in reaction):>24}")


if __name__ == "__main__":
    main()
