"""Swath generation: the driving angle (given, along a guidance line of the field, or by an
objective: fields.planner.objectives), then straight lines d = w - overlap apart across the region,
each cut into the swaths where its strip touches the region (a line crossing a hole or a bay gives
several)."""
from __future__ import annotations

import math
from typing import Callable

import numpy as np
from shapely import affinity
from shapely.geometry import LineString, MultiLineString, Polygon
from shapely.ops import unary_union

from ..field import Field, FieldError
from .curved_swaths import curved_lines
from .decomposition import straight_along
from .objectives import OBJECTIVES, best_angle
from .settings import Settings
from .types import Swath

SHIFTS = 9          # placements of the lines' slack across the region tried (the least unworked wins)
SHORTEST = 1.0      # m: a shorter piece of a line is not a swath


def generate(field: Field, piece: Polygon, settings: Settings, where: str, first_index: int = 0,
             first_line: int = 0) -> tuple[list[list[Swath]], Callable[[np.ndarray], float], float, str]:
    """The swaths of a piece of the inner field, line by line (lines numbered from ``first_line``,
    swaths from ``first_index``); the coordinate along them (for the cells); the driving angle and
    how it was chosen."""
    if settings.swath_pattern == "curved":
        if not field.lines:
            raise FieldError(f"{where}: swath_pattern = 'curved': the field has no guidance line to lay the swaths "
                             f"along (expected a curve: an AgOpenGPS curve, ISOXML curve guidance or a GeoJSON "
                             f"LineString)")
        line, how = guidance(field, settings.guidance_line or "*", where)
        lines, along = curved_lines(piece, line.points, settings.spacing, settings.working_width,
                                    settings.turn_radius, first_index, first_line)
        return lines, along, line.heading % math.pi, "offsets of " + how.removeprefix("along ")
    angle, how = driving_angle(field, piece, settings, where)
    lines = swath_lines(piece, angle, settings.spacing, settings.working_width, first_index, first_line)
    return lines, straight_along(angle), angle, how


def driving_angle(field: Field, region: Polygon, settings: Settings, where: str) -> tuple[float, str]:
    """(angle [rad] in [0, pi), how it was chosen)."""
    if settings.driving_angle is not None:
        return float(settings.driving_angle) % math.pi, "given"
    if settings.guidance_line:
        return along_line(field, settings.guidance_line, where)
    return best_angle(region, settings.spacing, OBJECTIVES[settings.angle_objective])


def along_line(field: Field, name: str, where: str) -> tuple[float, str]:
    """The driving angle of the field's guidance line (an AB line's heading, a curve's ends)."""
    line, how = guidance(field, name, where)
    return line.heading % math.pi, how


def guidance(field: Field, name: str, where: str):
    """The field's guidance line named ``name`` ("*": its first), and how it was chosen."""
    found = field.lines[:1] if name == "*" else [g for g in field.lines if g.name == name]
    if not found:
        have = ", ".join(repr(g.name) for g in field.lines) or "none"
        raise FieldError(f"{where}: guidance_line = {name!r}: the field has no such guidance line (it has {have})")
    line = found[0]
    return line, f"along the field's {line.kind} {line.name!r}"


def swath_lines(region: Polygon, angle: float, spacing: float, width: float, first_index: int = 0,
                first_line: int = 0) -> list[list[Swath]]:
    """Per line across the region, its swaths along the driving direction. The ceil(H / spacing)
    lines across the region's height H leave some slack; where they sit in it is chosen (SHIFTS
    placements) to leave the least of the region unworked: an edge at a small angle to the swaths
    leaves a wedge beside the outermost swath, and the shift puts the slack on the other side. Each
    swath runs as far as its strip (width w) touches the region, on the line within w/2 of it: the
    strip covers the corners where an edge crosses the swaths at a slant, and a line just outside a
    near-parallel edge still works the wedge beside it. Its ends are thus at most w/2 outside the
    region (the headland counts that in)."""
    deg = math.degrees(angle)
    rot = affinity.rotate(region, -deg, origin=(0, 0))
    minx, miny, maxx, maxy = rot.bounds
    count = math.ceil((maxy - miny) / spacing)
    best = None
    for share in np.linspace(0.0, 1.0, SHIFTS):
        first = miny + share * ((maxy - miny) - (count - 1) * spacing)
        strips = unary_union([LineString([(minx - 1, first + k * spacing), (maxx + 1, first + k * spacing)])
                              .buffer(0.5 * width, cap_style="flat") for k in range(count)])
        missed = rot.difference(strips).area
        if best is None or missed < best[0] - 1e-6 or (abs(missed - best[0]) <= 1e-6 and abs(share - 0.5) < abs(best[2] - 0.5)):
            best = (missed, first, share)
    offset = best[1]
    c, s = math.cos(angle), math.sin(angle)
    w_pad = width + 1.0
    near = rot.buffer(0.5 * width, join_style="mitre", mitre_limit=3.0)
    out: list[list[Swath]] = []
    number = first_index
    for k in range(count):
        yk = offset + k * spacing
        band = rot.intersection(LineString([(minx - 1, yk), (maxx + 1, yk)]).buffer(0.5 * width, cap_style="flat"))
        cut = near.intersection(LineString([(minx - w_pad, yk), (maxx + w_pad, yk)]))
        pieces = [g for g in (cut.geoms if isinstance(cut, MultiLineString) else [cut]) if isinstance(g, LineString)]
        swaths = []
        for g in sorted(pieces, key=lambda g: min(g.coords[0][0], g.coords[-1][0])):
            x0, x1 = sorted((g.coords[0][0], g.coords[-1][0]))
            # the part of the line whose strip touches the region
            part = band.intersection(LineString([(x0, yk), (x1, yk)]).buffer(0.5 * width, cap_style="flat"))
            if part.is_empty:
                continue
            x0, x1 = max(x0, part.bounds[0]), min(x1, part.bounds[2])
            if x1 - x0 < SHORTEST:
                continue
            a = [c * x0 - s * yk, s * x0 + c * yk]
            b = [c * x1 - s * yk, s * x1 + c * yk]
            swaths.append(Swath(number, first_line + len(out), np.array([a, b])))
            number += 1
        if swaths:
            out.append(swaths)
    return out
