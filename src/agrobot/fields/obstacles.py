"""Obstacles in a field: poles, trees, ponds, wells, given as polygons or as points with a radius.

The planner works round them as round the holes of the field's boundary: each becomes a hole (or
a bay, where it reaches the boundary) of the boundary, grown by a clearance, so that the headland
passes go round it, swaths stop short of it, turns and transits keep the tractor's half width off
it, and section control switches off over it.

A file of obstacles is GeoJSON: Point features with a ``radius`` property [m] (or ``radius_m``) and
Polygon features, in longitude/latitude when the field has a geographic reference, else in the
field's local metres (east, north); a feature's ``name`` property names it in messages.

Imported where used: pymap3d (the hardware extra).
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from shapely.geometry import Point, Polygon, shape
from shapely.ops import unary_union

from .field import Field, FieldError, polygons

CLEARANCE = 0.5         # m kept between an obstacle and the implement or the tractor's side


@dataclass(frozen=True)
class Obstacle:
    name: str
    shape: Polygon          # local metres of the field


def circle(name: str, x: float, y: float, radius: float, where: str) -> Obstacle:
    """A point obstacle (a pole, a tree) of ``radius`` metres about (x, y)."""
    for what, v in (("east", x), ("north", y), ("radius", radius)):
        if not math.isfinite(v):
            raise FieldError(f"{where}: obstacle {name!r}: {what} = {v}: expected a finite number")
    if not radius > 0:
        raise FieldError(f"{where}: obstacle {name!r}: radius = {radius:g} m: expected a positive radius")
    return Obstacle(name, Point(x, y).buffer(radius, quad_segs=8))


def parse_point(text: str, where: str, k: int = 0) -> Obstacle:
    """``E,N,R`` (metres east and north of the field's origin, radius) as given on the command line."""
    try:
        x, y, r = (float(v) for v in text.split(","))
    except ValueError:
        raise FieldError(f"{where}: --obstacle {text!r}: expected east,north,radius in metres (e.g. 12.5,-30,1.5)") \
            from None
    return circle(f"obstacle {k + 1} ({text})", x, y, r, where)


def read_obstacles(path: Path, field: Field) -> list[Obstacle]:
    """The obstacles of a GeoJSON file in the field's frame."""
    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8-sig"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise FieldError(f"{path}: cannot read obstacles: {exc}") from None
    features = doc.get("features", [doc] if doc.get("type") == "Feature" else None) if isinstance(doc, dict) else None
    if not isinstance(features, list):
        raise FieldError(f"{path}: expected a GeoJSON FeatureCollection of obstacles (Points with a radius, Polygons)")
    to_local = _to_local(field)
    out = []
    for k, feature in enumerate(features):
        props = (feature or {}).get("properties") or {}
        name = str(props.get("name", f"feature {k + 1}"))
        try:
            geom = shape(feature["geometry"])
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise FieldError(f"{path}: obstacle {name!r}: not a GeoJSON geometry: {exc}") from None
        if geom.geom_type == "Point":
            radius = props.get("radius", props.get("radius_m"))
            try:
                radius = float(radius)
            except (TypeError, ValueError):
                raise FieldError(f"{path}: obstacle {name!r}: a point needs a radius [m] property "
                                 f"('radius'), got {radius!r}") from None
            x, y = to_local(np.array([[geom.x, geom.y]]))[0]
            out.append(circle(name, float(x), float(y), radius, str(path)))
        elif geom.geom_type in ("Polygon", "MultiPolygon"):
            for poly in polygons(geom):
                ring = to_local(np.asarray(poly.exterior.coords)[:, :2])
                local = Polygon(ring, [to_local(np.asarray(h.coords)[:, :2]) for h in poly.interiors])
                if not local.is_valid or local.area <= 0:
                    raise FieldError(f"{path}: obstacle {name!r}: not a simple polygon of some area")
                out.append(Obstacle(name, local))
        else:
            raise FieldError(f"{path}: obstacle {name!r}: a {geom.geom_type}; expected a Point with a radius or a "
                             f"Polygon")
    return out


def _to_local(field: Field):
    if field.origin is None:
        return lambda xy: np.asarray(xy, float)
    import pymap3d

    def convert(lonlat: np.ndarray) -> np.ndarray:
        e, n, _ = pymap3d.geodetic2enu(lonlat[:, 1], lonlat[:, 0], 0.0, field.origin[0], field.origin[1], 0.0, deg=True)
        return np.column_stack([e, n])
    return convert


def with_obstacles(field: Field, obstacles: list[Obstacle], clearance: float = CLEARANCE) -> Field:
    """The field with each obstacle, grown by ``clearance``, cut out of its boundary. Refused (named):
    an obstacle outside the field, or one that cuts the field into pieces."""
    if not obstacles:
        return field
    where = f"{field.source}: field {field.name!r}"
    if not (math.isfinite(clearance) and clearance >= 0):
        raise FieldError(f"{where}: obstacle clearance = {clearance}: expected zero or more metres")
    outer = Polygon(field.boundary.exterior)
    for ob in obstacles:
        if not ob.shape.intersects(field.boundary) or ob.shape.intersection(outer).area <= 1e-9:
            c = ob.shape.centroid
            raise FieldError(f"{where}: obstacle {ob.name!r} at ({c.x:.1f}, {c.y:.1f}) m (east, north of the field's "
                             f"origin) lies outside the field; expected obstacles inside its boundary")
    cut = field.boundary.difference(unary_union([ob.shape.buffer(clearance, quad_segs=8) for ob in obstacles]))
    pieces = [p for p in polygons(cut) if p.area > 1e-6]
    if len(pieces) != 1:
        big = sorted(pieces, key=lambda p: -p.area)
        raise FieldError(f"{where}: the obstacles cut the field into {len(pieces)} pieces ("
                         + ", ".join(f"{p.area / 1e4:.2f} ha" for p in big[:4]) + "); plan each piece as a field of "
                         "its own")
    return replace(field, boundary=pieces[0], properties={**field.properties,
                                                          "obstacles": [ob.name for ob in obstacles],
                                                          "obstacle_clearance_m": clearance})
