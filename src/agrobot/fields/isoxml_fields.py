"""ISO 11783-10 TaskData (TASKDATA.XML, any file name; versions 3 and 4) as fields: partfields
(PFD) with their boundary polygons (PLN type 1: exterior and interior rings, and a boundary ring
written as a polygon of its own inside the largest; water, buildings, roads and obstacles of
types 3-6 become holes), guidance groups (GGP/GPN: AB lines from the A and B reference points,
curves from the pattern's points), read with the ``isoxml`` package.

As terminals write them: elements kept in external files (``<XFR A="PFD00001" B="1"/>`` naming
``PFD00001.XML`` beside it, whose root is ``XFC``) are read in place; an empty or degenerate
guidance pattern, or a partfield without a boundary, is skipped and named (the field's
``properties["skipped"]``), never the whole file refused; an invalid boundary (a ring that
crosses itself) is repaired with ``shapely.make_valid`` and named (``properties["repaired"]``).

Imported where used: isoxml (the fields extra).
"""
from __future__ import annotations

import math
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from shapely.geometry import Polygon
from shapely.geometry.polygon import orient

from agrobot.orchestrator.source_files import regular_file

from .coordinates import Coordinates
from .field import Field, FieldError, GuidanceLine, polygon
from .shapes import repaired_parts

HOLE_TYPES = {"WaterSurface", "Building", "Road", "Obstacle"}


def read_isoxml(path: Path, crs: str | None = None) -> list[Field]:
    """Partfields of a TaskData (any file name) with the isoxml package's models."""
    from isoxml.util.isoxml_io import isoxml_from_text

    text = _with_external_files(path, regular_file(path, FieldError).read_text(encoding="utf-8-sig"))
    try:
        with warnings.catch_warnings():      # a value xsdata cannot convert is kept as text and named below
            warnings.simplefilter("ignore")
            task = isoxml_from_text(text)
    except Exception as exc:            # noqa: BLE001 - xsdata raises many kinds for an invalid document
        raise FieldError(f"{path}: not a valid ISO 11783-10 TaskData: {type(exc).__name__}: {exc}") from None
    if not task.partfields:
        raise FieldError(f"{path}: a TaskData without partfields (PFD)")
    fields, skipped = [], []
    for pf in task.partfields:
        try:
            f = _partfield(path, pf, crs, skipped)
        except FieldError as exc:            # a partfield without a usable boundary does not hide the others
            if "expected a number" in str(exc):
                raise                          # a damaged number: the file itself is damaged
            skipped.append(str(exc))
            continue
        fields.append(f)
    if not fields:
        raise FieldError(f"{path}: no partfield with a usable boundary: {'; '.join(skipped[:3])}")
    if skipped:
        fields[0].properties["skipped"] = "; ".join(skipped)
    return fields


def _partfield(path: Path, pf, crs, skipped: list) -> Field:
    """One partfield as a Field (guidance patterns that cannot be lines skipped and named)."""
    if True:
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
                    (rings if ls.type is None or ls.type.name == "PolygonExterior" else holes).append(pts)
                elif kind in HOLE_TYPES and ls.type is not None and ls.type.name in ("PolygonExterior",
                                                                                     "PolygonInterior"):
                    holes.append(pts)
        if not rings:
            raise FieldError(f"{path}: partfield {pf.id} ({pf.designator}): no boundary polygon (PLN type 1 with an "
                             f"exterior LSG)")
        coords = Coordinates(f"{path}: partfield {pf.id}", None, crs or "EPSG:4326", np.vstack(rings))
        origin, to_local = coords.frame(rings)
        ext = max(rings, key=lambda r: Polygon(r).area)
        outer = Polygon(ext).buffer(0) if not Polygon(ext).is_valid else Polygon(ext)
        inside = [r for r in rings if r is not ext and outer.contains(Polygon(r).representative_point())]
        apart = [r for r in rings if r is not ext and not any(r is i for i in inside)]
        if apart:
            skipped.append(f"partfield {pf.id} ({pf.designator}): {len(apart)} boundary ring(s) outside its largest: "
                           f"left out")
        boundary, repaired = _valid(polygon(to_local(ext), [to_local(h) for h in holes + inside]), f"{path}: partfield {pf.id}")
        f = Field(str(pf.designator or pf.id), boundary, origin, str(path), coords.text,
                  properties={"id": pf.id, **({"area_m2_in_file": _iso_number(path, pf, "D (area, m2)", pf.area)}
                                          if pf.area not in (None, "") else {})})
        if repaired:
            f.properties["repaired"] = repaired
        for ggp in getattr(pf, "guidance_groups", None) or ():     # version 3 has none
            for gpn in ggp.guidance_patterns:
                pts = [p for ls in gpn.line_strings for p in ls.points]
                xy = np.array([[_iso_number(path, pf, "PNT E (east)", p.east),
                                _iso_number(path, pf, "PNT D (north)", p.north)] for p in pts], float).reshape(-1, 2)
                if len(xy) < 2 or len(np.unique(xy, axis=0)) < 2:
                    skipped.append(f"guidance pattern {gpn.id} ({gpn.designator or '-'}) of partfield {pf.id}: "
                                   f"{len(np.unique(xy, axis=0))} distinct point(s), a line needs two: skipped")
                    continue
                kinds = [p.type.name if p.type is not None else "" for p in pts]
                if gpn.type is not None and gpn.type.name in ("AB", "APlus") and "GuidanceReferenceA" in kinds \
                        and "GuidanceReferenceB" in kinds:
                    xy = xy[[kinds.index("GuidanceReferenceA"), kinds.index("GuidanceReferenceB")]]
                f.lines.append(GuidanceLine(str(gpn.designator or gpn.id), to_local(xy)))
    return f


def _valid(boundary: Polygon, where: str) -> tuple[Polygon, str | None]:
    """The boundary, or the largest polygon of its repair (fields.shapes.repaired_parts) and what was done."""
    parts, note = repaired_parts(boundary, where)
    if note is None:
        return boundary, None
    best = orient(max(parts, key=lambda g: g.area), 1.0)
    return best, (f"{note}: {best.area:.0f} m2 kept" + (f" of {sum(g.area for g in parts):.0f} m2" if len(parts) > 1 else ""))


def _with_external_files(path: Path, text: str) -> str:
    """The TaskData with every external file reference (XFR, ISO 11783-10 section 6.2: A the file
    name without suffix, B = 1 XML) replaced by the elements of that file (root XFC)."""
    if "<XFR" not in text:
        return text
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise FieldError(f"{path}: not a readable XML file: {exc}") from None
    names = {p.name.upper(): p for p in path.parent.iterdir()}
    for ref in [e for e in root if e.tag == "XFR"]:
        stem = ref.get("A", "")
        found = names.get(f"{stem.upper()}.XML")
        if found is None:
            raise FieldError(f"{path}: external file reference XFR A={stem!r}: no {stem}.XML beside it (ISO 11783-10 "
                             f"keeps those elements in that file)")
        try:
            ext = ET.parse(regular_file(found, FieldError)).getroot()
        except ET.ParseError as exc:
            raise FieldError(f"{found}: not a readable XML file: {exc}") from None
        if ext.tag != "XFC":
            raise FieldError(f"{found}: root element <{ext.tag}>; an ISO 11783-10 external file's root is <XFC>")
        at = list(root).index(ref)
        root.remove(ref)
        for k, child in enumerate(list(ext)):
            root.insert(at + k, child)
    return ET.tostring(root, encoding="unicode")

def _iso_number(path: Path, pf, attribute: str, value) -> float:
    """A number of a partfield's element; a FieldError naming the partfield and attribute otherwise."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        x = math.nan
    if not math.isfinite(x):
        raise FieldError(f"{path}: partfield {pf.id} ({pf.designator}): {attribute} is {value!r}, expected a number")
    return x
