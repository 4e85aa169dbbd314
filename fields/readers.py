"""Fields from the files farmers and planners write (issue 26, item 3), all to one Field type:

- GeoJSON (RFC 7946: longitude, latitude; a legacy ``crs`` member is honoured): Polygon and
  MultiPolygon features are fields (holes kept), LineString features guidance lines;
- WKT (a ``.wkt`` file): POLYGON, MULTIPOLYGON, LINESTRING;
- GML polygons (Fields2Cover's GAOS parcels: ``gml:coordinates`` under ``srsName``), the field's
  attributes (swath_width, best_angle ...) kept as properties;
- ISO 11783-10 TaskData (TASKDATA.XML, any file name; versions 3 and 4): partfields (PFD) with their boundary
  polygons (PLN type 1: exterior and interior rings; obstacles, water, buildings of types 3-6
  inside it become holes), guidance groups (GGP/GPN: AB lines from the A and B reference points,
  curves from the pattern's points), read with the ``isoxml`` package;
- KML (Google Earth, a farm software's export) and KMZ (zipped KML): Polygon placemarks are fields
  (inner rings holes), LineString placemarks guidance lines;
- AgOpenGPS field folders (file names in any letter case): Field.txt (StartFix latitude, longitude: the local frame's origin),
  Boundary.txt (rings: the first the fence, the others holes), Headland.txt, TrackLines.txt,
  ABLines.txt and CurveLines.txt (local east/north metres);
- a CSV of polygons, one per row (``name, x1, y1, z1, x2, y2, z2, ...``, as the open autonomous
  tractor's field_boundaries.csv), in the CRS given.

Coordinates: a CRS the file names, or ``crs`` given by the user (any pyproj input: "EPSG:6677"),
or, when neither says, longitude/latitude if every value fits and the extent is under half a
degree (a field, not a continent), else local metres as written. Everything geographic goes to the
local frame of fields.field.local_frame.
"""
from __future__ import annotations

import json
import math
import re
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from shapely import wkt as shapely_wkt
from shapely.geometry import LineString, MultiLineString, Polygon

from measurements.source_files import checked_path, regular_file

from .field import Field, FieldError, GuidanceLine, local_frame, polygon, polygons

MAX_GEOGRAPHIC_EXTENT = 0.5        # deg: beyond this a file of small numbers is metres, not degrees
EARTH_CIRCUMFERENCE = 40_075_017.0  # m (WGS 84 equator): no coordinate of a field on Earth is larger


class Coordinates:
    """How a file's numbers become local metres: lon/lat, a projected CRS, or local as written."""

    def __init__(self, where: str, declared: str | None, given: str | None, sample):
        self.where = where
        self.crs = None
        text = given or declared
        if text:
            import pyproj

            try:
                self.crs = pyproj.CRS.from_user_input(_epsg(text))
            except pyproj.exceptions.CRSError as exc:
                raise FieldError(f"{where}: unknown CRS {text!r} ({exc}); expected e.g. EPSG:4326, EPSG:28992 or "
                                 f"EPSG:6677") from None
            self.kind = "geographic" if self.crs.is_geographic else "projected"
            self.text = f"{self.crs.to_string()} ({'given' if given else 'named by the file'})"
        else:            # each field's own extent: one file may hold fields continents apart
            rings = sample if isinstance(sample, list) else [sample]
            allpts = np.vstack(rings)
            _on_earth(where, allpts)
            ok = len(allpts) > 0 and np.all(np.abs(allpts[:, 0]) <= 180) and np.all(np.abs(allpts[:, 1]) <= 90)
            extent = max(float(np.max(np.ptp(r, axis=0))) for r in rings) if len(allpts) else 0.0
            swapped = len(allpts) > 0 and np.all(np.abs(allpts[:, 0]) <= 90) and np.all(np.abs(allpts[:, 1]) <= 180)
            if not ok and swapped and extent < MAX_GEOGRAPHIC_EXTENT:
                lat = float(allpts[np.argmax(np.abs(allpts[:, 1])), 1])
                raise FieldError(f"{where}: latitude {lat:g} deg is beyond +-90 (the second number of a point is the "
                                 f"latitude); every point fits longitude/latitude with the two swapped: write "
                                 f"longitude first (GeoJSON RFC 7946, KML), or give --crs for metres of a projection")
            self.kind = "geographic" if ok and extent < MAX_GEOGRAPHIC_EXTENT else "local"
            self.text = ("longitude/latitude (WGS 84): the values fit and each field spans under half a degree"
                         if self.kind == "geographic" else "local metres as written (no CRS named; too large for degrees)")

    def lonlat(self, xy: np.ndarray) -> np.ndarray:
        xy = np.asarray(xy, float)[:, :2]
        if self.kind == "projected":
            import pyproj

            t = pyproj.Transformer.from_crs(self.crs, "EPSG:4326", always_xy=True)
            lon, lat = t.transform(xy[:, 0], xy[:, 1])
            return np.column_stack([lon, lat])
        return xy

    def frame(self, rings: list[np.ndarray], origin=None):
        """(origin, rings -> local) for the rings of one file."""
        if self.kind == "local":
            for r in rings:
                _on_earth(self.where, np.asarray(r, float)[:, :2])
            return None, (lambda xy: _on_earth(self.where, np.asarray(xy, float)[:, :2]))
        lonlat = [self.lonlat(r) for r in rings]
        bad = [p for r in lonlat for p in r if not (abs(p[0]) <= 180 and abs(p[1]) <= 90)]
        if bad:
            raise FieldError(f"{self.where}: coordinates {bad[0].tolist()} are not longitude/latitude under {self.text}")
        origin, to_local = local_frame(lonlat, origin)
        return origin, (lambda xy: to_local(self.lonlat(xy)))


def _on_earth(where: str, xy: np.ndarray) -> np.ndarray:
    """``xy`` when every coordinate is a finite number no larger than the Earth's circumference
    (a local or projected metre beyond it is no place on Earth); else a FieldError naming it."""
    bad = ~np.isfinite(xy) | (np.abs(xy) > EARTH_CIRCUMFERENCE)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise FieldError(f"{where}: coordinate {xy[i, j]:g} (point {i + 1}, {'xy'[j]}) is beyond the Earth: expected "
                         f"finite metres within +-{EARTH_CIRCUMFERENCE:.4g} (or longitude/latitude in degrees)")
    return xy


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


def _epsg(text: str) -> str:
    m = re.search(r"EPSG:{1,2}(\d+)$", text.strip(), re.I)
    return f"EPSG:{m.group(1)}" if m else text.strip()


# --- GeoJSON / WKT ------------------------------------------------------------------------------
def read_geojson(path: Path, crs: str | None = None) -> list[Field]:
    try:
        data = json.loads(regular_file(path, FieldError).read_text(encoding="utf-8-sig"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise FieldError(f"{path}: not a readable JSON file: {exc}") from None
    except RecursionError:
        raise FieldError(f"{path}: JSON nested deeper than a GeoJSON ever is (Python's parser gives up); "
                         f"expected a FeatureCollection of Features with Polygon geometries") from None
    from shapely.geometry import shape

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
    return _fields_from_shapes(path, shapes, crs, declared)


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
    return _fields_from_shapes(path, shapes, crs, None)


def _fields_from_shapes(path: Path, shapes: list, crs: str | None, declared: str | None) -> list[Field]:
    """A field per polygon, each in its own local frame (a file may hold fields continents apart);
    a line goes to the field it crosses most."""
    polys = []
    for geom, props in shapes:         # the parcels of one MultiPolygon feature: name_1, name_2 ...
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


# --- GML (Fields2Cover) -----------------------------------------------------------------------------
def read_gml(path: Path, crs: str | None = None, root=None) -> list[Field]:
    root = root if root is not None else _xml(path)
    gml = "{http://www.opengis.net/gml}"
    fields = []
    polys = list(root.iter(f"{gml}Polygon"))
    if not polys:
        raise FieldError(f"{path}: no gml:Polygon in it")
    parsed = []
    for k, poly in enumerate(polys):
        def ring(el):
            text = el.findtext(f".//{gml}coordinates")
            try:
                if text is not None:        # GML 2: "x,y[,z] x,y[,z] ..."
                    tuples = [[float(v) for v in t.split(",")] for t in text.split()]
                    short = [t for t in tuples if len(t) not in (2, 3)]
                    if short:
                        raise ValueError(f"a tuple of {len(short[0])} number(s), {short[0]}; expected 'x,y[,z]' tuples "
                                         f"apart by blanks")
                    return np.array([t[:2] for t in tuples], float)
                nums = [float(x) for x in (el.findtext(f".//{gml}posList") or "").split()]   # GML 3: x y x y
                return np.array(nums, float).reshape(-1, 2)
            except ValueError as exc:
                raise FieldError(f"{path}: gml:Polygon {k}: coordinates are not numbers: {exc}") from None
        outer = [ring(e) for e in poly.iter() if e.tag in (f"{gml}outerBoundaryIs", f"{gml}exterior")]
        inner = [ring(e) for e in poly.iter() if e.tag in (f"{gml}innerBoundaryIs", f"{gml}interior")]
        if not outer or len(outer[0]) < 3:
            raise FieldError(f"{path}: gml:Polygon {k}: no exterior ring with three points or more")
        parsed.append((poly, outer[0], inner))
    srs = parsed[0][0].get("srsName")
    coords = Coordinates(str(path), srs, crs, [o for _, o, _ in parsed])
    owner_attrs = {}
    for el in root.iter():
        if el.tag.endswith("Field") and el.attrib:
            owner_attrs = dict(el.attrib)
    for k, (poly, outer, inner) in enumerate(parsed):
        origin, to_local = coords.frame([outer])
        props = {key: _number(v) for key, v in owner_attrs.items()}
        name = str(props.pop("id", None) or root.get("id") or f"{path.stem}_{k + 1}")
        fields.append(Field(name if len(parsed) == 1 else f"{name}_{k + 1}", polygon(to_local(outer), [to_local(i) for i in inner]),
                            origin, str(path), coords.text, properties=props))
    return fields


def _number(text: str):
    try:
        return float(text)
    except (TypeError, ValueError):
        return text


def _xml(path: Path):
    try:
        return ET.parse(regular_file(path, FieldError)).getroot()
    except (ET.ParseError, OSError, LookupError, ValueError) as exc:
        raise FieldError(f"{path}: not a readable XML file: {exc}") from None


# --- ISO 11783-10 -------------------------------------------------------------------------------------
HOLE_TYPES = {"WaterSurface", "Building", "Road", "Obstacle"}


def read_isoxml(path: Path, crs: str | None = None) -> list[Field]:
    """Partfields of a TaskData (any file name) with the isoxml package's models."""
    from isoxml.util.isoxml_io import isoxml_from_text

    try:
        text = regular_file(path, FieldError).read_text(encoding="utf-8-sig")
        with warnings.catch_warnings():      # a value xsdata cannot convert is kept as text and named below
            warnings.simplefilter("ignore")
            task = isoxml_from_text(text)
    except Exception as exc:            # noqa: BLE001 - xsdata raises many kinds for an invalid document
        raise FieldError(f"{path}: not a valid ISO 11783-10 TaskData: {type(exc).__name__}: {exc}") from None
    if not task.partfields:
        raise FieldError(f"{path}: a TaskData without partfields (PFD)")
    fields = []
    for pf in task.partfields:
        rings, holes = [], []
        for pln in pf.polygons:
            kind = pln.type.name if pln.type is not None else ""
            for ls in pln.line_strings:
                pts = np.array([[_iso_number(path, pf, "PNT D (north)", p.north) for p in ls.points],
                                [_iso_number(path, pf, "PNT E (east)", p.east) for p in ls.points]], float).T[:, ::-1]
                if len(pts) < 3:
                    raise FieldError(f"{path}: partfield {pf.id} ({pf.designator}): polygon {pln.id or kind}: a ring of "
                                     f"{len(pts)} points (PNT); a ring needs three or more")
                if kind == "PartfieldBoundary":
                    (rings if ls.type.name == "PolygonExterior" else holes).append(pts)
                elif kind in HOLE_TYPES and ls.type.name == "PolygonExterior":
                    holes.append(pts)
        if not rings:
            raise FieldError(f"{path}: partfield {pf.id} ({pf.designator}): no boundary polygon (PLN type 1 with an "
                             f"exterior LSG)")
        coords = Coordinates(f"{path}: partfield {pf.id}", None, crs or "EPSG:4326", np.vstack(rings))
        origin, to_local = coords.frame(rings)
        ext = max(rings, key=lambda r: Polygon(r).area)
        boundary = polygon(to_local(ext), [to_local(h) for h in holes + [r for r in rings if r is not ext]])
        f = Field(str(pf.designator or pf.id), boundary, origin, str(path), coords.text,
                  properties={"id": pf.id, **({"area_m2_in_file": _iso_number(path, pf, "D (area, m2)", pf.area)}
                                          if pf.area not in (None, "") else {})})
        for ggp in getattr(pf, "guidance_groups", None) or ():     # version 3 has none
            for gpn in ggp.guidance_patterns:
                pts = [p for ls in gpn.line_strings for p in ls.points]
                xy = np.array([[_iso_number(path, pf, "PNT E (east)", p.east),
                                _iso_number(path, pf, "PNT D (north)", p.north)] for p in pts], float).reshape(-1, 2)
                if len(xy) < 2:
                    raise FieldError(f"{path}: guidance pattern {gpn.id}: {len(xy)} points; a line needs two")
                kinds = [p.type.name if p.type is not None else "" for p in pts]
                if gpn.type is not None and gpn.type.name in ("AB", "APlus") and "GuidanceReferenceA" in kinds \
                        and "GuidanceReferenceB" in kinds:
                    xy = xy[[kinds.index("GuidanceReferenceA"), kinds.index("GuidanceReferenceB")]]
                f.lines.append(GuidanceLine(str(gpn.designator or gpn.id), to_local(xy)))
        fields.append(f)
    return fields


def _iso_number(path: Path, pf, attribute: str, value) -> float:
    """A number of a partfield's element; a FieldError naming the partfield and attribute otherwise."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        x = math.nan
    if not math.isfinite(x):
        raise FieldError(f"{path}: partfield {pf.id} ({pf.designator}): {attribute} is {value!r}, expected a number")
    return x


# --- AgOpenGPS -----------------------------------------------------------------------------------------
def read_agopengps(folder: Path) -> list[Field]:
    origin = _aog_origin(folder)
    rings = _aog_rings(aog_file(folder, "Boundary.txt"))
    if not rings:
        raise FieldError(f"{aog_file(folder, 'Boundary.txt')}: no boundary ring in it (expected $Boundary, a True/False "
                         f"drive-through flag, a point count, then easting,northing,heading lines)")
    boundary = polygon(rings[0], rings[1:])
    crs = f"AgOpenGPS local metres about StartFix {origin[0]:.7f}, {origin[1]:.7f}"
    f = Field(folder.name, boundary, origin, str(folder), crs)
    head = aog_file(folder, "Headland.txt")
    if head.exists():
        hl = _aog_rings(head)
        if hl:
            f.headland = polygon(hl[0], hl[1:])
    f.lines = _aog_tracks(folder)
    return [f]


def aog_file(folder: Path, name: str) -> Path:
    """An AgOpenGPS file of the folder in whatever letter case it was written (Boundary.Txt,
    BOUNDARY.TXT); the name as given when the folder has none."""
    if (folder / name).exists():
        return folder / name
    lower = name.lower()
    found = [p for p in folder.iterdir() if p.name.lower() == lower] if folder.is_dir() else []
    return found[0] if found else folder / name


def _aog_boundary_only(folder: Path) -> bool:
    return folder.is_dir() and aog_file(folder, "Boundary.txt").exists() and not aog_file(folder, "Field.txt").exists()


def is_agopengps(folder: Path) -> bool:
    return folder.is_dir() and aog_file(folder, "Field.txt").exists() and aog_file(folder, "Boundary.txt").exists()


def _lines(path: Path) -> list[str]:
    try:
        return [ln.strip() for ln in regular_file(path, FieldError).read_text(encoding="utf-8-sig", errors="replace")
                .splitlines()]
    except OSError as exc:
        raise FieldError(f"{path}: cannot read: {exc}") from None


def _aog_origin(folder: Path) -> tuple[float, float]:
    path = aog_file(folder, "Field.txt")
    if not path.exists():
        raise FieldError(f"{folder}: an AgOpenGPS field folder (it has {aog_file(folder, 'Boundary.txt').name}) without "
                         f"Field.txt: its StartFix line gives the latitude,longitude that the boundary's local metres "
                         f"are measured from")
    lines = _lines(path)
    for i, line in enumerate(lines[:-1]):
        if line.lower().startswith("startfix"):
            parts = lines[i + 1].split(",")
            try:
                return float(parts[0]), float(parts[1])
            except (ValueError, IndexError):
                raise FieldError(f"{path}: line {i + 2}: StartFix must be followed by 'latitude,longitude', got "
                                 f"{lines[i + 1]!r}") from None
    raise FieldError(f"{path}: no StartFix line (the field's origin, 'latitude,longitude' on the next line)")


def _aog_rings(path: Path) -> list[np.ndarray]:
    """Rings of a Boundary.txt or Headland.txt: [$header] {[True|False]... count, count lines e,n[,h]}."""
    if not path.exists():
        return []
    lines = [ln for ln in _lines(path) if ln]
    i = 1 if lines and lines[0].startswith("$") else 0
    rings = []
    while i < len(lines):
        while i < len(lines) and lines[i].lower() in ("true", "false"):
            i += 1
        if i >= len(lines):
            break
        try:
            count = int(lines[i])
        except ValueError:
            raise FieldError(f"{path}: line {i + 1}: expected a point count, got {lines[i]!r}") from None
        pts = []
        for k in range(i + 1, i + 1 + count):
            try:
                e, n = (float(x) for x in lines[k].split(",")[:2])
            except (ValueError, IndexError):
                raise FieldError(f"{path}: line {k + 1}: expected easting,northing[,heading], got "
                                 f"{lines[k] if k < len(lines) else 'the end of the file'!r}") from None
            pts.append((e, n))
        if len(pts) >= 3:
            rings.append(np.array(pts))
        i += 1 + count
    return rings


def _aog_tracks(folder: Path) -> list[GuidanceLine]:
    out = []
    track = aog_file(folder, "TrackLines.txt")
    if track.exists():              # name, heading, A, B, nudge, mode, visible, count, count points
        lines = [ln for ln in _lines(track) if ln]
        i = 1 if lines and lines[0].startswith("$") else 0
        while i + 7 < len(lines):
            name = lines[i]
            try:
                a = [float(x) for x in lines[i + 2].split(",")[:2]]
                b = [float(x) for x in lines[i + 3].split(",")[:2]]
                count = int(lines[i + 7])
                pts = [[float(x) for x in lines[k].split(",")[:2]] for k in range(i + 8, i + 8 + count)]
            except (ValueError, IndexError):
                raise FieldError(f"{track}: track {name!r} (line {i + 1}): expected name, heading, A 'e,n', B 'e,n', "
                                 f"nudge, mode, visible, a point count and the points") from None
            out.append(GuidanceLine(name, np.array(pts if len(pts) >= 2 else [a, b], float)))
            i += 8 + count
    ab = aog_file(folder, "ABLines.txt")
    if ab.exists():                  # name, heading [deg, from north clockwise], easting, northing
        for k, line in enumerate(ln for ln in _lines(ab) if ln and not ln.startswith("$")):
            parts = line.split(",")
            try:
                heading, e, n = (float(x) for x in parts[1:4])
            except (ValueError, IndexError):
                raise FieldError(f"{ab}: line {k + 1}: expected name,heading,easting,northing, got {line!r}") from None
            d = np.array([math.sin(math.radians(heading)), math.cos(math.radians(heading))])
            out.append(GuidanceLine(parts[0], np.array([[e, n], [e + 100 * d[0], n + 100 * d[1]]])))
    curve = aog_file(folder, "CurveLines.txt")
    if curve.exists():               # $CurveLines, then name, heading, count, count points
        lines = [ln for ln in _lines(curve) if ln]
        i = 1 if lines and lines[0].startswith("$") else 0
        while i + 2 < len(lines):
            try:
                count = int(lines[i + 2])
                pts = [[float(x) for x in lines[k].split(",")[:2]] for k in range(i + 3, i + 3 + count)]
            except (ValueError, IndexError):
                raise FieldError(f"{curve}: curve {lines[i]!r} (line {i + 1}): expected name, heading, a point count "
                                 f"and the points") from None
            if len(pts) >= 2:
                out.append(GuidanceLine(lines[i], np.array(pts, float)))
            i += 3 + count
    return out


# --- CSV of polygons -------------------------------------------------------------------------------------
def read_polygon_csv(path: Path, crs: str | None = None) -> list[Field]:
    """One polygon a row: name, x1, y1, z1, x2, y2, z2 ... (or name, x1, y1, x2, y2 ... when the
    count is even), in ``crs`` (default: local metres)."""
    rows = []
    for k, line in enumerate(ln for ln in _lines(path) if ln and not ln.startswith("#")):
        parts = [p.strip() for p in line.split(",")]
        try:
            nums = [float(x) for x in parts[1:]]
        except ValueError:
            if k == 0:
                continue            # a header
            raise FieldError(f"{path}: row {k + 1} ({parts[0]!r}): expected numbers after the name") from None
        step = 3 if len(nums) % 3 == 0 and xyz_triples(nums) else 2
        if len(nums) % step:
            raise FieldError(f"{path}: row {k + 1} ({parts[0]!r}): {len(nums)} numbers are neither x,y pairs nor "
                             f"x,y,z triples")
        pts = np.array(nums, float).reshape(-1, step)[:, :2]
        if len(pts) < 3:
            raise FieldError(f"{path}: row {k + 1} ({parts[0]!r}): {len(pts)} points; a polygon needs three or more")
        rows.append((parts[0], pts))
    if not rows:
        raise FieldError(f"{path}: no polygon row (name, x1, y1, z1, x2, ...)")
    coords = Coordinates(str(path), None, crs, [p for _, p in rows])
    out = []
    for name, p in rows:
        origin, to_local = coords.frame([p])
        out.append(Field(name, polygon(to_local(p)), origin, str(path), coords.text))
    return out


def xyz_triples(nums: list[float]) -> bool:
    """x, y, z triples: every third value is a height (the same small number throughout)."""
    z = np.array(nums[2::3])
    return len(z) >= 3 and float(np.ptp(z)) < 50.0 and float(np.max(np.abs(z))) < 10000.0


# --- dispatch -----------------------------------------------------------------------------------------------
def read_fields(path: str | Path, crs: str | None = None) -> list[Field]:
    """Every field in a file or folder (a folder: an AgOpenGPS field, or every readable file in
    it); a FieldError names the file and what was expected."""
    path = checked_path(path, FieldError)
    if path.is_dir():
        return read_folder(path, crs)[0]
    regular_file(path, FieldError, None)
    kind = kind_of(path)
    if kind is None:
        raise FieldError(f"{path}: not a field file: expected .geojson/.json, .wkt, .xml (GML or ISO 11783-10 "
                         f"TaskData), .kml/.kmz, .csv, or an AgOpenGPS field folder (a GNSS track: --from-track)")
    if kind == "kml":
        from .kml import read_kml_shapes

        return _fields_from_shapes(path, read_kml_shapes(path), crs, "EPSG:4326")
    if kind == "xml":
        root = _xml(path)
        if root.tag.endswith("ISO11783_TaskData"):
            return read_isoxml(path, crs)
        return read_gml(path, crs, root)
    return {"geojson": read_geojson, "wkt": read_wkt, "csv": read_polygon_csv}[kind](path, crs)


def read_folder(path: Path, crs: str | None = None) -> tuple[list[Field], list[str]]:
    """(fields, why each other file was skipped) of a folder: an AgOpenGPS field, or every
    readable file in it (and AgOpenGPS fields one level down)."""
    if is_agopengps(path) or _aog_boundary_only(path):
        return read_agopengps(path), []       # without Field.txt: the error names it
    out, skipped = [], []
    for p in sorted(path.iterdir()):
        try:
            if p.is_dir() and (aog_file(p, "Field.txt").exists() or _aog_boundary_only(p)):
                out += read_agopengps(p)
            elif not p.is_dir() and kind_of(p):
                out += read_fields(p, crs)     # a device, a dangling link or a loop is named, not read
        except FieldError as exc:         # one bad field does not hide the others: it is named
            skipped.append(str(exc))
    distinct_names(out)
    if not out:
        raise FieldError(f"{path}: no field file in it (GeoJSON, WKT, GML, ISO 11783-10 TaskData, an AgOpenGPS "
                         f"field folder, a polygon CSV)" + (f"; {'; '.join(skipped[:3])}" if skipped else ""))
    return out, skipped


def kind_of(path: Path) -> str | None:
    suffix = path.suffix.lower()
    if suffix in (".geojson", ".json"):
        return "geojson"
    if suffix == ".wkt":
        return "wkt"
    if suffix == ".xml":
        return "xml"
    if suffix == ".csv":
        return "csv"
    if suffix in (".kml", ".kmz"):
        return "kml"
    return None
