"""A field: its boundary with holes, its guidance lines and headland, in a local metric frame.

Coordinates are metres east/north of ``origin`` (latitude, longitude in degrees), on the tangent
plane of the WGS-84 ellipsoid there (pymap3d's ENU, the frame the measured logs use): a field of a
few kilometres is flat to millimetres in it. A field read in local coordinates with no geographic
reference (an AgOpenGPS field has one: its StartFix) has ``origin`` None. Geometry is shapely's.

Imported where used: pymap3d (the hardware extra).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field as dc_field

import numpy as np
from shapely.geometry import LineString, MultiPolygon, Polygon
from shapely.geometry.polygon import orient
from shapely.validation import explain_validity

from agrobot.orchestrator.errors import InputError


EARTH_REACH = 2.0e7     # m: no two points of the Earth's surface are farther apart along it (half a meridian)


class FieldError(InputError, ValueError):
    """A field file that cannot be read, or a field that cannot be used (exit 2, named)."""


@dataclass
class GuidanceLine:
    """An AB line (two points: A then B) or a curve (a polyline), local metres."""

    name: str
    points: np.ndarray                 # (N, 2) east, north

    @property
    def kind(self) -> str:
        return "AB line" if len(self.points) == 2 else "curve"

    @property
    def heading(self) -> float:
        """From A towards B (or the curve's ends), rad, east = 0, counter-clockwise."""
        d = self.points[-1] - self.points[0]
        return math.atan2(d[1], d[0])

    @property
    def length(self) -> float:
        return float(LineString(self.points).length)


@dataclass
class Field:
    name: str
    boundary: Polygon                  # exterior and holes, local metres
    origin: tuple[float, float] | None  # (lat, lon) of the local frame; None: coordinates as given
    source: str
    crs: str                           # how the coordinates were read
    lines: list[GuidanceLine] = dc_field(default_factory=list)
    headland: Polygon | None = None    # an inner headland boundary, where the file has one
    properties: dict = dc_field(default_factory=dict)

    @property
    def area_ha(self) -> float:
        return self.boundary.area / 1e4

    @property
    def holes(self) -> int:
        return len(self.boundary.interiors)

    def problems(self) -> list[str]:
        """Why the boundary cannot be planned on (too few points, coordinates beyond the Earth,
        self-intersection), or []."""
        if self.boundary.is_empty or len(self.boundary.exterior.coords) < 4:
            return ["the boundary has fewer than three distinct points"]
        far = max(abs(b) for b in self.boundary.bounds)
        if not far <= EARTH_REACH:
            return [f"coordinates {far:.3g} m from the field's origin: beyond the Earth (no two places are more than "
                    f"{EARTH_REACH / 1e3:,.0f} km apart); is the coordinate system right (--crs)?"]
        if not self.boundary.is_valid:
            why = explain_validity(self.boundary)
            where = re.search(r"\[(-?[\d.e+-]+) (-?[\d.e+-]+)\]", why)
            if where:
                why = f"{why[:where.start()]} at ({float(where[1]):.2f}, {float(where[2]):.2f}) m east/north of the field's origin"
            return [f"the boundary is not a simple polygon: {why}"]
        return []

    def to_geodetic(self, xy: np.ndarray) -> np.ndarray:
        """(N, 2) local east/north -> (N, 2) longitude, latitude in degrees."""
        if self.origin is None:
            raise FieldError(f"{self.source}: field {self.name!r} has no geographic reference (local coordinates)")
        import pymap3d

        xy = np.asarray(xy, float)
        lat, lon, _ = pymap3d.enu2geodetic(xy[:, 0], xy[:, 1], 0.0, self.origin[0], self.origin[1], 0.0, deg=True)
        return np.column_stack([lon, lat])

    def summary(self) -> dict:
        minx, miny, maxx, maxy = self.boundary.bounds
        return {"name": self.name, "source": self.source, "crs": self.crs,
                "origin_lat_lon_deg": list(self.origin) if self.origin else None,
                "area_ha": round(self.area_ha, 4), "perimeter_m": round(self.boundary.exterior.length, 2),
                "rings": 1 + self.holes, "holes": self.holes, "extent_m": [round(maxx - minx, 2), round(maxy - miny, 2)],
                "lines": [{"name": g.name, "kind": g.kind, "length_m": round(g.length, 2),
                           "heading_deg": round(math.degrees(g.heading), 2)} for g in self.lines],
                "headland": self.headland is not None, "valid": not self.problems(), "problems": self.problems(),
                "properties": self.properties}


def local_frame(lonlat_rings: list[np.ndarray], origin: tuple[float, float] | None = None):
    """(origin, function lon/lat (N, 2) -> local (N, 2)) about ``origin`` or the rings' centre."""
    import pymap3d

    if origin is None:
        allpts = np.vstack(lonlat_rings)
        origin = (round(float(np.mean(allpts[:, 1])), 7), round(float(np.mean(allpts[:, 0])), 7))

    def to_local(lonlat: np.ndarray) -> np.ndarray:
        lonlat = np.asarray(lonlat, float)
        e, n, _ = pymap3d.geodetic2enu(lonlat[:, 1], lonlat[:, 0], 0.0, origin[0], origin[1], 0.0, deg=True)
        return np.column_stack([e, n])

    return origin, to_local


def polygon(exterior: np.ndarray, holes: list[np.ndarray] = ()) -> Polygon:
    """A shapely polygon from rings ((N, 2), closed or not), exterior counter-clockwise."""
    return orient(Polygon(exterior, [h for h in holes if len(h) >= 3]), 1.0)


def polygons(geom) -> list[Polygon]:
    if isinstance(geom, Polygon):
        return [geom]
    if isinstance(geom, MultiPolygon):
        return list(geom.geoms)
    return []


def choose_field(fields: list[Field], name: str | None, where: str) -> Field:
    """The field named ``name`` (the largest when None); refused when no field, or several, have the name."""
    if name is None:
        return max(fields, key=lambda f: f.boundary.area)
    found = [f for f in fields if f.name == name]
    if not found:
        raise FieldError(f"{where}: no field named {name!r}; fields: {', '.join(f.name for f in fields)}")
    if len(found) > 1:
        raise FieldError(f"{where}: {len(found)} fields are named {name!r}; give the file's fields distinct names")
    return found[0]
