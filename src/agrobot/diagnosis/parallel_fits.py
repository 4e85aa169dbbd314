"""The selection's candidate fits over several worker processes, with the same result whatever
their number.

A fit is a pure function of its arguments and the replay (candidates.fit_key; the replays' caches are
exact), so it may be computed anywhere, ahead of being asked for. Before the selection fits a batch
of independent candidates (each effect joined to the model in turn, each pair of effects of a misfit
stage), the batch is run once with every fit only noted (candidates._fit, ``replay.collecting``);
the noted fits are computed by the workers, and the batch then runs for real, each fit taken from
those computed ahead (``replay.fits_ahead``) when its arguments are the same, else computed there.
The selection's own code decides everything, in its own order: the workers only make its fits
ready sooner.

The workers are processes of the ``forkserver`` start method where the platform has it (else
``spawn``): nothing is inherited but the replay, sent once to each worker, so the pool works from
threads, and from any script (the workers do not run it again: FitPool._start).

Imported where used: multiprocessing, threading, types (only for more than one worker: a diagnosis on
one worker never loads them).
"""
from __future__ import annotations

import copy
import os
import pickle
import sys

from threadpoolctl import threadpool_limits

from agrobot.orchestrator.work_progress import Work

from .candidates import Replay, Speculated, fit_key, fitted
from .selection import Selector

_WORKER: dict[str, Replay] = {}
PRELOAD = ["agrobot.diagnosis.candidates"]        # what the forkserver imports once for every worker


def default_workers() -> int:
    """The cores this process may run on."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:              # not on Linux
        return max(1, os.cpu_count() or 1)


def _install(payload: bytes) -> None:
    """A worker's replay, and its BLAS libraries on one thread (identification.blas_threads)."""
    threadpool_limits(limits=1, user_api="blas")
    _WORKER["replay"] = pickle.loads(payload)


def _fit_in_worker(args: tuple):
    """The fit, or None when it fails (a fit computed ahead that the selection may never ask for:
    if it does, it fails there, as it would on one worker)."""
    try:
        return fitted(_WORKER["replay"], *args)
    except Exception:       # noqa: BLE001 - any failure is the selection's to meet, in its own order
        return None


class FitPool:
    """Fits computed ahead by ``workers`` processes (none for one worker), the replay sent to each
    when the pool starts."""

    def __init__(self, replay: Replay, workers: int) -> None:
        self.replay, self.workers = replay, max(1, int(workers))
        if self.workers > 1:
            import multiprocessing

            if multiprocessing.current_process().daemon:     # a daemonic process may not start any
                self.workers = 1
        self._pool = None

    def warm(self) -> None:
        """Start the forkserver (a fresh interpreter importing the replay's modules, a second or two) in
        the background, while the baseline is fitted: the workers fork from it when the pool starts."""
        import multiprocessing
        import multiprocessing.forkserver
        import threading

        if self.workers > 1 and "forkserver" in multiprocessing.get_all_start_methods():
            multiprocessing.get_context("forkserver").set_forkserver_preload(PRELOAD)
            threading.Thread(target=multiprocessing.forkserver.ensure_running, daemon=True).start()

    def _start(self):
        """A multiprocessing pool, every worker started now with the replay. The workers do not run the
        caller's main script again (spawn and forkserver would, and a script without a main guard
        would diagnose again in each): the main module is hidden while they start."""
        import multiprocessing
        import types

        method = "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn"
        context = multiprocessing.get_context(method)
        if method == "forkserver":
            context.set_forkserver_preload(PRELOAD)
        payload = pickle.dumps(self.replay, protocol=pickle.HIGHEST_PROTOCOL)
        main = sys.modules["__main__"]
        sys.modules["__main__"] = types.ModuleType("__main__")
        try:
            return context.Pool(self.workers, initializer=_install, initargs=(payload,))
        finally:
            sys.modules["__main__"] = main

    def ahead(self, batch, first_only: bool) -> None:
        """Run ``batch`` (a callable) with its fits only noted (``first_only``: stopped at its first),
        and compute the noted fits on the workers, ready for the batch's real run."""
        if self.workers < 2:
            return
        replay = self.replay
        replay.collecting, replay.collect_first = [], first_only
        try:
            batch()
        except Exception:       # noqa: BLE001 - noting is best effort: the real run meets any failure itself
            pass
        finally:
            noted = replay.__dict__.pop("collecting")
            del replay.collect_first
        ready = replay.__dict__.get("fits_ahead") or {}
        wanted = {fit_key(*args): args for args in noted}
        ready = {k: ready[k] for k in wanted if k in ready}          # what this batch may still ask for
        jobs = [(k, args) for k, args in wanted.items() if k not in ready]
        if len(jobs) >= 2 and self._pool is None:
            try:
                self._pool = self._start()
            except (OSError, AssertionError) as exc:   # AssertionError: inside a daemonic process (a Pool's worker)
                print(f"note: the candidate fits run in this process only ({exc})", file=sys.stderr)
                self.workers = 1
        if len(jobs) >= 2 and self._pool is not None:
            done = self._pool.map(_fit_in_worker, [a for _, a in jobs], chunksize=1)
            ready.update((k, fit) for (k, _), fit in zip(jobs, done) if fit is not None)
        replay.fits_ahead = ready

    def close(self) -> None:
        if self._pool is not None:
            self._pool.close()
            self._pool.join()
            self._pool = None
        self.replay.__dict__.pop("fits_ahead", None)


class ParallelSelector(Selector):
    """The selection (diagnosis.selection.Selector) with its batches of candidate fits computed
    ahead by a FitPool: each effect joined to the model (``add``, from the first candidate of a
    batch on) and each pair of a misfit stage (``pair``)."""

    def __init__(self, *args, workers: int = 1, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.pool = FitPool(self.replay, workers)
        self.pool.warm()

    def run(self):
        try:
            return super().run()
        finally:
            self.pool.close()

    def _shadow(self) -> Selector:
        """A copy whose runs leave this selector as it was (its caches, starts and catalogue its own)."""
        shadow = copy.copy(self)
        shadow._cache, shadow._first = dict(self._cache), dict(self._first)
        shadow.catalogue, shadow.widened, shadow.work = list(self.catalogue), list(self.widened), Work(None, "", 0)
        return shadow

    def add(self, model, members, effect):
        """Selector.add, the candidates from ``effect`` to the catalogue's end (what the selection's step
        asks for next) computed ahead when ``effect``'s fit is not ready."""
        if self.pool.workers > 1:
            rest = [e for e in self.catalogue if e not in members]
            batch = [effect] + (rest[rest.index(effect) + 1:] if effect in rest else [])
            shadow = self._shadow()

            def noted():
                for e in batch:
                    try:
                        Selector.add(shadow, model, members, e)
                    except Speculated:
                        pass
            self.pool.ahead(noted, first_only=True)
        return super().add(model, members, effect)

    def pair(self, model, members, removed):
        if self.pool.workers > 1:
            self.misfit_stages(model)               # memoised: the noting run reads it, fits nothing
            shadow = self._shadow()
            self.pool.ahead(lambda: Selector.pair(shadow, model, members, removed), first_only=False)
        return super().pair(model, members, removed)
