"""ISO 11783-10 TaskData (TASKDATA.XML, any file name; versions 3 and 4) as fields: partfields
(PFD) with their boundary polygons (PLN type 1: exterior and interior rings; obstacles, water,
buildings of types 3-6 inside it become holes), guidance groups (GGP/GPN: AB lines from the A
and B reference points, curves from the pattern's points), read with the ``isoxml`` package."""
from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
from shapely.geometry import Polygon

from agrobot.orchestrator.source_files import regular_file

from .coordinates import Coordinates
from .field import Field, FieldError, GuidanceLine, polygon

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
