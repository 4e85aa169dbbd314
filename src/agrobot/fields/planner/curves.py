"""Turns a tractor can drive: continuous curvature, bounded curvature and bounded sharpness.

A turn is built from *CC turns* (Fraichard and Scheuer's continuous-curvature arcs): curvature
ramps linearly from 0 to +-kappa_max at the sharpness sigma (a clothoid), holds (an arc), and
ramps back to 0, turning the heading by theta; a turn too short for full ramps peaks lower
(kappa_p = sqrt(sigma |theta|)). The sharpness is the steering-rate limit seen along the path:
d kappa / ds = d delta / dt / (L v cos^2 delta) <= delta_rate_max / (L v). Paths are sequences of CC
turns and straights, integrated numerically (heading = int kappa ds, position = int (cos, sin)),
so every point's curvature is known.

``connect(a, b)`` finds the shortest path from pose a to pose b among the CSC families (turn,
straight, turn: LSL, RSR, LSR, RSL) and the CCC families (LRL, RLR: the omega turn between swaths
closer than a U-turn's width), each solved for its free lengths and angles by Newton's method
(scipy) on the integrated end pose. Why not a library: Dubins paths (the ``dubins`` package,
Reeds-Shepp's ``rsplan``) jump in curvature at every arc's ends, which a steering that turns at
tens of degrees per second cannot follow; continuous-curvature Dubins is what Fields2Cover uses
(from the steering_functions library, C++, not packaged for Python here).
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from .sampling import TURN_STEP


@dataclass(frozen=True)
class Limits:
    """kappa_max = 1 / R_min [1/m]; sigma = d kappa / ds [1/m^2]."""

    kappa_max: float
    sigma: float

    @classmethod
    def of(cls, turn_radius: float, wheelbase: float, steer_rate: float, speed: float) -> "Limits":
        """R_min, and the sharpness a steering rate [rad/s] allows at ``speed`` (at the straight
        ahead, where d delta / d kappa = L)."""
        return cls(1.0 / turn_radius, steer_rate / (wheelbase * max(speed, 0.1)))


def cc_profile(theta: float, limits: Limits) -> list[tuple[float, float, float]]:
    """[(length, kappa at start, kappa at end)] of a CC turn of heading change theta (signed)."""
    sign = 1.0 if theta >= 0 else -1.0
    th = abs(theta)
    if th < 1e-12:
        return []
    km, sg = limits.kappa_max, limits.sigma
    if th <= km * km / sg:                       # no room for the full ramps: a clothoid pair
        kp = math.sqrt(sg * th)
        ramp = kp / sg
        return [(ramp, 0.0, sign * kp), (ramp, sign * kp, 0.0)]
    ramp = km / sg
    arc = (th - km * ramp) / km
    return [(ramp, 0.0, sign * km), (arc, sign * km, sign * km), (ramp, sign * km, 0.0)]


def integrate(pieces: list[tuple[float, float, float]], start=(0.0, 0.0, 0.0), step: float = TURN_STEP) -> np.ndarray:
    """(N, 4) x, y, heading, curvature along pieces of linearly varying curvature, every ``step``
    (the last point exactly at the end); exact for straights and arcs, second order for ramps."""
    x, y, th = start
    out = [(x, y, th, pieces[0][1] if pieces else 0.0)]
    for length, k0, k1 in pieces:
        n = max(1, int(math.ceil(length / step)))
        h = length / n
        dk = (k1 - k0) / length if length > 0 else 0.0
        for i in range(n):
            ka, kb = k0 + dk * i * h, k0 + dk * (i + 1) * h
            th_mid = th + 0.5 * h * ka + dk * h * h / 8.0           # the heading half a step on
            x += h * math.cos(th_mid)                               # midpoint rule on cos, sin
            y += h * math.sin(th_mid)
            th = th + 0.5 * h * (ka + kb)                           # exact for linear curvature
            out.append((x, y, th, kb))
    return np.array(out)


_GL_X, _GL_W = np.polynomial.legendre.leggauss(24)


def end_pose(pieces, start=(0.0, 0.0, 0.0)) -> np.ndarray:
    """The end pose of the pieces, by Gauss-Legendre quadrature of (cos, sin) of the heading
    (a quadratic in s on each piece): the solver's fast path, to 1e-12 on turns of a few radians.
    All pieces at once: the heading at each piece's start is the sum of the turns before it."""
    x, y, th = start
    p = np.asarray(pieces, float).reshape(-1, 3)
    p = p[p[:, 0] > 0]
    if not len(p):
        return np.array([x, y, th])
    length, k0, k1 = p[:, :1], p[:, 1:2], p[:, 2:]
    turn = 0.5 * length * (k0 + k1)
    th0 = th + np.cumsum(turn) - turn[:, 0]
    sq = 0.5 * length * (_GL_X + 1.0)
    heading = th0[:, None] + k0 * sq + 0.5 * ((k1 - k0) / length) * sq * sq
    w = 0.5 * length * _GL_W
    return np.array([x + float(np.sum(w * np.cos(heading))), y + float(np.sum(w * np.sin(heading))),
                     th + float(np.sum(turn))])


def _pieces(kind: str, params: np.ndarray, limits: Limits) -> list:
    """The pieces of a family: CSC params (theta1, straight, theta2), CCC (theta1, theta2, theta3)."""
    if kind in ("LSL", "RSR", "LSR", "RSL"):
        s1 = 1.0 if kind[0] == "L" else -1.0
        s2 = 1.0 if kind[2] == "L" else -1.0
        return cc_profile(s1 * abs(params[0]), limits) + ([(abs(params[1]), 0.0, 0.0)] if abs(params[1]) > 1e-9 else []) \
            + cc_profile(s2 * abs(params[2]), limits)
    s = 1.0 if kind == "LRL" else -1.0
    return cc_profile(s * abs(params[0]), limits) + cc_profile(-s * abs(params[1]), limits) + \
        cc_profile(s * abs(params[2]), limits)


def _length(pieces) -> float:
    return float(sum(p[0] for p in pieces))


FAMILIES = ("LSL", "RSR", "LSR", "RSL", "LRL", "RLR")


def turn_families(a, b) -> tuple[str, ...]:
    """The families worth trying for a U-turn-like move (heading reversed): towards the side
    the goal lies on, turn-straight-turn or the omega loop; otherwise all of them."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    if abs(_wrap(b[2] - a[2] - math.pi)) > 0.3:
        return FAMILIES
    side = math.cos(a[2]) * (b[1] - a[1]) - math.sin(a[2]) * (b[0] - a[0])
    return ("LSL", "RLR", "LSR", "RSL") if side > 0 else ("RSR", "LRL", "RSL", "LSR")


def connect(a, b, limits: Limits, families=None) -> np.ndarray | None:
    """The shortest CC path (N, 4) from pose a = (x, y, heading) to pose b, or None."""
    families = tuple(families or turn_families(a, b))
    a, b = np.asarray(a, float), np.asarray(b, float)
    c, s = math.cos(-a[2]), math.sin(-a[2])
    d = b[:2] - a[:2]
    goal = (c * d[0] - s * d[1], s * d[0] + c * d[1], _wrap(b[2] - a[2]))     # b in a's frame
    local = _local_path(tuple(round(g, 9) for g in goal), limits, families)
    if local is None:
        return None
    ca, sa = math.cos(a[2]), math.sin(a[2])
    return np.column_stack([a[0] + ca * local[:, 0] - sa * local[:, 1], a[1] + sa * local[:, 0] + ca * local[:, 1],
                            a[2] + local[:, 2], local[:, 3]])


@functools.lru_cache(maxsize=4096)
def _local_path(goal: tuple[float, float, float], limits: Limits, families: tuple[str, ...]) -> np.ndarray | None:
    """The shortest CC path from the origin heading east to ``goal`` (x, y, heading), integrated;
    cached: the turns between parallel swaths whose ends line up are all one turn, moved. The CSC
    families in closed form (``_csc``), Newton's method where that does not apply (a turn too short
    for full ramps); the CCC families (omega loops) only where they can be shorter."""
    goal = np.array(goal)
    best = None
    R = 1.0 / limits.kappa_max
    r, mu = cc_circle(limits)
    ramp = limits.kappa_max / limits.sigma
    for kind in sorted(families, key=lambda k: k not in CSC):
        if kind in CSC:
            pieces = _csc(kind, goal, limits)
            if pieces is not None:
                if best is None or _length(pieces) < best[0] - 1e-6:
                    best = (_length(pieces), pieces)
                continue
        else:
            # a CCC path turns through more than pi in its middle turn: no shorter than pi R plus three ramps;
            # its outer turns' circles are at most 4 r apart
            if best is not None and best[0] <= math.pi * R + 3 * ramp:
                continue
            s = 1.0 if kind[0] == "L" else -1.0
            if np.hypot(*(_centre(np.zeros(3), s, r, mu, True) - _centre(goal, s, r, mu, False))) > 4 * r + 1e-6:
                continue
        for guess in _guesses(kind, goal, R):
            def residual(p):
                e = end_pose(_pieces(kind, p, limits))
                return [e[0] - goal[0], e[1] - goal[1], R * _wrap(e[2] - goal[2])]
            try:
                sol = least_squares(residual, guess, method="lm", xtol=1e-10, ftol=1e-10, max_nfev=80)
            except (ValueError, FloatingPointError):
                continue
            if np.max(np.abs(sol.fun)) > 1e-3:
                continue
            pieces = _pieces(kind, sol.x, limits)
            length = _length(pieces)
            if best is None or length < best[0] - 1e-6:
                best = (length, pieces)
    if best is None:
        return None
    path = integrate(best[1])
    path.setflags(write=False)
    return path


CSC = ("LSL", "RSR", "LSR", "RSL")


@functools.lru_cache(maxsize=64)
def cc_circle(limits: Limits) -> tuple[float, float]:
    """(r, mu) of a CC turn with full ramps (Fraichard and Scheuer): from its start, the centre of
    its arc is at distance r, mu off the normal towards the turn; the turn ends on the circle of
    radius r about that centre, its heading mu outwards of that circle's tangent. So the straight
    after it is tangent to the circle of radius r cos mu about the centre."""
    km, sg = limits.kappa_max, limits.sigma
    xs, ys, ths = end_pose([(km / sg, 0.0, km)])
    R = 1.0 / km
    ox, oy = xs - R * math.sin(ths), ys + R * math.cos(ths)
    return math.hypot(ox, oy), math.atan2(ox, oy)


def _centre(pose: np.ndarray, side: float, r: float, mu: float, starts: bool) -> np.ndarray:
    """The centre of the CC turn (side +1 left, -1 right) that starts (or ends) at pose."""
    along = r * math.sin(mu) * (1.0 if starts else -1.0)
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return np.array([pose[0] + c * along - s * side * r * math.cos(mu), pose[1] + s * along + c * side * r * math.cos(mu)])


def _csc(kind: str, goal: np.ndarray, limits: Limits) -> list | None:
    """The pieces of the CSC path of this family from the origin (heading 0) to ``goal`` in closed
    form: the straight is a common tangent of the circles of radius rho = r cos mu about the two
    turns' centres (outer for LSL, RSR; inner for LSR, RSL), and runs from r sin mu past the first
    tangent point to r sin mu before the second. None where a turn is too short for full ramps
    (deflection under kappa^2 / sigma) or the turns overlap: Newton's method takes those."""
    r, mu = cc_circle(limits)
    rho = r * math.cos(mu)
    s1, s2 = (1.0 if kind[0] == "L" else -1.0), (1.0 if kind[2] == "L" else -1.0)
    a, b = _centre(np.zeros(3), s1, r, mu, True), _centre(goal, s2, r, mu, False)
    d = b - a
    D, alpha = float(np.hypot(*d)), math.atan2(d[1], d[0])
    if s1 == s2:
        phi, t = alpha, D
    else:
        if D < 2 * rho:
            return None
        phi = alpha + s1 * math.asin(2 * rho / D)
        t = math.sqrt(max(D * D - 4 * rho * rho, 0.0))
    straight = t - 2 * r * math.sin(mu)
    th1 = (s1 * phi) % (2 * math.pi)
    th2 = (s2 * (goal[2] - phi)) % (2 * math.pi)
    least = limits.kappa_max ** 2 / limits.sigma
    if straight < -1e-9 or th1 < least or th2 < least:
        return None
    pieces = cc_profile(s1 * th1, limits) + ([(straight, 0.0, 0.0)] if straight > 1e-9 else []) + \
        cc_profile(s2 * th2, limits)
    e = end_pose(pieces)
    if max(abs(e[0] - goal[0]), abs(e[1] - goal[1]), abs(_wrap(e[2] - goal[2]))) > 1e-6:
        return None
    return pieces


def _guesses(kind: str, goal: np.ndarray, R: float) -> list[np.ndarray]:
    dist = float(np.hypot(goal[0], goal[1]))
    turn = abs(goal[2])
    if kind in ("LSL", "RSR", "LSR", "RSL"):
        return [np.array([t1, max(dist - 2 * R, 0.5), t2]) for t1, t2 in
                ((turn / 2, turn / 2), (math.pi / 2, math.pi / 2), (0.3, turn + 0.3), (turn + 0.3, 0.3))]
    return [np.array([t1, t2, t3]) for t1, t2, t3 in
            ((0.8, math.pi + 1.6 - turn, 0.8), (0.5, math.pi + 1.0, 0.5), (1.2, math.pi + 2.4, 1.2))]


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2 * math.pi) - math.pi
