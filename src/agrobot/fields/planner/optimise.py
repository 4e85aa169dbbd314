"""The route order that drives least without working: the swaths as a generalised travelling
salesman problem, solved with OR-tools' routing solver (Fields2Cover's route planner does the same).

Each swath is two nodes, one per direction it may be driven in; a disjunction makes the route visit
exactly one of them. The cost of a move from node u to node v is the length of the turn from u's
run-out (its end, the implement's length and ``settle`` on, heading out) to v's run-in, estimated
for every pair at once in closed form:

- CSC (turn, straight, turn) continuous-curvature paths: the straight is a common tangent of the
  circles of radius r cos mu about the turns' centres (fields.planner.curves.cc_circle); a CC turn
  of deflection theta is theta / kappa_max + kappa_max / sigma long (its two clothoids add one ramp
  to the arc), a shorter one 2 sqrt(theta / sigma) (a clothoid pair);
- CCC (the omega loop between swaths closer than a U-turn's width): Dubins' LRL and RLR on circles
  of radius r, plus the ramps;
- a move between the two ends of one piece of the field (it cannot cross the worked field) costs
  the way round the end of the swaths as well: half their lengths.

The solver starts from the cheapest arc from the start and improves the route by guided local
search for at most ``route_seconds``; the order it returns is then joined by the real turns
(fields.planner.turns), and a move whose turn would leave the field goes along the headland.

Imported where used: ortools (the fields extra).
"""
from __future__ import annotations

import math
import time

import numpy as np

from .curves import Limits, cc_circle
from .settings import Settings
from .types import Swath

SCALE = 100             # costs in centimetres (the solver takes integers)
IMPROVING_WORK = 1.3e11   # greedy local search: improving moves x n^4 (a move costs ~n^4 with OR-tools'
MOST_IMPROVEMENTS = 500   # neighbourhoods): 500 moves for 128 swaths, about 2 s of CPU
FEWEST_IMPROVEMENTS = 5   # below this the search is not worth its minutes: the pattern order is kept
BACKSTOP = 120.0         # s: a clock limit only against pathological sizes (then said in the result)
UNREACHABLE = 10.0      # turn radii added to the straight distance where no estimate applies


def poses(swaths: list[Swath], lead: float) -> tuple[np.ndarray, np.ndarray]:
    """(entry, exit) poses (2n, 3) of the 2n nodes: node 2i drives swath i as given, 2i + 1 reversed;
    entry its run-in's start, exit its run-out's end."""
    entry, exit_ = np.zeros((2 * len(swaths), 3)), np.zeros((2 * len(swaths), 3))
    for i, sw in enumerate(swaths):
        for o, s in enumerate((sw, sw.reversed())):
            d_in, d_out = s.direction(), s.direction(at_end=True)
            entry[2 * i + o] = (*(s.start - lead * d_in), math.atan2(d_in[1], d_in[0]))
            exit_[2 * i + o] = (*(s.end + lead * d_out), math.atan2(d_out[1], d_out[0]))
    return entry, exit_


def turn_length(theta: np.ndarray, limits: Limits) -> np.ndarray:
    """Length of a CC turn of deflection theta >= 0."""
    km, sg = limits.kappa_max, limits.sigma
    return np.where(theta >= km * km / sg, theta / km + km / sg, 2.0 * np.sqrt(np.maximum(theta, 0.0) / sg))


def move_costs(a: np.ndarray, b: np.ndarray, limits: Limits) -> np.ndarray:
    """(len(a), len(b)) estimated length [m] of the shortest CC path from each pose of a to each of b."""
    r, mu = cc_circle(limits)
    rho = r * math.cos(mu)
    two_pi = 2.0 * math.pi
    ha, hb = a[:, 2][:, None], b[:, 2][None, :]
    best = np.full((len(a), len(b)), np.inf)
    for s1 in (1.0, -1.0):
        ax = a[:, 0] + r * math.sin(mu) * np.cos(a[:, 2]) - s1 * r * math.cos(mu) * np.sin(a[:, 2])
        ay = a[:, 1] + r * math.sin(mu) * np.sin(a[:, 2]) + s1 * r * math.cos(mu) * np.cos(a[:, 2])
        for s2 in (1.0, -1.0):
            bx = b[:, 0] - r * math.sin(mu) * np.cos(b[:, 2]) - s2 * r * math.cos(mu) * np.sin(b[:, 2])
            by = b[:, 1] - r * math.sin(mu) * np.sin(b[:, 2]) + s2 * r * math.cos(mu) * np.cos(b[:, 2])
            dx, dy = bx[None, :] - ax[:, None], by[None, :] - ay[:, None]
            D, alpha = np.hypot(dx, dy), np.arctan2(dy, dx)
            if s1 == s2:
                phi, t, ok = alpha, D, np.ones_like(D, bool)
            else:
                ok = D >= 2 * rho
                ratio = np.clip(2 * rho / np.maximum(D, 1e-9), -1.0, 1.0)
                phi, t = alpha + s1 * np.arcsin(ratio), np.sqrt(np.maximum(D * D - 4 * rho * rho, 0.0))
            straight = t - 2 * r * math.sin(mu)
            th1, th2 = (s1 * (phi - ha)) % two_pi, (s2 * (hb - phi)) % two_pi
            length = turn_length(th1, limits) + turn_length(th2, limits) + straight
            best = np.minimum(best, np.where(ok & (straight >= 0), length, np.inf))
    for s in (1.0, -1.0):                       # LRL (s = 1), RLR: Dubins on circles of radius r
        cx = a[:, 0] - s * r * np.sin(a[:, 2])
        cy = a[:, 1] + s * r * np.cos(a[:, 2])
        gx = b[:, 0] - s * r * np.sin(b[:, 2])
        gy = b[:, 1] + s * r * np.cos(b[:, 2])
        dx, dy = gx[None, :] - cx[:, None], gy[None, :] - cy[:, None]
        D = np.hypot(dx, dy)
        ok = D <= 4 * r
        beta = np.arccos(np.clip(D / (4 * r), -1.0, 1.0))
        alpha = np.arctan2(dy, dx)
        for sign in (1.0, -1.0):
            mx = cx[:, None] + 2 * r * np.cos(alpha + sign * beta)
            my = cy[:, None] + 2 * r * np.sin(alpha + sign * beta)
            t1 = np.arctan2(my - cy[:, None], mx - cx[:, None]) + s * 0.5 * math.pi    # heading at the first tangent
            t2 = np.arctan2(gy[None, :] - my, gx[None, :] - mx) - s * 0.5 * math.pi    # at the second
            th1 = (s * (t1 - ha)) % two_pi
            th2 = (-s * (t2 - t1)) % two_pi
            th3 = (s * (hb - t2)) % two_pi
            length = (th1 + th2 + th3) / limits.kappa_max + 3 * limits.kappa_max / limits.sigma
            best = np.minimum(best, np.where(ok, length, np.inf))
    far = np.hypot(b[None, :, 0] - a[:, None, 0], b[None, :, 1] - a[:, None, 1]) + UNREACHABLE / limits.kappa_max
    return np.where(np.isfinite(best), best, far)


def improvements(n: int) -> int:
    """Improving moves the greedy local search makes at most for n swaths: a count, not a clock,
    so that a plan is the same on every machine."""
    return int(min(MOST_IMPROVEMENTS, IMPROVING_WORK / max(n, 1) ** 4))


def order(swaths: list[Swath], groups: np.ndarray, settings: Settings, start=None, end=None,
          initial: list[int] | None = None) -> tuple[list[Swath], str]:
    """The swaths oriented and in the order the solver finds; ``groups``: each swath's piece of
    the field (moves between a piece's two ends pay the way round); ``initial``: a first route, the
    nodes in order (2i: swath i as given, 2i + 1: reversed), improved by local search (never worse)."""
    from ortools.constraint_solver import pywrapcp, routing_enums_pb2

    n = len(swaths)
    if n == 0:
        return [], "optimised"
    entry, exit_ = poses(swaths, settings.lead)
    cost = move_costs(exit_, entry, settings.limits)
    # the two ends of a piece: a swath's generated direction is the piece's; its run-out after driving
    # it as given is on the piece's far end
    group = np.repeat(groups, 2)
    exit_far = np.tile([True, False], n)                 # node 2i leaves at the far end, 2i + 1 at the near
    entry_far = ~exit_far                                # node 2i enters at the near end
    lengths = np.repeat([sw.length for sw in swaths], 2)
    across = (group[:, None] == group[None, :]) & (exit_far[:, None] != entry_far[None, :])
    cost = cost + np.where(across, 0.5 * (lengths[:, None] + lengths[None, :]), 0.0)
    size = 2 * n + 2
    matrix = np.zeros((size, size), np.int64)
    matrix[:2 * n, :2 * n] = np.round(cost * SCALE)
    if start is not None:
        matrix[2 * n, :2 * n] = np.round(np.hypot(entry[:, 0] - start[0], entry[:, 1] - start[1]) * SCALE)
    if end is not None:
        matrix[:2 * n, 2 * n + 1] = np.round(np.hypot(exit_[:, 0] - end[0], exit_[:, 1] - end[1]) * SCALE)
    for i in range(n):                                   # never straight from one direction of a swath to the other
        matrix[2 * i, 2 * i + 1] = matrix[2 * i + 1, 2 * i] = int(1e12)
    manager = pywrapcp.RoutingIndexManager(size, 1, [2 * n], [2 * n + 1])
    routing = pywrapcp.RoutingModel(manager)
    callback = routing.RegisterTransitMatrix(matrix.tolist())
    routing.SetArcCostEvaluatorOfAllVehicles(callback)
    penalty = int(matrix.max()) * 4 + 1
    for i in range(n):
        routing.AddDisjunction([manager.NodeToIndex(2 * i), manager.NodeToIndex(2 * i + 1)], penalty, 1)
    params = pywrapcp.DefaultRoutingSearchParameters()
    params.first_solution_strategy = routing_enums_pb2.FirstSolutionStrategy.PATH_CHEAPEST_ARC
    if settings.route_seconds > 0:
        params.local_search_metaheuristic = routing_enums_pb2.LocalSearchMetaheuristic.GUIDED_LOCAL_SEARCH
        params.time_limit.FromMilliseconds(int(1000 * settings.route_seconds))
    else:
        # greedy descent, bounded: its full neighbourhoods take minutes from some hundred swaths on
        params.local_search_metaheuristic = routing_enums_pb2.LocalSearchMetaheuristic.GREEDY_DESCENT
        # bounded by a count of improving moves, not by the clock: the same plan on any machine
        params.solution_limit = improvements(n)
        params.time_limit.FromMilliseconds(int(1000 * BACKSTOP))
    began = time.monotonic()

    def as_given(nodes: list[int]) -> list[Swath]:
        return [swaths[v // 2] if v % 2 == 0 else swaths[v // 2].reversed() for v in nodes]

    if settings.route_seconds <= 0 and improvements(n) < FEWEST_IMPROVEMENTS and initial is not None:
        return as_given(initial), (f"the pattern's order ({n} swaths: beyond what the bounded local search improves "
                                   f"in seconds)")
    if initial is not None:
        routing.CloseModelWithParameters(params)
        first = routing.ReadAssignmentFromRoutes([[int(manager.NodeToIndex(v)) for v in initial]], True)
        solution = routing.SolveFromAssignmentWithParameters(first, params)
    else:
        solution = routing.SolveWithParameters(params)
    if solution is None:
        return (as_given(initial), "the pattern's order (the solver found none better)") if initial else \
            ([], "optimised (no solution)")
    out, index = [], routing.Start(0)
    while not routing.IsEnd(index):
        node = manager.IndexToNode(index)
        if node < 2 * n:
            out.append(swaths[node // 2] if node % 2 == 0 else swaths[node // 2].reversed())
        index = solution.Value(routing.NextVar(index))
    search = (f"{settings.route_seconds:g} s of guided local search" if settings.route_seconds > 0 else
              f"greedy local search, at most {improvements(n)} improving moves")
    if settings.route_seconds <= 0 and time.monotonic() - began >= 0.95 * BACKSTOP:
        search += f"; stopped by the {BACKSTOP:g} s backstop, so it may differ between machines"
    return out, f"optimised (OR-tools routing from the {'skip' if initial else 'cheapest-arc'} order, {search})"
