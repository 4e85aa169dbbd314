"""GeoJSON (RFC 7946: longitude, latitude; a legacy ``crs`` member is honoured) and WKT field
files: Polygon and MultiPolygon features are fields (holes kept), LineString features guidance
lines. A GeoJSON geometry is checked against RFC 7946 before shapely reads it, so that what is
wrong is named by feature and position."""
from __future__ import annotations

import json
import math
import re
from pathlib import Path

from shapely import wkt as shapely_wkt
from shapely.geometry import shape

from agrobot.orchestrator.source_files import regular_file

from .field import Field, FieldError
from .shapes import fields_from_shapes


def read_geojson(path: Path, crs: str | None = None) -> list[Field]:
    try:
        data = json.loads(regular_file(path, FieldError).read_text(encoding="utf-8-sig"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise FieldError(f"{path}: not a readable JSON file: {exc}") from None
    except RecursionError:
        raise FieldError(f"{path}: JSON nested deeper than a GeoJSON ever is (Python's parser gives up); "
                         f"expected a FeatureCollection of Features with Polygon geometries") from None
    if not isinstance(data, dict) or "type" not in data:
        raise FieldError(f"{path}: not GeoJSON: expected an object with a 'type' (FeatureCollection, Feature or a geometry)")
    feats = data.get("features") if data["type"] == "FeatureCollection" else \
        [data] if data["type"] == "Feature" else [{"type": "Feature", "geometry": data, "properties": {}}]
    if not isinstance(feats, list):
        raise FieldError(f"{path}: 'features' must be a list")
    shapes = []
    for i, f in enumerate(feats):
        if not isinstance(f, dict) or not isinstance(f.get("geometry"), dict):
            raise FieldError(f"{path}: feature {i}: not a geometry: none given (expected a Feature with a 'geometry' object: "
                             f"{{'type': 'Polygon', 'coordinates': [[[lon, lat], ...]]}})")
        _check_geometry(path, i, f["geometry"])
        props = f.get("properties")
        try:
            shapes.append((shape(f["geometry"]), props if isinstance(props, dict) else {}))
        except Exception as exc:        # noqa: BLE001 - shapely raises many kinds for a bad geometry
            raise FieldError(f"{path}: feature {i}: not a geometry: {exc}") from None
    declared = ((data.get("crs") or {}).get("properties") or {}).get("name")
    return fields_from_shapes(path, shapes, crs, declared)


DEPTH = {"Point": 0, "MultiPoint": 1, "LineString": 1, "MultiLineString": 2, "Polygon": 2, "MultiPolygon": 3}
LEAST = {"LineString": 2, "MultiLineString": 2, "Polygon": 4, "MultiPolygon": 4}     # positions a line / ring needs


def _check_geometry(path: Path, i: int, geom: dict, depth: int = 0) -> None:
    """A GeoJSON geometry as RFC 7946 writes it (a type, coordinates nested to its depth, each
    position two or three finite numbers), else a FieldError naming the feature and what is wrong."""
    kind = geom.get("type")
    if kind == "GeometryCollection" and depth < 4 and isinstance(geom.get("geometries"), list):
        for g in geom["geometries"]:
            _check_geometry(path, i, g if isinstance(g, dict) else {}, depth + 1)
        return
    if kind not in DEPTH:
        raise FieldError(f"{path}: feature {i}: not a geometry: type {str(kind)[:40]!r}; expected one of "
                         f"{', '.join(DEPTH)} or GeometryCollection")

    def walk(value, level: int, where: str) -> None:
        if level == 0:
            if not (isinstance(value, list) and len(value) in (2, 3)
                    and all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in value)):
                raise FieldError(f"{path}: feature {i}: not a geometry: {kind} position {where}: {str(value)[:40]}; expected "
                                 f"[longitude, latitude] (or x, y) of two or three finite numbers")
            return
        if not isinstance(value, list):
            raise FieldError(f"{path}: feature {i}: not a geometry: {kind} coordinates{' ' + where if where else ''}: {str(value)[:40]}; expected "
                             f"lists nested {DEPTH[kind] + 1} deep around the positions")
        if level == 1 and kind in LEAST and len(value) < LEAST[kind]:
            raise FieldError(f"{path}: feature {i}: not a geometry: {kind} {'ring' if 'Polygon' in kind else 'line'} {where or '0'}: "
                             f"{len(value)} position(s); it needs {LEAST[kind]} or more")
        for k, v in enumerate(value):
            walk(v, level - 1, f"{where}[{k}]")
    walk(geom.get("coordinates"), DEPTH[kind], "")


def read_wkt(path: Path, crs: str | None = None) -> list[Field]:
    text = regular_file(path, FieldError).read_text(encoding="utf-8-sig", errors="replace").strip()
    shapes = []
    for i, chunk in enumerate(c for c in re.split(r"\n\s*\n|;\s*\n?", text) if c.strip()):
        try:
            shapes.append((shapely_wkt.loads(chunk), {}))
        except Exception as exc:        # noqa: BLE001
            raise FieldError(f"{path}: geometry {i}: not WKT: {exc}") from None
    return fields_from_shapes(path, shapes, crs, None)
