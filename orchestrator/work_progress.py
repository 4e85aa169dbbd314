"""How far a counted stage of a tool is, and an estimate of what remains (identify, diagnose).

``with Work(say, "fitting the candidate effects", 15, "fits") as work:`` then ``work.step()`` after
each unit. ``say`` is the tool's progress callable (the command's lines on stderr,
orchestrator.observers.timed_progress, or the Python API's ``progress=``); it gets the stage when
it starts, then at most every ``every`` seconds

    fitting the candidate effects: 6 of 15 fits (40%), 12 s so far, about 18 s left

(left = elapsed / done x (total - done), the rate so far), and the time it took at the end. On a
terminal (a ``say`` whose ``terminal`` attribute is true) a tqdm bar replaces the lines in between.
``work.more(n)`` grows the total when a stage learns it has more to do (a further round).

Imported where used: tqdm (on a terminal only).
"""
from __future__ import annotations

import sys
import time
from typing import Callable

from .observers import PROGRESS


def _seconds(s: float) -> str:
    return f"{s:.0f} s" if s < 120 else f"{s / 60:.1f} min"


class Work:
    def __init__(self, say: Callable[[str], None] | None, what: str, total: int, unit: str = "",
                 every: float = 5.0) -> None:
        self.say = say or (lambda text: None)
        self.what, self.total, self.unit, self.every = what, max(int(total), 0), unit, every
        self.done = 0
        self.bar = None
        self.start = self.last = time.perf_counter()

    def __enter__(self) -> "Work":
        self.start = self.last = time.perf_counter()
        self.say(f"{self.what}: {self.total} {self.unit}".rstrip())
        if getattr(self.say, "terminal", False) and PROGRESS["shown"]:
            from tqdm import tqdm

            self.bar = tqdm(total=self.total, desc=self.what, unit=f" {self.unit}" if self.unit else "it",
                            file=sys.stderr, leave=False, mininterval=0.5)
        return self

    def line(self) -> str:
        """What the stage has done and about what remains."""
        elapsed = time.perf_counter() - self.start
        share = self.done / self.total if self.total else 1.0
        left = f", about {_seconds(elapsed / self.done * (self.total - self.done))} left" if self.done else ""
        return (f"{self.what}: {self.done} of {self.total} {self.unit} ({100 * share:.0f}%), "
                f"{_seconds(elapsed)} so far{left}").replace("  ", " ")

    def step(self, n: int = 1) -> None:
        self.done += n
        self.total = max(self.total, self.done)
        if self.bar is not None:
            self.bar.total = self.total
            self.bar.update(n)
            return
        now = time.perf_counter()
        if now - self.last >= self.every and self.done < self.total:
            self.last = now
            self.say(self.line())

    def more(self, n: int) -> None:
        """The stage has ``n`` units more to do than it said."""
        self.total += max(int(n), 0)
        if self.bar is not None:
            self.bar.total = self.total
            self.bar.refresh()

    def __exit__(self, *exc) -> None:
        if self.bar is not None:
            self.bar.close()
        if exc[0] is None:
            self.say(f"{self.what}: {self.done} {self.unit} done in {_seconds(time.perf_counter() - self.start)}"
                     .replace("  ", " "))
