"""The 8-shaped reference: two straights crossing at the origin, tangent to two circles.

Circles of radius r centred at (+-c, 0); the straights through the origin make the angle
theta = asin(r/c) with the x-axis and have length d = sqrt(c^2 - r^2) from the origin to the
tangent point. One lap (starting at the origin, heading theta):
  straight (2d) -> clockwise arc round the right circle (pi + 2 theta) -> straight (2d)
  -> counter-clockwise arc round the left circle (pi + 2 theta) -> back at the origin.
Time based: arc length s(t) = v t^2 / (2 T) for t < T (a start ramp), v (t - T/2) after.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

STRAIGHT, CURVED = 0, 1


@dataclass(frozen=True)
class Figure8Path:
    radius: float
    centre_offset: float

    def __post_init__(self) -> None:
        if not (0 < self.radius < self.centre_offset):
            raise ValueError("need 0 < radius < centre_offset")

    @functools.cached_property      # the path is frozen: worked out once, not at each pose
    def theta(self) -> float:
        return math.asin(self.radius / self.centre_offset)

    @functools.cached_property      # the path is frozen: worked out once, not at each pose
    def straight_length(self) -> float:
        return 2.0 * math.sqrt(self.centre_offset**2 - self.radius**2)

    @functools.cached_property      # the path is frozen: worked out once, not at each pose
    def arc_angle(self) -> float:
        return math.pi + 2.0 * self.theta

    @functools.cached_property      # the path is frozen: worked out once, not at each pose
    def lap_length(self) -> float:
        return 2.0 * self.straight_length + 2.0 * self.radius * self.arc_angle

    def pose(self, s: float) -> tuple[float, float, float, float, int]:
        """(x, y, heading, curvature, segment label) at arc length s (wraps every lap)."""
        s = s % self.lap_length
        th, d, r, c = self.theta, self.straight_length, self.radius, self.centre_offset
        arc = r * self.arc_angle
        half = d / 2.0
        if s < half:                                  # origin -> right tangent point
            return s * math.cos(th), s * math.sin(th), th, 0.0, STRAIGHT
        s -= half
        if s < arc:                                   # clockwise round (c, 0)
            phi0 = th + math.pi / 2.0                 # angle of the tangent point seen from the centre
            phi = phi0 - s / r
            return c + r * math.cos(phi), r * math.sin(phi), th - s / r, -1.0 / r, CURVED
        s -= arc
        if s < d:                                     # lower right -> upper left through the origin
            h = math.pi - th
            x0, y0 = half * math.cos(-th), half * math.sin(-th)
            return x0 + s * math.cos(h), y0 + s * math.sin(h), h, 0.0, STRAIGHT
        s -= d
        if s < arc:                                   # counter-clockwise round (-c, 0)
            phi0 = -th - math.pi / 2.0 + math.pi      # tangent point (upper left) seen from (-c, 0)
            phi = phi0 + s / r
            return -c + r * math.cos(phi), r * math.sin(phi), math.pi - th + s / r, 1.0 / r, CURVED
        s -= arc                                      # lower left -> origin
        x0, y0 = -half * math.cos(th), -half * math.sin(th)
        return x0 + s * math.cos(th), y0 + s * math.sin(th), th, 0.0, STRAIGHT
