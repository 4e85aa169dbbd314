"""Which components are due at base step k, and what a run will cost before it starts.

A component stepping every ``ratio`` base steps is due at k when ``k % ratio == 0``; the pattern
repeats with period ``lcm(ratios)``. For rates that share a factor the period is short and the
due lists are a table indexed by ``k % period``. Coprime rates make the period astronomical
(70, 110, 130, 170, 190 and 230 ms on a 1 ms base step: about 7.4e10 base steps), yet only a few
distinct *sets* of due components occur: the lists are then made the first time a set is met and
kept by that set (at most one per set that occurs, never one per phase).

``budget`` computes, before anything is built, the base steps of the run and the memory the
signal table holds between two writes, and refuses a run past the limits with the numbers and a
base step that would serve.
"""
from __future__ import annotations

import math
from fractions import Fraction
from typing import Any, Callable, Iterable, Sequence

from .study_files import StudyError

TABLE_LIMIT = 4096                 # phases held as a table; beyond, due lists are made when met
MAX_BASE_STEPS = 2_000_000_000     # a run longer than this is refused (hours of stepping at best)
MAX_HELD_BYTES = 2 * 1024 ** 3     # the signal rows held in memory between two writes
WRITE_EVERY = 10_000               # base steps between two writes of the signal table ...
WRITE_BYTES = 32 * 1024 ** 2       # ... unless the whole run's table fits in this: one write after it


class Schedule:
    """``schedule[phase]``: ``make(due)`` for the items due at ``phase`` (``phase % ratio == 0``),
    ``phase`` being ``k % schedule.period``."""

    def __init__(self, items: Sequence[Any], ratio: Callable[[Any], int], make: Callable[[list], Any] = list,
                 table_limit: int = TABLE_LIMIT) -> None:
        self.items, self._ratio, self._make = list(items), ratio, make
        self.ratios = sorted({ratio(i) for i in self.items}) or [1]
        self.period = math.lcm(*self.ratios)
        self._cache: dict[tuple[int, ...], Any] = {}
        self._table = [self._lookup(j) for j in range(self.period)] if self.period <= table_limit else None
        # ``lookup(phase)`` is ``schedule[phase]``: the table's own indexing when there is one (no
        # Python call at each base step)
        self.lookup: Callable[[int], Any] = self._table.__getitem__ if self._table is not None else self._lookup

    def _lookup(self, phase: int) -> Any:
        key = tuple(r for r in self.ratios if phase % r == 0)
        entry = self._cache.get(key)
        if entry is None:
            due = set(key)
            entry = self._cache[key] = self._make([i for i in self.items if self._ratio(i) in due])
        return entry

    def __getitem__(self, phase: int) -> Any:
        return self._table[phase] if self._table is not None else self._lookup(phase)

    @property
    def sets(self) -> int:
        """Distinct due lists made so far (the memory the schedule holds)."""
        return len(self._cache)


def block_rows(columns: int, rows: int, steps: int = WRITE_EVERY, held_bytes: int = WRITE_BYTES) -> int:
    """Base steps between two writes of a signal table of ``columns`` signals (and time) over a run
    of ``rows`` rows: the whole run when its table fits in ``held_bytes`` (a write costs 30 ms
    whatever its rows: a 160 s figure-8 is written once, after the run), else ``steps``."""
    return max(rows, steps) if rows * (columns + 1) * 8 <= held_bytes else steps


def common_step(steps: Iterable[float]) -> float | None:
    """The largest step of which every one of ``steps`` is a whole multiple (their greatest common
    divisor as fractions of a second, to a nanosecond), None for none."""
    fracs = [Fraction(s).limit_denominator(10 ** 9) for s in steps if s and s > 0]
    if not fracs:
        return None
    num = math.gcd(*(f.numerator for f in fracs))
    den = math.lcm(*(f.denominator for f in fracs))
    return float(Fraction(num, den))


def _size(n: float) -> str:
    for unit in ("B", "kB", "MB", "GB", "TB"):
        if n < 1024 or unit == "TB":
            return f"{n:.3g} {unit}"
        n /= 1024
    return f"{n:.3g} TB"


def budget(where: str, base_step: float, span: float, steps: Iterable[float], ratios: Iterable[int], columns: int,
           chunk: int, max_steps: int = MAX_BASE_STEPS, max_bytes: int = MAX_HELD_BYTES) -> dict[str, float]:
    """The cost of a run, computed before anything is built: base steps, the schedule's period
    and the bytes of signal rows held between two writes (a write falls on a multiple of the
    period, at least ``chunk`` base steps apart). Raises a StudyError past a limit."""
    steps = list(steps)
    n_steps = span / base_step
    period = math.lcm(*ratios) if ratios else 1
    held_rows = min(n_steps + 1, max(chunk, period) + 1)
    held = held_rows * (columns + 1) * 8
    facts = {"base_steps": n_steps, "period": period, "held_bytes": held}
    if n_steps <= max_steps and held <= max_bytes:
        return facts
    common = common_step(steps)
    hint = (f"; the components' steps ({', '.join(f'{s:g}' for s in sorted(set(steps))[:8])} s) are all whole "
            f"multiples of {common:g} s: set study.base_step = {common:g}" if common and common > base_step else
            "; choose a larger study.base_step or a shorter run")
    if n_steps > max_steps:
        raise StudyError(f"{where}: study.base_step = {base_step:g} s over {span:g} s is {n_steps:.3g} base steps, "
                         f"more than the {max_steps:.3g} a run may take{hint}")
    raise StudyError(f"{where}: study.base_step = {base_step:g} s: the signal table would hold {held_rows:.3g} rows "
                     f"of {columns + 1} columns ({_size(held)}) in memory, more than {_size(max_bytes)}{hint}")
