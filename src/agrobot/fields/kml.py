"""KML and KMZ (zipped KML) files as shapes: the Polygon placemarks (outer and inner rings) and
LineString placemarks, with each placemark's name, in longitude/latitude (KML's only CRS,
WGS 84). fields.readers makes fields of them. Parsed with the standard library's XML parser:
KML's geometry is a few elements, whatever its namespace (KML 2.0-2.2, Google's gx)."""
from __future__ import annotations

import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
from shapely.geometry import LineString, Polygon

from agrobot.orchestrator.source_files import LIMITS, regular_file, size_text

from .field import FieldError


def _local(tag: str) -> str:
    return tag.rsplit("}", 1)[-1]


def _coordinates(el, where: str) -> np.ndarray:
    text = next((c.text or "" for c in el.iter() if _local(c.tag) == "coordinates"), "")
    pts = []
    for k, tup in enumerate(t for t in text.split() if t.strip()):
        try:
            values = [float(v) for v in tup.split(",")]
        except ValueError:
            values = []
        if len(values) not in (2, 3):
            raise FieldError(f"{where}: coordinate tuple {k + 1} is {tup[:40]!r}; expected 'longitude,latitude"
                             f"[,altitude]' (tuples apart by blanks, numbers within one by commas)")
        pts.append(values[:2])
    return np.array(pts, float).reshape(-1, 2)


def kml_root(path: Path):
    """The KML document of a .kml file, or of the first .kml inside a .kmz."""
    try:
        if path.suffix.lower() == ".kmz":
            with zipfile.ZipFile(regular_file(path, FieldError)) as z:
                names = [n for n in z.namelist() if n.lower().endswith(".kml")]
                if not names:
                    raise FieldError(f"{path}: a KMZ without a .kml file in it (found {', '.join(z.namelist()[:5])})")
                name = "doc.kml" if "doc.kml" in names else names[0]
                size = z.getinfo(name).file_size
                if size > LIMITS["whole"]:
                    raise FieldError(f"{path}: {name} unpacks to {size_text(size)}, above the {size_text(LIMITS['whole'])} "
                                     f"limit for a file read whole into memory (--max-file-size raises it)")
                return ET.fromstring(z.read(name))
        return ET.parse(regular_file(path, FieldError)).getroot()
    except FieldError:
        raise
    except (ET.ParseError, OSError, zipfile.BadZipFile, LookupError, ValueError) as exc:      # LookupError: an unknown encoding
        raise FieldError(f"{path}: not a readable {'KMZ' if path.suffix.lower() == '.kmz' else 'KML'} file: {exc}") from None


def read_kml_shapes(path: Path) -> list[tuple[object, dict]]:
    """[(shapely Polygon or LineString, {"name": ...})] of every placemark's geometry."""
    root = kml_root(path)
    if _local(root.tag) != "kml" and not any(_local(e.tag) == "Placemark" for e in root.iter()):
        raise FieldError(f"{path}: not KML: the root element is <{_local(root.tag)}>, expected <kml>")
    shapes = []
    for k, mark in enumerate(e for e in root.iter() if _local(e.tag) == "Placemark"):
        name = next((c.text for c in mark if _local(c.tag) == "name" and c.text), f"{path.stem}_{k + 1}")
        where = f"{path}: placemark {name!r}"
        for geom in mark.iter():
            kind = _local(geom.tag)
            if kind == "Polygon":
                outer = [_coordinates(b, where) for b in geom if _local(b.tag) == "outerBoundaryIs"]
                inner = [_coordinates(b, where) for b in geom if _local(b.tag) == "innerBoundaryIs"]
                if not outer or len(outer[0]) < 3:
                    raise FieldError(f"{where}: a Polygon without an outer ring of three points or more")
                shapes.append((Polygon(outer[0], [h for h in inner if len(h) >= 3]), {"name": name}))
            elif kind == "LineString":
                pts = _coordinates(geom, where)
                if len(pts) >= 2:
                    shapes.append((LineString(pts), {"name": name}))
    return shapes
