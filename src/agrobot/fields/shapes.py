"""Shapely geometries (GeoJSON, WKT, KML) as fields: a field per polygon, each in its own local
frame, every field with a name of its own; an invalid polygon (a ring that crosses itself) is
repaired with ``shapely.make_valid`` and named (``properties["repaired"]``)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from shapely import make_valid
from shapely.geometry import LineString, MultiLineString, MultiPolygon, Polygon
from shapely.validation import explain_validity

from .coordinates import Coordinates
from .field import Field, FieldError, GuidanceLine, polygon, polygons


def distinct_names(fields: list[Field]) -> list[Field]:
    """The fields with names told apart: a name that repeats gets _2, _3 ... in file order, so that
    ``plan --name`` picks one field, not the first of several."""
    taken: set[str] = set()
    counts: dict[str, int] = {}
    for f in fields:
        name, k = f.name, counts.get(f.name, 1)
        while name in taken:
            k += 1
            name = f"{f.name}_{k}"
        counts[f.name] = k
        taken.add(name)
        f.name = name
    return fields


SLIVER_SHARE = 0.1      # a part of a repaired polygon smaller than this share of its largest part is a sliver


def repaired_parts(poly, where: str) -> tuple[list[Polygon], str | None]:
    """(polygons, note): ``poly`` as it is when valid (note None), else the polygons of its repair
    by shapely.make_valid (a line or point left by the repair dropped) and what was done."""
    if poly.is_valid:
        return list(getattr(poly, "geoms", [poly])), None
    why = explain_validity(poly)
    fixed = make_valid(poly)
    parts = [g for g in getattr(fixed, "geoms", [fixed]) if isinstance(g, Polygon) and g.area > 0]
    if not parts:
        raise FieldError(f"{where}: the polygon is invalid ({why}) and shapely.make_valid leaves no area of it")
    # a sliver the repair cuts off where a ring touches itself is not a field of its own
    largest = max(g.area for g in parts)
    kept = [g for g in parts if g.area >= SLIVER_SHARE * largest]
    dropped = sum(g.area for g in parts) - sum(g.area for g in kept)
    note = f"the polygon was invalid ({why}); repaired with shapely.make_valid into {len(kept)} polygon(s)"
    if len(kept) < len(parts):
        note += (f"; {len(parts) - len(kept)} sliver(s) under {100 * SLIVER_SHARE:.0f} % of the largest part left out "
                 f"({100 * dropped / (dropped + sum(g.area for g in kept)):.1f} % of the area)")
    return kept, note


def fields_from_shapes(path: Path, shapes: list, crs: str | None, declared: str | None) -> list[Field]:
    """A field per polygon, each in its own local frame (a file may hold fields continents apart);
    a line goes to the field it crosses most."""
    polys = []
    for i, (geom, props) in enumerate(shapes):     # the parcels of one MultiPolygon feature: name_1, name_2 ...
        if isinstance(geom, (Polygon, MultiPolygon)):
            label = props.get("Name") or props.get("name") or props.get("id")
            fixed, note = repaired_parts(geom, f"{path}: " + (f"{label!r}" if label else f"geometry {i}"))
            if note:
                geom, props = (fixed[0] if len(fixed) == 1 else MultiPolygon(fixed)), {**props, "repaired": note}
        parts = polygons(geom)
        base = props.get("Name") or props.get("name") or props.get("id")
        for k, p in enumerate(parts, 1):
            polys.append((p, props if base is None or len(parts) == 1 else {**props, "name": f"{base}_{k}", "Name": None}))
    lines = [(ln, props) for geom, props in shapes
             for ln in ([geom] if isinstance(geom, LineString) else list(geom.geoms) if isinstance(geom, MultiLineString) else [])]
    if not polys:
        raise FieldError(f"{path}: no Polygon or MultiPolygon in it (found {', '.join(sorted({g.geom_type for g, _ in shapes})) or 'nothing'})")
    rings = [np.asarray(p.exterior.coords)[:, :2] for p, _ in polys]
    coords = Coordinates(str(path), declared, crs, rings)
    fields, frames = [], []
    for i, (p, props) in enumerate(polys):
        origin, to_local = coords.frame([rings[i]])
        name = str(props.get("Name") or props.get("name") or props.get("id") or f"{path.stem}_{i + 1}")
        boundary = polygon(to_local(np.asarray(p.exterior.coords)), [to_local(np.asarray(h.coords)) for h in p.interiors])
        fields.append(Field(name, boundary, origin, str(path), coords.text, properties=_plain(props)))
        frames.append((p, to_local))
    distinct_names(fields)
    for j, (ln, props) in enumerate(lines):
        k = max(range(len(polys)), key=lambda i: polys[i][0].intersection(ln).length) if len(polys) > 1 else 0
        fields[k].lines.append(GuidanceLine(str(props.get("Name") or props.get("name") or props.get("path_id")
                                                or f"line {j + 1}"), frames[k][1](np.asarray(ln.coords))))
    return fields


def _plain(props: dict) -> dict:
    return {k: v for k, v in props.items() if isinstance(v, (int, float, str, bool)) and k not in ("Name", "name")}
