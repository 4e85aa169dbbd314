"""A field from a GNSS track a machine drove (a harvester's, a tractor's): the worked area's
outline and its passes, so that the planner can replan the field.

- Passes: the track, cut at gaps and jumps, simplified (Douglas-Peucker, shapely, tolerance
  ``STRAIGHT_TOLERANCE``): an edge of the simplified track at least ``min_pass`` long is a
  straight stretch of one heading, a pass; its ends are the AB line's A and B.
- Working width: given (or the recording's own, ISO 11783 DDI 67 'actual working width'), else
  the spacing of the passes of the dominant direction: for each, the distance to the nearest
  parallel pass beside it (their stretches overlapping by half the shorter), the median of those.
- Worked area: the track buffered by half the working width (the ground the implement covered),
  its largest part, holes smaller than one pass-width square metre per metre of pass filled
  (GNSS noise between neighbouring passes), simplified to 0.25 m.
"""
from __future__ import annotations

import math

import numpy as np
from shapely.geometry import LineString, Polygon
from shapely.ops import unary_union

from .field import Field, FieldError, GuidanceLine, local_frame, polygon, polygons

STRAIGHT_TOLERANCE = 1.0     # m: deviation a pass may have from its straight line (GNSS noise, steering)
JUMP = 50.0                  # m: a step longer than this between fixes is a jump, not driving
PARALLEL = math.radians(12)  # passes within this of the dominant direction count for the width


def pieces(xy: np.ndarray, t: np.ndarray) -> list[np.ndarray]:
    """The track cut where the fixes jump or pause for long (> 5 typical periods and 5 s)."""
    step = np.hypot(*np.diff(xy, axis=0).T)
    dt = np.diff(t)
    pause = max(5.0 * float(np.median(dt)), 5.0) if len(dt) else math.inf
    cut = np.flatnonzero((step > JUMP) | (dt > pause)) + 1
    return [p for p in np.split(xy, cut) if len(p) >= 2]


def passes(parts: list[np.ndarray], min_pass: float) -> list[np.ndarray]:
    """[(A, B)] of the straight stretches at least ``min_pass`` long."""
    out = []
    for p in parts:
        keep = np.concatenate([[True], np.hypot(*np.diff(p, axis=0).T) > 0.05])
        p = p[keep]
        if len(p) < 2:
            continue
        simple = np.asarray(LineString(p).simplify(STRAIGHT_TOLERANCE, preserve_topology=False).coords)
        for a, b in zip(simple[:-1], simple[1:]):
            if math.hypot(*(b - a)) >= min_pass:
                out.append(np.array([a, b]))
    return out


def working_width(ab: list[np.ndarray]) -> tuple[float, str]:
    """(width [m], how) from the spacing of the passes of the dominant direction."""
    if len(ab) < 3:
        raise FieldError(f"{len(ab)} straight pass(es) in the track: too few to tell the working width from their "
                         f"spacing; give it with --width")
    d = np.array([b - a for a, b in ab])
    length = np.hypot(d[:, 0], d[:, 1])
    angle = np.arctan2(d[:, 1], d[:, 0])
    main = 0.5 * math.atan2(float(np.sum(length * np.sin(2 * angle))), float(np.sum(length * np.cos(2 * angle))))
    off = np.angle(np.exp(2j * (angle - main))) / 2
    normal, along = np.array([-math.sin(main), math.cos(main)]), np.array([math.cos(main), math.sin(main)])
    par = [p for p, o in zip(ab, off) if abs(o) < PARALLEL]
    offsets = np.array([float((p[0] + p[1]) @ normal) / 2 for p in par])
    spans = [np.sort(p @ along) for p in par]
    nearest = []
    for i, (oi, (a0, a1)) in enumerate(zip(offsets, spans)):
        best = math.inf
        for j, (oj, (b0, b1)) in enumerate(zip(offsets, spans)):
            shared = min(a1, b1) - max(a0, b0)
            if j != i and shared > 0.5 * min(a1 - a0, b1 - b0) and 0.5 < abs(oj - oi) < best:
                best = abs(oj - oi)
        if math.isfinite(best):
            nearest.append(best)
    if len(nearest) < 2:
        raise FieldError(f"{len(par)} parallel pass(es) in the track, {len(nearest)} beside another: too few to tell "
                         f"the working width from their spacing; give it with --width")
    width = float(np.median(nearest))
    return width, (f"the median distance of {len(nearest)} passes to their nearest parallel neighbour (heading "
                   f"{math.degrees(main):.1f} deg, east = 0, counter-clockwise)")


def field_from_track(t: np.ndarray, lat: np.ndarray, lon: np.ndarray, name: str, source: str,
                     width: float | None = None, min_pass: float | None = None) -> Field:
    """The worked field of a track of fixes (times [s], latitude and longitude [deg])."""
    ok = np.isfinite(lat) & np.isfinite(lon) & np.isfinite(t)
    if ok.sum() < 10:
        raise FieldError(f"{source}: {int(ok.sum())} fixes in the track; a field needs a track of many")
    lonlat = np.column_stack([lon[ok], lat[ok]])
    origin, to_local = local_frame([lonlat])
    xy, times = to_local(lonlat), np.asarray(t, float)[ok]
    parts = pieces(xy, times)
    extent = float(np.max(np.ptp(xy, axis=0)))
    if extent < 10.0:
        raise FieldError(f"{source}: the track spans {extent:.1f} m: it does not cover a field")
    if width is not None and not 0.3 <= width <= 60.0:
        raise FieldError(f"--width {width:g}: expected a working width in metres, 0.3 to 60")
    min_pass = min_pass or max(20.0, 3.0 * (width or 3.0))
    ab = passes(parts, min_pass)
    how = "given (--width)"
    if width is None:
        width, how = working_width(ab)
    covered = unary_union([LineString(p).buffer(width / 2, cap_style="flat", join_style="round") for p in parts])
    biggest = max(polygons(covered), key=lambda g: g.area)
    holes = [h for h in biggest.interiors if Polygon(h).area > width * width * 4]
    area = Polygon(biggest.exterior, holes).simplify(0.25, preserve_topology=True)
    if area.is_empty or area.area <= 0:
        raise FieldError(f"{source}: the track covers no area")
    shape = polygons(area)[0] if not isinstance(area, Polygon) else area
    lines = [GuidanceLine(f"pass {k + 1}", p) for k, p in enumerate(ab)]
    return Field(name, polygon(np.asarray(shape.exterior.coords), [np.asarray(h.coords) for h in shape.interiors]),
                 origin, source, "the track's longitude/latitude (WGS 84)", lines=lines,
                 properties={"working_width_m": round(width, 3), "working_width_from": how, "passes": len(ab),
                             "track_fixes": int(ok.sum()), "track_pieces": len(parts),
                             "track_length_m": round(float(sum(LineString(p).length for p in parts)), 1)})



