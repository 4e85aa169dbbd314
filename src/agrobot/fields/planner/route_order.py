"""Route order: the swaths in driving order, each entered from its nearer end, then the headland
passes.

- **Pattern**: boustrophedon when a U-turn fits between adjacent swaths (d >= about 2 R_min);
  otherwise rows are skipped in blocks (``skip_order``: every move spans at least s lines, the
  smallest s whose s d fits a U-turn), so no turn loops round (an omega turn needs far more
  headland).
- **Cells**: each driven in that pattern, forwards or backwards; from the first on, the nearest
  unvisited cell next (by the straight distance to its first swath's nearer end).
"""
from __future__ import annotations

import math

import numpy as np

from .curves import Limits, connect
from .optimise import order as optimised
from .settings import Settings
from .types import Cell, HeadlandPass, Route, Swath


def u_turn(D: float, limits: Limits) -> np.ndarray | None:
    """The CC turn between two swaths D apart (the second to the left), or None."""
    return connect((0.0, 0.0, 0.0), (0.0, D, math.pi), limits)


def reach(path: np.ndarray) -> float:
    """How far a turn from a swath's end runs on beyond it."""
    return float(np.max(path[:, 0]))


def pattern(settings: Settings) -> tuple[str, int, float]:
    """(order, skip, how far its turns reach beyond the swath ends)."""
    spacing, limits = settings.spacing, settings.limits

    def csc(D):          # a U-turn of turn-straight-turn turning through pi once: no loop
        p = connect((0.0, 0.0, 0.0), (0.0, D, math.pi), limits, families=("LSL",))
        return p is not None and np.all(np.diff(p[:, 2]) >= -1e-9) and np.ptp(p[:, 2]) <= math.pi + 1e-6

    fits = csc(spacing)
    chosen = "optimised" if settings.order == "optimised" else None      # its headland: as the auto pattern's
    if settings.order == "boustrophedon" or (settings.order in ("auto", "optimised") and fits):
        return chosen or "boustrophedon", 1, reach(u_turn(spacing, limits))
    # the narrowest U-turn on a grid of quarter spacings (the turn fits from some width on: bisection)
    widths, u = [spacing], spacing
    while u < 10 * settings.turn_radius + 10 * spacing:
        u += 0.25 * spacing
        widths.append(u)
    lo, hi = 0, len(widths) - 1
    if not fits and csc(widths[hi]):
        while hi - lo > 1:
            mid = (lo + hi) // 2
            lo, hi = (lo, mid) if csc(widths[mid]) else (mid, hi)
    u_min = widths[0] if fits else widths[hi]
    s = max(2, math.ceil(u_min / spacing))
    return chosen or "skip", s, max(reach(u_turn(s * spacing, limits)), reach(u_turn((s + 1) * spacing, limits)))


def skip_order(n: int, s: int) -> list[int]:
    """An order of n parallel swaths in which every move spans at least s lines (a U-turn each),
    in blocks of 2s (the last takes the rest): an even block b..b+2h-1 goes b+h, b, b+h+1, b+1,
    ..., b+2h-1, b+h-1; an odd one b+h-1, b, b+h, b+1, ..., b+h-2, b+2h-2. Moves within a block
    span h and h - 1 lines, between blocks more. Fewer than 2s swaths: some moves are shorter
    (omega turns)."""
    sizes = [2 * s] * max(1, n // (2 * s))
    sizes[-1] += n - sum(sizes)
    out, b = [], 0
    for k in sizes:
        if k % 2 == 0:
            h = k // 2
            for i in range(h):
                out += [b + h + i, b + i]
        else:
            h = (k + 1) // 2
            for i in range(h - 1):
                out += [b + h - 1 + i, b + i]
            out.append(b + 2 * h - 2)
        b += k
    return out


def entered(swath: Swath, pos) -> Swath:
    """The swath entered from its end nearer ``pos`` (as it is when pos is None): after a U-turn
    that is the alternate direction."""
    if pos is None or np.hypot(*(swath.start - pos)) <= np.hypot(*(swath.end - pos)):
        return swath
    return swath.reversed()


def cell_order(cells: list[Cell], skip: int, pos=None) -> tuple[list[Swath], frozenset[int]]:
    """The swaths in driving order (as generated, not yet oriented) and where each cell begins; the
    first cell the one nearest ``pos`` (given), else the first."""
    def sequence(cell: Cell) -> list[Swath]:
        n = len(cell.swaths)
        return [cell.swaths[k] for k in (range(n) if skip == 1 else skip_order(n, skip))]

    left = list(range(len(cells)))
    out: list[Swath] = []
    starts: set[int] = set()
    pos = None if pos is None else np.asarray(pos, float)
    while left:
        options = [(c, seq) for c in left for seq in (sequence(cells[c]), sequence(cells[c])[::-1])]
        if pos is None:
            c, seq = options[0]
        else:
            c, seq = min(options, key=lambda o: min(np.hypot(*(o[1][0].start - pos)), np.hypot(*(o[1][0].end - pos))))
        left.remove(c)
        starts.add(len(out))
        out += seq
        for sw in seq:
            pos = entered(sw, pos).end
    return out, frozenset(starts)


def route(cells: list[Cell], skip: int, order: str, settings: Settings, rings: list[HeadlandPass]) -> Route:
    """The work in driving order: each swath entered from the end nearer where the last one's
    run-out ended, lengthened by ``swath_extension`` at each end; then the headland passes."""
    first_rings = settings.headland_order == "first" and rings
    start = None if first_rings or settings.start_point is None else settings.start_point
    if order == "optimised":
        return _optimised(cells, skip, settings, rings, start)
    chosen, starts = cell_order(cells, skip, start)
    if settings.max_swaths:
        chosen = chosen[:settings.max_swaths]
    passes: list[Swath | HeadlandPass] = []
    run_out = None if start is None else np.asarray(start, float)
    for sw in chosen:
        sw = entered(sw, run_out).extended(settings.swath_extension)
        passes.append(sw)
        run_out = sw.end + settings.lead * sw.direction(at_end=True)
    how = f"{order}" + (f" (skip {skip})" if order == "skip" else "")
    if len(cells) > 1:
        how += f" in {len(cells)} cells (lines that cross holes or bays give several swaths)"
    starts = frozenset(k for k in starts if k < len(chosen))
    if settings.headland_order == "first":
        return Route(tuple(rings) + tuple(passes), frozenset(k + len(rings) for k in starts), how + ", headland first")
    return Route(tuple(passes) + tuple(rings), starts, how)


def _optimised(cells: list[Cell], skip: int, settings: Settings, rings: list[HeadlandPass], start) -> Route:
    """The order of fields.planner.optimise, from the pattern's order (boustrophedon or skip) on."""
    swaths = [sw for c in cells for sw in c.swaths]
    position = {sw.index: k for k, sw in enumerate(swaths)}
    piece = np.array([c.piece for c in cells for _ in c.swaths])
    initial, run_out = [], None if start is None else np.asarray(start, float)
    for sw in cell_order(cells, skip, start)[0]:
        e = entered(sw, run_out)
        initial.append(2 * position[sw.index] + (0 if e is sw else 1))
        run_out = e.end + settings.lead * e.direction(at_end=True)
    chosen, how = optimised(swaths, piece, settings, start, None if rings else settings.end_point, initial)
    if settings.max_swaths:
        chosen = chosen[:settings.max_swaths]
    passes = tuple(sw.extended(settings.swath_extension) for sw in chosen)
    moves = frozenset(range(len(passes)))               # any move may go round by the headland
    if settings.headland_order == "first" and rings:
        return Route(tuple(rings) + passes, frozenset(k + len(rings) for k in moves), how + ", headland first")
    return Route(passes + tuple(rings), moves, how)
