"""What the live view costs a simulated run: the figure-8 (160 s simulated) run in process without a live
view, with one and no viewer, and with one and a subscribed WebSocket viewer (every topic), each run
``--repeats`` times in one process, interleaved; the table gives the median wall time and the ratio to
the run without a view (the goal: at most 1.10 at the default rate).

    python benchmarks/live_view.py [--repeats 3] [--rate 20]
"""
from __future__ import annotations

import argparse
import json
import socket
import statistics
import threading

from agrobot.orchestrator.mcap_out import LIVE_RATE_HZ, LiveView
from agrobot.orchestrator.runner import run_study
from agrobot.orchestrator.study import Study
from agrobot.studies import shipped


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _viewer(port: int, stop: threading.Event, counts: list) -> None:
    """A Foxglove WebSocket client subscribed to every advertised channel, counting the messages."""
    from websockets.sync.client import connect

    with connect(f"ws://127.0.0.1:{port}", subprotocols=["foxglove.sdk.v1"], open_timeout=10) as ws:
        while not stop.is_set():
            try:
                message = ws.recv(timeout=0.5)
            except TimeoutError:
                continue
            except Exception:           # noqa: BLE001 - the server closed: the run ended
                return
            if isinstance(message, str):
                op = json.loads(message)
                if op["op"] == "advertise":
                    ws.send(json.dumps({"op": "subscribe", "subscriptions": [
                        {"id": c["id"], "channelId": c["id"]} for c in op["channels"]]}))
            else:
                counts[0] += 1


def one(mode: str, rate: float) -> tuple[float, int]:
    study = Study.load(shipped("figure8.toml"))
    observers, view, stop, counts, thread = [], None, threading.Event(), [0], None
    if mode != "none":
        view = LiveView(study, port=_free_port(), rate=rate, wait=10.0 if mode == "viewer" else 0.0)
        observers = [view]
        if mode == "viewer":
            thread = threading.Thread(target=_viewer, args=(view.port, stop, counts), daemon=True)
            thread.start()
    result = run_study(study, None, plots=False, progress=False, observers=observers)
    if view is not None:
        view.stop()
    stop.set()
    if thread is not None:
        thread.join(5)
    return result.metrics["wall_time_s"], counts[0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--rate", type=float, default=LIVE_RATE_HZ)
    args = parser.parse_args()
    times = {m: [] for m in ("none", "server", "viewer")}
    received = 0
    for _ in range(args.repeats):
        for mode in times:
            wall, n = one(mode, args.rate)
            times[mode].append(wall)
            received = max(received, n)
    base = statistics.median(times["none"])
    print(f"figure-8, 160 s simulated, {args.repeats} runs each, live view at {args.rate:g} instants/s of wall time")
    print(f"{'live view':<34}{'median wall [s]':>16}{'ratio':>8}")
    for mode, label in (("none", "none"), ("server", "served, no viewer"), ("viewer", "served, a viewer subscribed")):
        med = statistics.median(times[mode])
        print(f"{label:<34}{med:>16.3f}{med / base:>8.3f}")
    print(f"messages the viewer received in its run: {received}")


if __name__ == "__main__":
    main()
