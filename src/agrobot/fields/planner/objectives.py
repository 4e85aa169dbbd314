"""How the driving angle is chosen: objectives over the candidate angles (Fields2Cover's swath
generator objectives). An objective gives each angle a key; the angle with the smallest key is
driven. Add one by putting an ``Objective`` into ``OBJECTIVES`` under its name.

- ``fewest_swaths``: ceil(H(a) / d) swaths, H(a) the region's height across the driving direction,
  d the spacing; hence the fewest turns (Fields2Cover's NSwath). Ties: the longer mean swath.
- ``longest_edge``: along the region's longest boundary edges: the key is minus the length of the
  edges within 1 degree of the angle (farmers drive along the longest side; ties by fewest swaths).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
from shapely import affinity
from shapely.geometry import Polygon

CANDIDATES_DEG = np.arange(0.0, 180.0, 1.0)      # the angles tried, deg


@dataclass(frozen=True)
class Objective:
    name: str
    describe: str                                               # "the fewest swaths (N)", with {detail}
    key: Callable[[Polygon, float, float], tuple]               # (region, angle deg, spacing) -> key, smaller better
    detail: Callable[[tuple], str] = lambda key: ""


def _swath_count(region: Polygon, deg: float, spacing: float) -> tuple[int, float]:
    minx, miny, maxx, maxy = affinity.rotate(region, -deg, origin=(0, 0)).bounds
    count = math.ceil((maxy - miny) / spacing)
    return count, -region.area / max(count, 1)


def _edges(region: Polygon) -> tuple[np.ndarray, np.ndarray]:
    """(direction mod 180 deg, length) of every boundary edge."""
    d = np.diff(np.asarray(region.exterior.coords), axis=0)
    return np.degrees(np.arctan2(d[:, 1], d[:, 0])) % 180.0, np.hypot(d[:, 0], d[:, 1])


def _along_edges(region: Polygon, deg: float, spacing: float) -> tuple[float, int, float]:
    direction, length = _edges(region)
    off = np.abs((direction - deg + 90.0) % 180.0 - 90.0)
    return (-float(length[off <= 1.0].sum()),) + _swath_count(region, deg, spacing)


OBJECTIVES: dict[str, Objective] = {
    "fewest_swaths": Objective("fewest_swaths", "the fewest swaths ({detail}), hence the fewest turns; ties by the "
                               "longer swath", _swath_count, lambda key: f"{key[0]}"),
    "longest_edge": Objective("longest_edge", "along the longest boundary edges ({detail} m within 1 deg)",
                              _along_edges, lambda key: f"{-key[0]:.0f}"),
}


def best_angle(region: Polygon, spacing: float, objective: Objective) -> tuple[float, str]:
    """(angle [rad] in [0, pi), how) minimising the objective over CANDIDATES_DEG."""
    best = None
    for deg in CANDIDATES_DEG:
        key = objective.key(region, float(deg), spacing)
        if best is None or key < best[0]:
            best = (key, float(deg))
    return math.radians(best[1]), "chosen: " + objective.describe.format(detail=objective.detail(best[0]))
