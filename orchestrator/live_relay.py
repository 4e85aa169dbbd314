"""The live view's front door: a WebSocket relay, in a process of its own, between the viewers and the
Foxglove SDK's server (orchestrator.mcap_out.LiveView).

The SDK's server (foxglove-sdk 0.30) speaks the Foxglove WebSocket protocol under the subprotocols
``foxglove.sdk.v1`` and ``foxglove.sdk.v1.1`` only, has no option to add another and none to bound its
clients. The relay accepts ``foxglove.websocket.v1`` (Lichtblick, PlotJuggler's Foxglove bridge, Foxglove
Studio before 2.0, the protocol's reference client) beside them: Foxglove states that ``foxglove.sdk.v1`` is
the same protocol under a new name, so each frame is passed on unchanged, over a connection of its own to the
SDK's server (``foxglove.sdk.v1`` for a ``foxglove.websocket.v1`` viewer).

Bounds, so that no number of viewers, and no slow one, holds the run:

- at most ``--max-viewers`` viewers at once; one more is accepted and closed at once with code 1013 (try
  again later) and a reason naming the limit and the option that changes it; a request without one of
  the subprotocols is refused with HTTP 400 naming them;
- per viewer, the frames from the server wait in a queue of ``--queue`` frames: when it is full the oldest
  message data frame (binary) is dropped, and counted; a viewer whose control messages (text: advertise,
  status) alone fill it is closed (1008, too slow);
- the relay reads the server without waiting on any viewer, and runs at a lower priority (nice +5) in its
  own process: its work never takes the run's interpreter lock.

Protocol with the parent: one JSON line on standard output once listening (``{"listening": port}``) or
refused (``{"error": text}``, exit 2); standard input closed (the parent ended or died): the relay writes
one JSON line of counts, lets its viewers drain (3 s at most) and exits.

    python -P live_relay.py --upstream ws://127.0.0.1:PORT --host HOST --port PORT --max-viewers N --queue N
"""
from __future__ import annotations

import argparse
import asyncio
import json
import os
import selectors
import subprocess
import sys
import time
from collections import Counter, deque

from websockets.asyncio.client import connect
from websockets.asyncio.server import serve
from websockets.exceptions import ConnectionClosed

# what the relay accepts from a viewer -> what it speaks to the SDK's server (the same frames)
SUBPROTOCOLS = {"foxglove.websocket.v1": "foxglove.sdk.v1", "foxglove.sdk.v1": "foxglove.sdk.v1",
                "foxglove.sdk.v1.1": "foxglove.sdk.v1.1"}
TRY_AGAIN_LATER, POLICY_VIOLATION = 1013, 1008
RELAY_NICE = 5


class ViewerQueue:
    """The frames waiting for one viewer, at most ``limit``: a new frame in a full queue drops the oldest
    message data frame (bytes); ``put`` returns False when there is none to drop (control frames alone fill
    it: the viewer is too slow). ``finish()`` ends it once the frames left are taken."""

    def __init__(self, limit: int) -> None:
        self.limit, self.frames, self.dropped = max(int(limit), 1), deque(), 0
        self.ready = asyncio.Event()
        self.finished = False

    def put(self, frame: str | bytes) -> bool:
        if len(self.frames) >= self.limit:
            oldest = next((k for k, f in enumerate(self.frames) if isinstance(f, bytes)), None)
            if oldest is None:
                return False
            del self.frames[oldest]
            self.dropped += 1
        self.frames.append(frame)
        self.ready.set()
        return True

    def finish(self) -> None:
        self.finished = True
        self.ready.set()

    async def get(self) -> str | bytes | None:
        """The oldest frame, or None once finished and empty."""
        while not self.frames:
            if self.finished:
                return None
            self.ready.clear()
            await self.ready.wait()
        return self.frames.popleft()


class Relay:
    """Viewers in, one SDK connection each out; ``counts`` what happened (by subprotocol, refused, dropped)."""

    def __init__(self, upstream: str, max_viewers: int, queue: int) -> None:
        self.upstream, self.max_viewers, self.queue = upstream, int(max_viewers), int(queue)
        self.active = 0
        self.counts: Counter = Counter()

    def check_request(self, connection, request):
        """HTTP 400 for a request without a subprotocol the relay speaks (the SDK's own refusal tells the
        viewer nothing)."""
        offered = [p.strip() for h in request.headers.get_all("Sec-WebSocket-Protocol") for p in h.split(",")]
        if not any(p in SUBPROTOCOLS for p in offered):
            self.counts["refused_subprotocol"] += 1
            return connection.respond(400, f"expected the WebSocket subprotocol {' or '.join(SUBPROTOCOLS)} "
                                           f"(Foxglove WebSocket protocol); offered: {', '.join(offered) or 'none'}\n")
        return None

    @staticmethod
    def choose(connection, offered):
        """The first subprotocol the viewer offers that the relay speaks."""
        return next((p for p in offered if p in SUBPROTOCOLS), None)

    async def handle(self, viewer) -> None:
        if self.active >= self.max_viewers:
            self.counts["refused_full"] += 1
            await viewer.close(TRY_AGAIN_LATER, f"live view full: {self.max_viewers} viewer{'' if self.max_viewers == 1 else 's'} at most "
                                                f"(--live-viewers N changes it)")
            return
        self.active += 1
        self.counts[viewer.subprotocol] += 1
        try:
            await self._serve(viewer)
        finally:
            self.active -= 1

    async def _serve(self, viewer) -> None:
        try:
            server = await connect(self.upstream, subprotocols=[SUBPROTOCOLS[viewer.subprotocol]], proxy=None,
                                   compression=None, max_size=None, open_timeout=10, close_timeout=2)
        except (OSError, asyncio.TimeoutError, ConnectionClosed) as exc:
            await viewer.close(1011, f"the run's server did not answer ({type(exc).__name__})")
            return
        queue = ViewerQueue(self.queue)
        tasks = [asyncio.ensure_future(c) for c in (self._from_server(server, viewer, queue),
                                                    self._to_viewer(viewer, queue), self._from_viewer(viewer, server))]
        try:
            await tasks[1]                      # the viewer served until the run ends or it leaves
        finally:
            for task in tasks:
                task.cancel()
            await server.close()

    async def _from_server(self, server, viewer, queue: ViewerQueue) -> None:
        """Every frame of the server into the viewer's queue, never waiting on the viewer."""
        try:
            async for frame in server:
                dropped = queue.dropped
                if not queue.put(frame):
                    self.counts["closed_slow"] += 1
                    await viewer.close(POLICY_VIOLATION, "viewer too slow: its control messages filled its queue")
                    break
                self.counts["dropped"] += queue.dropped - dropped
        except ConnectionClosed:
            pass
        queue.finish()

    @staticmethod
    async def _to_viewer(viewer, queue: ViewerQueue) -> None:
        try:
            while (frame := await queue.get()) is not None:
                await viewer.send(frame)
            await viewer.close(1001, "the run ended")
        except ConnectionClosed:
            pass

    @staticmethod
    async def _from_viewer(viewer, server) -> None:
        """The viewer's requests (subscribe, unsubscribe ...) to the server; the viewer gone, its queue ends."""
        try:
            async for frame in viewer:
                await server.send(frame)
        except ConnectionClosed:
            pass
        await server.close()


async def _stdin_closed() -> None:
    """Returns when standard input ends (the parent closed it, or died)."""
    await asyncio.get_running_loop().run_in_executor(None, sys.stdin.buffer.read)


async def run(args: argparse.Namespace) -> int:
    relay = Relay(args.upstream, args.max_viewers, args.queue)
    try:
        server = await serve(relay.handle, args.host, args.port, subprotocols=list(SUBPROTOCOLS),
                             select_subprotocol=relay.choose, process_request=relay.check_request, compression=None,
                             close_timeout=2, max_size=2 ** 20, backlog=1024)
    except (OSError, OverflowError) as exc:
        _say({"error": str(exc)})
        return 2
    _say({"listening": server.sockets[0].getsockname()[1]})
    await _stdin_closed()
    _say(dict(relay.counts))                       # first: a relay starved of the processor still reports
    server.close(close_connections=False)          # the viewers left drain their queues, then close
    try:
        await asyncio.wait_for(server.wait_closed(), 3)
    except asyncio.TimeoutError:
        pass
    return 0


def _say(line: dict) -> None:
    """One JSON line to the parent (gone: nothing to tell)."""
    try:
        print(json.dumps(line), flush=True)
    except (BrokenPipeError, ValueError):
        pass


class RelayProcess:
    """The relay, started from the run's process: ``port`` once it listens; ``stop()`` ends it and returns
    its counts. A refusal (the port in use, a host that cannot be bound) raises RelayRefused with the reason."""

    def __init__(self, upstream_port: int, host: str, port: int, max_viewers: int, queue: int,
                 timeout: float = 30.0) -> None:
        # a session of its own: Ctrl-C reaches the run, which stops the relay
        self.proc = subprocess.Popen(
            [sys.executable, "-P", os.path.abspath(__file__), "--upstream", f"ws://127.0.0.1:{upstream_port}",
             "--host", host, "--port", str(port), "--max-viewers", str(max_viewers), "--queue", str(queue)],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, start_new_session=True)
        self.late = False
        first = self._line(timeout) or {}
        if "listening" not in first:
            self._end(5.0)
            raise RelayRefused(first.get("error", "the relay ended before it listened"))
        self.port = int(first["listening"])

    def _line(self, timeout: float) -> dict | None:
        """The relay's next JSON line within ``timeout`` seconds (None if none)."""
        with selectors.DefaultSelector() as selector:
            selector.register(self.proc.stdout, selectors.EVENT_READ)
            if not selector.select(timeout):
                return None
        line = self.proc.stdout.readline()
        try:
            return json.loads(line) if line.strip() else None
        except json.JSONDecodeError:
            return None

    def _end(self, timeout: float) -> None:
        try:
            self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()

    def finish(self) -> None:
        """Tell the relay to end (its standard input closed): it reports, then closes its viewers once their
        server has gone."""
        if not self.proc.stdin.closed:
            self.proc.stdin.close()

    def stop(self, timeout: float = 10.0) -> dict:
        """End the relay: its counts of viewers by subprotocol, refused, dropped ({} and ``late`` if none came
        within ``timeout`` seconds)."""
        if self.proc.poll() is not None:          # ended before: its error is on the run's standard error
            self.late = True
            return {}
        deadline = time.monotonic() + timeout
        self.finish()
        counts = self._line(timeout)
        self.late = counts is None
        self._end(max(deadline - time.monotonic(), 0.1))
        self.proc.stdout.close()
        return counts or {}


class RelayRefused(RuntimeError):
    """The relay could not serve where asked."""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="the live view's WebSocket relay (orchestrator.mcap_out)")
    parser.add_argument("--upstream", required=True, help="ws://HOST:PORT of the Foxglove SDK's server")
    parser.add_argument("--host", required=True)
    parser.add_argument("--port", type=int, required=True)
    parser.add_argument("--max-viewers", type=int, required=True)
    parser.add_argument("--queue", type=int, required=True, help="frames waiting per viewer")
    args = parser.parse_args(argv)
    try:
        os.nice(RELAY_NICE)
    except OSError:
        pass
    return asyncio.run(run(args))


if __name__ == "__main__":
    sys.exit(main())
