"""A sweep's points on a Dask cluster (``--scheduler ADDRESS``, or ``local`` to start one): the
client made, the points submitted as their workers free up, and an interrupted sweep's cluster
ended at once (orchestrator.sweep runs the points; this module only carries them).

Imported where used: distributed and psutil (the dask extra; psutil comes with distributed).
"""
from __future__ import annotations

import contextlib
import logging
import signal
import threading
import time
from typing import Any, Callable

from .study import StudyError


def point_result(fut) -> dict[str, Any]:
    """A finished point's result; a worker that died is a failed point (kind bug), not an error."""
    try:
        return fut.result()
    except Exception as exc:  # a worker process died (killed, out of memory)
        return {"status": "failed", "kind": "bug", "error": f"worker lost: {type(exc).__name__}: {exc}"}


CONNECT_TIMEOUT = 6.0        # s: a wrong --scheduler address fails well within 10 s


class SchedulerError(StudyError):
    """The --scheduler address does not lead to a Dask scheduler (exit 2)."""


def dask_client(scheduler: str, workers: int):
    """(client, local cluster or None, this process's children before it started): a Dask client on
    ``scheduler`` ('local': a cluster of ``workers`` processes started here). An interrupt while
    the cluster starts kills what it started; an address that does not answer is a SchedulerError."""
    from distributed import Client, LocalCluster

    before = _children()
    client = cluster = None
    try:
        if scheduler == "local":
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
            client = Client(cluster)
        else:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError, ValueError) as exc:
        abandon_cluster(client, cluster, before)
        if scheduler == "local":
            raise
        raise SchedulerError(f"--scheduler {scheduler}: no Dask scheduler answered within "
                             f"{CONNECT_TIMEOUT:g} s ({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}); "
                             f"expected an address like tcp://HOST:8786, or 'local'") from None
    except BaseException:
        abandon_cluster(client, cluster, before)
        raise
    return client, cluster, before


def execute_dask(run: Callable, jobs, workers: int, scheduler: str, keep_signals: bool = True):
    """(point, result, folder) as points finish, each point run by ``run`` (orchestrator.sweep's
    simulate_point) on a worker of ``scheduler``."""
    from distributed import as_completed

    client, cluster, before = dask_client(scheduler, workers)
    try:
        futures = {client.submit(run, point, str(folder) if folder else None, "python", keep_signals,
                                 pure=False,
                                 key=f"{p.key}-{time.time_ns()}"): (p, folder) for p, point, folder in jobs}
        for fut in as_completed(futures):
            point, folder = futures[fut]
            yield point, point_result(fut), folder
    except BaseException:
        abandon_cluster(client, cluster, before)
        raise
    client.close()
    if cluster is not None:
        cluster.close()


def _children() -> set[int]:
    """The process ids of this process's children, grandchildren included, but multiprocessing's
    resource tracker (shared with the rest of the process; killed, its successor reports every
    resource it did not know)."""
    import psutil

    out = set()
    for child in psutil.Process().children(recursive=True):
        with contextlib.suppress(psutil.Error):
            if not any("resource_tracker" in part for part in child.cmdline()):
                out.add(child.pid)
    return out


def abandon_cluster(client, cluster, before: set[int]) -> None:
    """An interrupted Dask sweep ends now: the local cluster's processes (those started since
    ``before``) are killed rather than asked to finish (its orderly close waited some 13 s, and a
    second Ctrl-C inside it left the process hanging until SIGKILL), then the client and cluster
    are closed within a second each. SIGINT and SIGTERM are held off meanwhile: a second Ctrl-C
    cannot cut the clean-up in half. The points in flight are dropped (their folders are in
    .running, removed by the sweep; a rerun does them again)."""
    import psutil

    for name in ("asyncio", "distributed", "tornado"):       # a cluster killed at start complains of it
        logging.getLogger(name).setLevel(logging.CRITICAL)
    main = threading.current_thread() is threading.main_thread()
    held = {s: signal.signal(s, signal.SIG_IGN) for s in (signal.SIGINT, signal.SIGTERM)} if main else {}
    try:
        if cluster is not None:
            for pid in _children() - before:
                with contextlib.suppress(psutil.Error):
                    psutil.Process(pid).kill()
        for close in (getattr(client, "close", None), getattr(cluster, "close", None)):
            if close is not None:
                with contextlib.suppress(Exception):
                    close(timeout=1)
    finally:
        for sig, handler in held.items():
            signal.signal(sig, handler)
