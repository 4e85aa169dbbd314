"""Fields from the files farmers and planners write, all to one Field type:

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

This module reads GML and polygon CSVs, and chooses the reader of the others (fields.geojson,
fields.isoxml_fields, fields.kml, fields.agopengps); fields.coordinates turns every file's numbers
into local metres, and fields.shapes names the fields of a file apart.
"""
from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from agrobot.orchestrator.source_files import checked_path, regular_file

from .agopengps import (
    aog_file,
    boundary_without_field_txt,
    is_agopengps,
    read_agopengps,
    text_lines,
)
from .coordinates import Coordinates
from .field import Field, FieldError, polygon
from .geojson import read_geojson, read_wkt
from .isoxml_fields import read_isoxml
from .kml import read_kml_shapes
from .shapes import distinct_names, fields_from_shapes

__all__ = ["Coordinates", "aog_file", "is_agopengps", "kind_of", "read_agopengps", "read_fields", "read_folder",
           "read_geojson", "read_gml", "read_isoxml", "read_polygon_csv", "read_wkt"]


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


# --- CSV of polygons -------------------------------------------------------------------------------------
def read_polygon_csv(path: Path, crs: str | None = None) -> list[Field]:
    """One polygon a row: name, x1, y1, z1, x2, y2, z2 ... (or name, x1, y1, x2, y2 ... when the
    count is even), in ``crs`` (default: local metres)."""
    rows = []
    for k, line in enumerate(ln for ln in text_lines(path) if ln and not ln.startswith("#")):
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
        return fields_from_shapes(path, read_kml_shapes(path), crs, "EPSG:4326")
    if kind == "xml":
        root = _xml(path)
        if root.tag.endswith("ISO11783_TaskData"):
            return read_isoxml(path, crs)
        if root.tag == "XFC":
            raise FieldError(f"{path}: an ISO 11783-10 external file (root XFC): its elements are read through the "
                             f"TASKDATA.XML that refers to it (XFR)")
        return read_gml(path, crs, root)
    return {"geojson": read_geojson, "wkt": read_wkt, "csv": read_polygon_csv}[kind](path, crs)


def read_folder(path: Path, crs: str | None = None) -> tuple[list[Field], list[str]]:
    """(fields, why each other file was skipped) of a folder: an AgOpenGPS field, or every
    readable file in it (and AgOpenGPS fields one level down)."""
    if is_agopengps(path) or boundary_without_field_txt(path):
        return read_agopengps(path), []       # without Field.txt: the error names it
    out, skipped = [], []
    for p in sorted(path.iterdir()):
        try:
            if p.is_dir() and (aog_file(p, "Field.txt").exists() or boundary_without_field_txt(p)):
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
