"""Observers of a run, kept apart from the master algorithm (after libcosim's observers): they see
the simulation, never change it. The engine (orchestrator.engine) calls each hook an observer
defines, and only those:

- ``started(sim)``: every component initialised and its outputs at t0 published (the other hooks
  are read after it: an observer may set them there);
- ``instant(k)``: before base step k is taken (real-time pacing, orchestrator.realtime);
- ``recorded(phase)``: every output of instant k is published (``sim.published``), before
  anything integrates past t_k (the signal recorder, orchestrator.signal_recorder); ``phase`` is
  k modulo the schedule's period;
- ``advanced(k)``: a call to ``Simulation.advance`` has reached base step k (progress).

``Stage`` and ``report_progress`` tell the same of the steps of a command outside the engine
(an analysis, a compiler run).

Imported where used: tqdm (start-up: 0.012 s on every command; the bar is drawn on a terminal only).
"""
from __future__ import annotations

import os
import sys
import threading
import time


PROGRESS = {"shown": True}       # a command's --no-progress or --quiet turns every progress line off


class Observer:
    """Base of the observers: a hook left None is not called."""

    started = None
    instant = None
    recorded = None
    advanced = None


class Progress(Observer):
    """How far a run is, in the unit of its work: a component that defines ``run_progress()`` returning
    (done, total, unit) (a route: metres of the route) is asked; otherwise simulated time against
    the stop time. tqdm on a terminal; otherwise a line on stderr once the run has lasted
    ``first`` seconds, then every ``every`` seconds."""

    def __init__(self, total_steps: int, h: float, every: float = 10.0, first: float = 5.0) -> None:
        self.total, self.h, self.every = total_steps, h, every
        self.t_start = time.perf_counter()
        self.next = self.t_start + first
        self.bar = None
        self._source = None              # (component name, its progress method)

    def started(self, sim) -> None:
        for node in sim.system.nodes.values():
            report = getattr(node.component, "run_progress", None)
            if callable(report) and report() is not None:
                self._source = (node.name, report)
                break
        if sys.stderr.isatty() and PROGRESS["shown"]:
            from tqdm import tqdm

            total, unit = (self.total * self.h, "s") if self._source is None else self._source[1]()[1:]
            self.bar = tqdm(total=total, unit=unit, file=sys.stderr, leave=False, mininterval=1.0,
                            desc=self._source[0] if self._source else "simulated time",
                            bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.0f}/{total:.0f} {unit} [{elapsed}<{remaining}]")

    def _where(self, k: int) -> tuple[float, float, str]:
        if self._source is not None:
            return self._source[1]()
        return k * self.h, self.total * self.h, "s"

    def advanced(self, k: int) -> None:
        if self.bar is not None:
            self.bar.n = self._where(k)[0]
            self.bar.refresh()
            return
        now = time.perf_counter()
        if now < self.next or not PROGRESS["shown"]:
            return
        self.next = now + self.every
        done, total, unit = self._where(k)
        share = done / total if total else 1.0
        amount = (lambda x: f"{x:.0f}") if total >= 100 else (lambda x: f"{x:.3g}")
        what = f"{self._source[0]} {amount(done)} of {amount(total)} {unit} ({100 * share:.0f}%), t = {k * self.h:.6g} s" \
            if self._source else f"t = {done:.6g} of {total:.6g} s ({100 * share:.0f}%)"
        print(f"progress: {what}, {k * self.h / (now - self.t_start):.3g} x real time", file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _terminal():
    """A stream to the terminal the command was started with, even while a tool sends this
    process's stderr elsewhere (a compiler's output to a log file)."""
    try:
        return os.fdopen(os.dup(sys.stderr.fileno()), "w", buffering=1)
    except (OSError, ValueError, AttributeError):
        return sys.stderr


_STAGES: list["Stage"] = []


class Stage:
    """``with Stage("analysing the signals"):`` a step of a command that may take a while: once it
    has lasted ``first`` seconds a line says what it is doing and for how long, then every
    ``every`` seconds, with the progress it reports (``report_progress``); a step that ends sooner
    prints nothing. Of nested stages only the innermost speaks."""

    def __init__(self, what: str, first: float = 5.0, every: float = 10.0) -> None:
        self.what, self.first, self.every = what, first, every
        self.detail = ""
        self.printed = False

    def __enter__(self) -> "Stage":
        self._start = time.perf_counter()
        self._stop = threading.Event()
        self._out = _terminal()
        self._thread = threading.Thread(target=self._watch, daemon=True, name="stage")
        self._thread.start()
        _STAGES.append(self)
        return self

    def _watch(self) -> None:
        wait = self.first
        while not self._stop.wait(wait):
            wait = self.every
            if (_STAGES and _STAGES[-1] is not self) or not PROGRESS["shown"]:
                continue
            elapsed = time.perf_counter() - self._start
            print(f"{self.what}{': ' + self.detail if self.detail else ''} ... {elapsed:.0f} s",
                  file=self._out, flush=True)
            self.printed = True

    def __exit__(self, *exc) -> None:
        _STAGES.remove(self)
        self._stop.set()
        self._thread.join()
        if self.printed and exc[0] is None:
            print(f"{self.what}: done in {time.perf_counter() - self._start:.0f} s", file=self._out, flush=True)
        if self._out is not sys.stderr:
            self._out.close()


def timed_progress():
    """A ``progress(text)`` that prints each line on stderr with the seconds since it was made
    (nothing with --no-progress or --quiet); ``progress.terminal``: stderr is a terminal (a counted
    stage draws a tqdm bar there, orchestrator.work_progress)."""
    start = time.perf_counter()

    def progress(text: str) -> None:
        if PROGRESS["shown"]:
            print(f"[{time.perf_counter() - start:6.1f} s] {text}", file=sys.stderr, flush=True)
    progress.terminal = sys.stderr.isatty()           # counted stages draw a bar there (work_progress)
    return progress


def report_progress(done: float, total: float, unit: str) -> None:
    """What an analysis or a tool may call while it works ("12 of 40 swaths"): shown by the
    innermost running Stage, nothing otherwise."""
    if _STAGES:
        _STAGES[-1].detail = f"{done:.6g} of {total:.6g} {unit}"
